"""The calibration file (``calibrate --save``, :mod:`calib.calibration.calfile`,
docs/calibration-file.md): exact round trip, the same trajectory as re-fitting, clear refusals, the
.mat export."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest
import scipy.io

from bench.cli import main
from calib.calibration.calfile import FILE_UNITS, FORMAT, FORMAT_VERSION, load_calibration
from calib.calibration.tilt_plane import calibrate
from calib.files.course import read_datos, read_ensayo
from calib.units import missing_units
from tests.checks import assert_same_tree, result_only
from tests.cli import one_line_error as _error
from tests.cli import run as _run
from tests.cli import unwrap


@pytest.fixture(scope="module")
def saved(tmp_path_factory, course_dir):
    """``calibrate ensayo.mat --datos datos.txt --save cal.json`` (and ``cal.mat``) once."""
    out = tmp_path_factory.mktemp("cal")
    for name in ("cal.json", "cal.mat"):
        assert main(["calibrate", str(course_dir / "ensayo.mat"), "--datos",
                     str(course_dir / "datos.txt"), "--save", str(out / name), "--json"]) == 0
    return out


def _course_cal(course_dir, method="ols"):
    return calibrate(read_ensayo(course_dir / "ensayo.mat"),
                     read_datos(course_dir / "datos.txt").noise_var, method)


def test_file_round_trips_exactly(saved, course_dir):
    assert load_calibration(saved / "cal.json") == _course_cal(course_dir)


@pytest.mark.parametrize("noise", ["datos", "none"])
def test_wls_and_estimated_sigma2_round_trip(tmp_path, course_dir, capsys, noise):
    extra = ["--datos", course_dir / "datos.txt"] if noise == "datos" else []
    rc, _, _ = _run(capsys, "calibrate", course_dir / "ensayo.mat", "--method", "wls", *extra,
                    "--save", tmp_path / "w.json", "--json")
    assert rc == 0
    nv = read_datos(course_dir / "datos.txt").noise_var if extra else None
    assert load_calibration(tmp_path / "w.json") == calibrate(
        read_ensayo(course_dir / "ensayo.mat"), nv, "wls")
    doc = json.loads((tmp_path / "w.json").read_text())
    assert doc["sigma2_source"] == ("datos.txt" if extra else "estimated")


def test_header_names_format_source_units_and_tool(saved, course_dir):
    doc = json.loads((saved / "cal.json").read_text())
    assert (doc["format"], doc["format_version"]) == (FORMAT, FORMAT_VERSION)
    assert list(doc)[:2] == ["format", "format_version"]  # the header comes first
    sha = hashlib.sha256((course_dir / "ensayo.mat").read_bytes()).hexdigest()
    assert doc["source"] == {"name": "ensayo.mat", "sha256": sha}
    assert doc["noise_file"]["name"] == "datos.txt"
    assert doc["sigma2_source"] == "datos.txt" and doc["sigma2"] == [0.25, 0.64]
    assert doc["tool"] == {"name": "tiltbench", "version": "0.1.0"}
    assert doc["units"] == FILE_UNITS and missing_units(doc) == []
    cal = _course_cal(course_dir)
    assert np.array_equal(doc["params"], cal.params) and np.array_equal(doc["cov"], cal.cov)


def test_trajectory_from_the_file_equals_refitting(saved, course_dir, capsys):
    common = ["--acel", course_dir / "acel.mat", "--puntos", course_dir / "puntos.mat",
              "--datos", course_dir / "datos.txt", "--json"]
    rc1, refit, _ = _run(capsys, "trajectory", "--ensayo", course_dir / "ensayo.mat", *common)
    rc2, fromfile, _ = _run(capsys, "trajectory", "--calibration", saved / "cal.json", *common)
    assert rc1 == rc2 == 0
    a, b = result_only(refit), result_only(fromfile)
    assert_same_tree(b, a)
    assert a["decision"] == b["decision"]


def test_trajectory_takes_method_from_the_file(saved, course_dir, capsys):
    msg = _error(capsys, "trajectory", "--calibration", saved / "cal.json", "--method", "wls",
                 "--acel", course_dir / "acel.mat", "--puntos", course_dir / "puntos.mat")
    assert "--method wls" in msg and "cal.json" in msg


def test_trajectory_refuses_ensayo_and_calibration_together(saved, course_dir, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["trajectory", "--calibration", str(saved / "cal.json"), "--ensayo",
              str(course_dir / "ensayo.mat"), "--acel", str(course_dir / "acel.mat"),
              "--puntos", str(course_dir / "puntos.mat")])
    assert exit_.value.code == 2
    assert "not allowed with" in unwrap(capsys.readouterr().err)


@pytest.mark.parametrize("name", ["cal.json", "cal.mat"])
def test_nmin_takes_a_calibration_file(saved, course_dir, capsys, name):
    """nmin --calibration gives the --ensayo answers but the subsampling, which needs the run
    (skipped, and said on stderr)."""
    common = ["--acel", course_dir / "acel.mat", "--puntos", course_dir / "puntos.mat",
              "--datos", course_dir / "datos.txt", "--json", "--workers", "1",
              "--confirm-runs", "200"]
    rc, out, err = _run(capsys, "nmin", "--calibration", saved / name, *common)
    assert rc == 0, err
    assert "subsampling" in err and "skipped" in err
    got = json.loads(out)
    rc, out, _ = _run(capsys, "nmin", "--ensayo", course_dir / "ensayo.mat", "--steps", "1",
                      *common)
    want = result_only(out)
    got = result_only(got)
    assert got["subsample"] == [] and len(want["subsample"]) == 1
    for key in set(want) - {"subsample"}:
        assert got[key] == want[key], key


def _edited(tmp_path, saved, edit) -> str:
    doc = json.loads((saved / "cal.json").read_text())
    edit(doc)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    return str(path)


@pytest.mark.parametrize("edit, field", [
    (lambda d: d.update(format_version=FORMAT_VERSION + 1), "format_version"),
    (lambda d: d.update(format_version=1), "format_version"),
    (lambda d: d.update(format="something-else"), "format"),
    (lambda d: d.pop("format"), "format"),
    (lambda d: d.pop("cov"), "cov"),
    (lambda d: d.pop("sigma2_source"), "sigma2_source"),
    (lambda d: d.update(params=[1.0, 2.0]), "params"),
    (lambda d: d["calibration"].pop("method"), "calibration.method"),
    (lambda d: d.update(method="lsq"), "method"),
])
def test_bad_files_are_one_line_naming_file_and_field(tmp_path, saved, course_dir, capsys,
                                                      edit, field):
    path = _edited(tmp_path, saved, edit)
    msg = _error(capsys, "trajectory", "--calibration", path, "--acel",
                 course_dir / "acel.mat", "--puntos", course_dir / "puntos.mat")
    assert path in msg and f"'{field}'" in msg


def test_a_calibrate_json_output_is_not_a_calibration_file(tmp_path, course_dir, capsys):
    rc, out, _ = _run(capsys, "calibrate", course_dir / "ensayo.mat", "--json")
    assert rc == 0
    (tmp_path / "est.json").write_text(out)
    msg = _error(capsys, "trajectory", "--calibration", tmp_path / "est.json", "--acel",
                 course_dir / "acel.mat", "--puntos", course_dir / "puntos.mat")
    assert "'format'" in msg and "--save" in msg


def test_save_refuses_overwrite_without_force(saved, course_dir, capsys):
    before = (saved / "cal.json").read_bytes()
    msg = _error(capsys, "calibrate", course_dir / "ensayo.mat", "--method", "wls", "--save",
                 saved / "cal.json")
    assert "--force" in msg and (saved / "cal.json").read_bytes() == before
    rc, _, _ = _run(capsys, "calibrate", course_dir / "ensayo.mat", "--datos",
                    course_dir / "datos.txt", "--save", saved / "cal.json", "--force")
    assert rc == 0 and (saved / "cal.json").read_bytes() == before  # same inputs, same bytes


def test_save_needs_json_or_mat(tmp_path, course_dir, capsys):
    msg = _error(capsys, "calibrate", course_dir / "ensayo.mat", "--save", tmp_path / "c.txt")
    assert ".json" in msg and ".mat" in msg and not (tmp_path / "c.txt").exists()


def test_mat_export_holds_the_same_numbers(saved):
    doc = json.loads((saved / "cal.json").read_text())
    m = scipy.io.loadmat(str(saved / "cal.mat"))
    assert str(m["format"][0]) == FORMAT and m["format_version"].item() == FORMAT_VERSION
    assert str(m["method"][0]) == doc["method"] and m["g"].item() == doc["g"]
    assert m["n"].item() == doc["n"]
    assert np.array_equal(m["params"].ravel(), doc["params"])
    assert np.array_equal(m["cov"], doc["cov"])
    assert np.array_equal(m["std"].ravel(), doc["std"])
    assert np.array_equal(m["sigma2"].ravel(), doc["sigma2"])
    assert str(m["sigma2_source"][0]) == "datos.txt"
    assert str(m["source_sha256"][0]) == doc["source"]["sha256"]
    assert str(m["param_names"][0]).split(",") == doc["param_names"]


def test_validate_reads_the_calibration_file(tmp_path, capsys):
    out = tmp_path / "set"
    rc, _, _ = _run(capsys, "generate", "calibration", "--out", out, "--count", 300)
    assert rc == 0
    rc, est, _ = _run(capsys, "calibrate", out / "ensayo.mat", "--save", tmp_path / "c.json",
                      "--json")
    assert rc == 0
    (tmp_path / "est.json").write_text(est)
    base = ["validate", "--truth", out / "truth.json", "--json"]
    rc1, a, _ = _run(capsys, *base, "--estimates", tmp_path / "est.json")
    rc2, b, _ = _run(capsys, *base, "--calibration", tmp_path / "c.json")
    assert rc1 == rc2 and a.replace("est.json", "c.json") == b
    rc3, c, _ = _run(capsys, *base, "--calibration", tmp_path / "c.json", "--ensayo",
                     out / "ensayo.mat")
    assert rc3 in (0, 1) and json.loads(c)
    other = tmp_path / "other"
    _run(capsys, "generate", "calibration", "--out", other, "--count", 300, "--seed", 1)
    msg = _error(capsys, *base, "--calibration", tmp_path / "c.json", "--ensayo",
                 other / "ensayo.mat")
    assert "SHA-256" in msg


def test_mat_export_loads_back_exactly(saved, course_dir):
    """``.mat`` → :func:`load_calibration` gives the same Calibration as the ``.json`` (exact)."""
    assert load_calibration(saved / "cal.mat") == load_calibration(saved / "cal.json")
    assert load_calibration(saved / "cal.mat") == _course_cal(course_dir)


def _edited_mat(tmp_path, saved, **changes) -> str:
    m = scipy.io.loadmat(str(saved / "cal.mat"))
    m = {k: v for k, v in m.items() if not k.startswith("__")}
    m.update(changes)
    path = tmp_path / "bad.mat"
    scipy.io.savemat(str(path), m, format="5", oned_as="row")
    return str(path)


@pytest.mark.parametrize("changes, field", [
    ({"format_version": float(FORMAT_VERSION + 1)}, "format_version"),
    ({"format_version": 1.0}, "format_version"),
    ({"format": "something-else"}, "format"),
    ({"params": np.zeros((1, 4))}, "params"),
])
def test_bad_mat_files_name_file_and_field(tmp_path, saved, course_dir, capsys, changes,
                                           field):
    path = _edited_mat(tmp_path, saved, **changes)
    msg = _error(capsys, "trajectory", "--calibration", path, "--acel",
                 course_dir / "acel.mat", "--puntos", course_dir / "puntos.mat")
    assert "bad.mat" in msg and f"'{field}'" in msg


def test_commands_take_a_mat_calibration(saved, course_dir, capsys):
    """trajectory gives the same JSON with cal.mat as with cal.json."""
    base = ["--acel", course_dir / "acel.mat", "--puntos", course_dir / "puntos.mat",
            "--datos", course_dir / "datos.txt", "--json"]
    outs = [_run(capsys, "trajectory", "--calibration", saved / n, *base) for n in
            ("cal.json", "cal.mat")]
    assert outs[0][0] == outs[1][0] == 0 and outs[0][1] == outs[1][1]
