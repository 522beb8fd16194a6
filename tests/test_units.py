"""Units in every output (docs/units.md): every ``--json`` object and JSON file has a
top-level ``"units"`` object covering each of its numbers; printed numbers carry units; an
underflowed p-value prints as a bound; a wrong file type is named as such."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest

from bench.cli import main
from calib.gap.results import EffectEstimate
from calib.units import format_estimate, format_p, missing_units, unit_of
from tests.cli import unwrap

REPO = Path(__file__).resolve().parents[1]


def _run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def _json(argv: list[str]) -> dict:
    code, out, err = _run(argv)
    assert code == 0, err
    return json.loads(out)


def _covered(obj: dict, what: str) -> None:
    assert isinstance(obj.get("units"), dict) and obj["units"], f"{what}: no units object"
    assert all(isinstance(u, str) and u for u in obj["units"].values()), what
    assert missing_units(obj) == [], f"{what}: numbers without a unit: {missing_units(obj)}"


@pytest.fixture(scope="module")
def course_args(course_dir) -> dict:
    return {k: str(course_dir / f) for k, f in (("e", "ensayo.mat"), ("a", "acel.mat"),
                                               ("p", "puntos.mat"), ("d", "datos.txt"))}


@pytest.mark.parametrize("extra", [[], ["--method", "wls"], ["--no-datos"]])
def test_calibrate_json_has_units(course_args, extra):
    argv = ["calibrate", course_args["e"], "--json"]
    if extra != ["--no-datos"]:
        argv += ["--datos", course_args["d"], *extra]
    d = _json(argv)
    _covered(d, "calibrate --json")
    assert unit_of(d["units"], "axes.x.bias") == "m/s²"
    assert unit_of(d["units"], "axes.y.scale") == "1"
    assert unit_of(d["units"], "axes.x.sigma2") == "(m/s²)²"
    assert {"method", "g", "axes"} <= set(d)  # the existing keys stay


def test_trajectory_and_nmin_json_have_units(course_args):
    c = course_args
    inputs = ["--ensayo", c["e"], "--acel", c["a"], "--puntos", c["p"], "--datos", c["d"]]
    t = _json(["trajectory", *inputs, "--json"])
    _covered(t, "trajectory --json")
    assert unit_of(t["units"], "final_corrected") == "m"
    assert unit_of(t["units"], "calibration.axes.x.bias") == "m/s²"
    n = _json(["nmin", *inputs, "--runs", "2", "--mc-n", "101", "--json"])
    _covered(n, "nmin --json")


def test_gap_json_has_units_from_the_effect_catalog():
    d = _json(["gap", str(REPO / "data" / "sweep-lever-arm" / "ensayo.mat"), "--noise-var",
               "0.25,0.64", "--json"])
    _covered(d, "gap --json")
    assert unit_of(d["units"], "effects.params.pos_x") == "m"
    assert unit_of(d["units"], "effects.std.pos_x") == "m"
    assert unit_of(d["units"], "effects.params.delta") == "rad"


@pytest.mark.parametrize("kind", ["calibration", "vehicle", "course"])
def test_generate_stdout_and_truth_json_have_units(tmp_path, kind):
    argv = ["generate", kind, "--seed", "3", "--out", str(tmp_path / kind), "--json"]
    if kind in ("calibration", "course"):
        argv += ["--count", "201"]
    d = _json(argv)
    _covered(d, f"generate {kind} --json")
    truth = json.loads((tmp_path / kind / "truth.json").read_text())
    _covered(truth, f"generate {kind}: truth.json")
    if kind == "vehicle":
        assert d["units"]["final_position"] == "m"


def test_generate_vehicle_prints_final_position_in_metres(tmp_path):
    code, out, err = _run(["generate", "vehicle", "--seed", "1", "--out", str(tmp_path / "v")])
    assert code == 0, err
    line = next(ln for ln in out.splitlines() if ln.startswith("final_position"))
    assert line.endswith("] m")


def test_calibrate_table_rows_carry_units(course_args):
    code, out, err = _run(["calibrate", course_args["e"], "--datos", course_args["d"]])
    assert code == 0, err
    rows = {ln.split()[0]: ln.split()[1] for ln in out.splitlines()
            if ln.startswith(("bias ", "scale "))}
    assert rows == {"bias": "m/s²", "scale": "1"}
    assert "(m/s²)²" in out  # σ²


def test_effect_line_has_units_and_an_underflowed_p_is_a_bound():
    e = EffectEstimate("misalignment", "x", {"delta": 0.019523}, {"delta": 0.0012},
                       statistic=2000.0, p_value=0.0)
    text = str(e)
    assert "delta = 0.01952 ± 0.0012 rad" in text
    assert "p < 1e-300" in text and "p = 0" not in text
    assert format_p(5e-324) == "p < 1e-300"
    assert format_p(0.0123) == "p = 0.0123"
    assert format_estimate(0.15174471, 0.0037597, "m") == "0.15174 ± 0.0038 m"


def test_a_text_file_given_as_the_ensayo_is_named_as_such(course_args):
    code, out, err = _run(["calibrate", course_args["d"]])
    assert code == 2 and out == ""
    err = unwrap(err)  # the message, wrapped at 100 columns, on one line
    assert "is a text file" in err and "datos.txt" in err and "ensayo .mat" in err
    assert "index out of range" not in err


def test_a_json_file_given_as_a_mat_file_is_named_as_such(tmp_path, course_args):
    p = tmp_path / "est.json"
    p.write_text('{"method": "ols"}')
    code, _, err = _run(["trajectory", "--ensayo", course_args["e"], "--acel", str(p),
                         "--puntos", course_args["p"], "--datos", course_args["d"]])
    assert code == 2 and "JSON" in err and "acel .mat" in unwrap(err)


def test_validate_json_and_the_class_answer_key_have_units(tmp_path):
    out = tmp_path / "cal"
    _json(["generate", "calibration", "--seed", "5", "--count", "201", "--out", str(out),
           "--json"])
    est = json.loads(_run(["calibrate", str(out / "ensayo.mat"), "--noise-var", "0.25,0.64",
                           "--json"])[1])
    (tmp_path / "est.json").write_text(json.dumps(est))
    rc, stdout, _ = _run(["validate", "--truth", str(out / "truth.json"), "--estimates",
                          str(tmp_path / "est.json"), "--json"])
    assert rc in (0, 1)
    v = json.loads(stdout)
    _covered(v, "validate --json")
    assert v["units"]["parameters.bias_x.estimate"] == "m/s²"
    _json(["generate", "class", "--students", "2", "--seed", "1", "--out",
           str(tmp_path / "class"), "--json"])
    key = json.loads((tmp_path / "class" / "answer_key.json").read_text())
    _covered(key, "answer_key.json")
