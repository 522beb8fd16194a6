"""``sensor.json`` validated like ``cal.json`` (:mod:`calib.noise.sensor_profile`, format
version 2): a profile written by ``tiltbench noise --save`` on a simulated static log loads and
round-trips exactly; every edited profile — the known failures one by one, then every field of
a real profile replaced by wrong values or deleted — is refused in one line naming the file and
the field, never a traceback; ``generate --sensor`` and ``gap --sensor`` refuse through the one
loader, :mod:`bench.sensor_twin` runs the same checks on a profile object, and the saver writes
nothing when they fail."""

from __future__ import annotations

import copy
import json
import math
import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import scipy.io

from calib.input_rules import DataError
from calib.noise import sensor_profile as sp
from calib.noise.sensor_profile import (
    NoiseTerm,
    SensorProfile,
    check_profile,
    defining_checksum,
    load_profile,
    save_profile,
)
from tests.cli import one_line_error, run


def term(v: float, level: float = 0.683) -> NoiseTerm:
    return NoiseTerm(v, (0.9 * v, 1.1 * v), (0.02, 10.0), level)


@pytest.fixture(scope="module")
def made(tmp_path_factory, course_dir) -> dict[str, Path]:
    """A twin's static log (120 s at 50 Hz, flicker on x, a walk on y, x quantized), the course
    calibration, and the profile ``tiltbench noise --calibration --save`` writes of the log."""
    from bench.cli import main

    tmp = tmp_path_factory.mktemp("schema")
    twin = save_profile(tmp / "twin.json", SensorProfile(
        sample_rate=50.0, white_noise_density=(term(2e-3), term(3e-3)),
        bias_instability=(term(1e-3), None), rate_random_walk=(None, term(4e-4)),
        quantization_step=(0.005, None)))
    assert main(["generate", "static", "--sensor", str(twin), "--duration", "120", "--theta",
                 "0.4", "--seed", "3", "--out", str(tmp / "s")]) == 0
    assert main(["calibrate", str(course_dir / "ensayo.mat"), "--save", str(tmp / "cal.json")]
                ) == 0
    assert main(["noise", str(tmp / "s" / "static.mat"), "--calibration", str(tmp / "cal.json"),
                 "--save", str(tmp / "sensor.json")]) == 0
    return {"log": tmp / "s" / "static.mat", "cal": tmp / "cal.json",
            "sensor": tmp / "sensor.json", "twin": twin}


@pytest.fixture
def doc(made) -> dict:
    return json.loads(made["sensor"].read_text())


def write(path: Path, obj: Any) -> Path:
    path.write_text(json.dumps(obj, indent=2))
    return path


def refused(path: Path) -> str:
    """The one-line DataError of loading ``path`` (fails on success or any other error)."""
    with pytest.raises(DataError) as exc:
        load_profile(path)
    line = str(exc.value)
    assert "\n" not in line and str(path) in line, line
    return line


def named_field(line: str) -> str | None:
    m = re.search(r"field '([^']+)'", line)
    return m.group(1) if m else None


# ------------------------------------------------------------------ the valid profile
def test_noise_save_writes_a_version_2_profile_that_round_trips(made, doc, tmp_path):
    assert doc["format"] == "tiltbench-sensor" and doc["format_version"] == 2
    assert list(doc) == ["format", "format_version", "tool", "sample_rate", "axes", "fit",
                         "calibration", "source", "units", "checksum"]
    assert set(doc["axes"]) == {"x", "y"} and doc["sample_rate"] == 50.0
    for block in doc["axes"].values():
        assert list(block) == list(sp.AXIS_FIELDS) and isinstance(block["fit_ok"], bool)
        w = block["white_noise_density"]
        assert w["interval"][0] <= w["value"] <= w["interval"][1]
    assert doc["axes"]["x"]["quantization_step"] == pytest.approx(0.005)
    assert doc["fit"] == {"level": 0.683, "alpha": 0.05, "n": 6000}
    assert doc["calibration"]["param_names"] == ["bias_x", "scale_x", "bias_y", "scale_y"]
    assert doc["checksum"] == {"algorithm": "sha256", "covers": list(sp.CHECKSUM_FIELDS),
                               "value": defining_checksum(doc)}
    assert doc["units"] == sp.UNITS
    prof = load_profile(made["sensor"])
    assert prof.axes == ("x", "y") and prof.source["name"] == "static.mat"
    assert prof.to_dict() == doc
    again = save_profile(tmp_path / "again.json", prof)
    assert again.read_bytes() == made["sensor"].read_bytes()  # the same bytes: exact
    assert load_profile(again) == prof
    # the per-axis API answers by index or by name, resolved or not
    assert prof.term("white_noise_density", "y") == prof.white_noise_density[1]
    for a in "xy":
        for name in sp.TERM_NAMES:
            got = prof.upper_bound(name, a)
            block = doc["axes"][a]
            assert got == (None if block[name] is not None
                           else block["unresolved_upper_bounds"][name])
    # the tool block is cosmetic: never checked, not under the checksum
    doc["tool"] = {"name": "elsewhere", "version": "9"}
    assert load_profile(write(tmp_path / "tool.json", doc)).tool_version == "9"


def test_a_profile_object_built_in_python_round_trips(tmp_path):
    """The bias/scale calibration form: lists in the order of the axes in memory, objects
    keyed by axis name in the file; an empty profile (white noise unresolved) is valid."""
    prof = SensorProfile(sample_rate=100.0, white_noise_density=(None, term(3e-3)),
                         calibration={"bias": [0.07, -0.02], "scale": [-0.03, 0.01]})
    path = save_profile(tmp_path / "p.json", prof)
    doc = json.loads(path.read_text())
    assert doc["calibration"] == {"bias": {"x": 0.07, "y": -0.02},
                                  "scale": {"x": -0.03, "y": 0.01}}
    assert doc["fit"] is None and doc["axes"]["x"]["fit_ok"] is None
    loaded = load_profile(path)
    assert loaded.to_dict() == doc == check_profile(prof).to_dict()
    from bench.sensor_twin import calibration_pairs

    assert calibration_pairs(prof) == calibration_pairs(loaded) == ((0.07, -0.02),
                                                                    (-0.03, 0.01))


# ------------------------------------------------------------------ the known failures
def _bias_instability_1e6(d):
    d["axes"]["x"]["bias_instability"] = {"value": 1e6, "interval": [0.0, 2e6],
                                          "tau_range": [0.02, 10.0], "level": 0.683}
    d["axes"]["x"]["unresolved_upper_bounds"].pop("bias_instability", None)


def _set(path: str, value: Any) -> Callable[[dict], None]:
    def edit(d):
        *head, last = path.split(".")
        for k in head:
            d = d[int(k)] if isinstance(d, list) else d[k]
        if isinstance(d, list):
            d[int(last)] = value
        else:
            d[last] = value
    return edit


def _delete(path: str) -> Callable[[dict], None]:
    def edit(d):
        *head, last = path.split(".")
        for k in head:
            d = d[k]
        del d[last]
    return edit


def _scaled_n(d):  # within every range and interval: only the checksum tells
    w = d["axes"]["x"]["white_noise_density"]
    w["value"] = w["value"] * (1 + 1e-6)


KNOWN: dict[str, tuple[Callable[[dict], Any], str]] = {
    "negative N": (_set("axes.x.white_noise_density.value", -2e-3),
                   "axes.x.white_noise_density.value"),
    "N = 1e6": (_set("axes.y.white_noise_density.value", 1e6),
                "axes.y.white_noise_density.value"),
    "1e9 Hz sample rate": (_set("sample_rate", 1e9), "sample_rate"),
    "5 m/s² quantization step": (_set("axes.x.quantization_step", 5.0),
                                 "axes.x.quantization_step"),
    "1e6 bias instability": (_bias_instability_1e6, "axes.x.bias_instability.value"),
    "1e6 calibration bias": (_set("calibration.params.0", 1e6), "calibration.params"),
    "1e6 bias (bias/scale form)": (_set("calibration", {"bias": {"x": 1e6, "y": 0.0},
                                                        "scale": {"x": 0.0, "y": 0.0}}),
                                   "calibration.bias.x"),
    "gain 1 + scale = 0": (_set("calibration.params.1", -1.0), "calibration.params"),
    "one axis of two": (_delete("axes.y"), "axes.y"),
    "params shorter than param_names (was: zip() argument 2 is shorter)": (
        lambda d: d["calibration"]["params"].pop(), "calibration.params"),
    "bias/scale for one axis": (_set("calibration", {"bias": {"x": 0.1}, "scale": {"x": 0.0}}),
                                "calibration.bias"),
    "NaN sample rate": (_set("sample_rate", math.nan), "sample_rate"),
    "Infinity in an interval": (_set("axes.y.white_noise_density.interval.1", math.inf),
                                "axes.y.white_noise_density.interval[1]"),
    "NaN in the covariance": (_set("calibration.cov.2.2", math.nan), "calibration.cov[2][2]"),
    "string where a number": (_set("sample_rate", "50"), "sample_rate"),
    "string in a term": (_set("axes.x.white_noise_density.value", "0.002"),
                         "axes.x.white_noise_density.value"),
    "bool where a number": (_set("axes.x.quantization_step", True), "axes.x.quantization_step"),
    "float sample count": (_set("fit.n", 6000.5), "fit.n"),
    "fit_ok a string": (_set("axes.x.fit_ok", "yes"), "axes.x.fit_ok"),
    "missing fit": (_delete("fit"), "fit"),
    "missing fit_ok": (_delete("axes.x.fit_ok"), "axes.x.fit_ok"),
    "missing checksum": (_delete("checksum"), "checksum"),
    "missing sample rate": (_delete("sample_rate"), "sample_rate"),
    "unknown field": (_set("extra", {}), "extra"),
    "unknown axis": (_set("axes.w", None), "axes.w"),
    "axes as a list (version-1 style)": (_set("axes", ["x", "y"]), "axes"),
    "interval without its value": (_set("axes.x.white_noise_density.interval", [1.0, 2.0]),
                                   "axes.x.white_noise_density.interval"),
    "negative τ": (_set("axes.x.white_noise_density.tau_range", [-1.0, 2.0]),
                   "axes.x.white_noise_density.tau_range"),
    "bound of a resolved term": (_set("axes.x.unresolved_upper_bounds.white_noise_density",
                                      0.1), "axes.x.unresolved_upper_bounds.white_noise_density"),
    "level other than the fit's": (_set("axes.x.white_noise_density.level", 0.95),
                                   "axes.x.white_noise_density.level"),
    "covariance not symmetric": (_set("calibration.cov.0.1", 1e-9), "calibration.cov"),
    "param_names of another sensor": (_set("calibration.param_names.0", "bias_z"),
                                      "calibration.param_names"),
    "calibration method unknown": (_set("calibration.method", "guess"), "calibration.method"),
    "source not a file reference": (_set("source", {"name": 3}), "source"),
    "units edited": (_set("units.sample_rate", "kHz"), "units"),
    "hand-edited value, old checksum": (_scaled_n, "checksum"),
    "version 1": (_set("format_version", 1), "format_version"),
    "version 3": (_set("format_version", 3), "format_version"),
    "another format": (_set("format", "tiltbench-calibration"), "format"),
}


@pytest.mark.parametrize("case", KNOWN, ids=str)
def test_known_failures_are_one_line_naming_file_and_field(case, doc, tmp_path):
    edit, field = KNOWN[case]
    edit(doc)
    line = refused(write(tmp_path / "sensor.json", doc))
    assert f"field '{field}'" in line, line
    if case == "hand-edited value, old checksum":
        assert "checksum/consistency failed" in line and "--save" in line
    if field == "format_version":
        assert "re-run `tiltbench noise" in line


@pytest.mark.parametrize("text,what", [
    ("[1, 2]", "the top level is a JSON list"), ('"sensor"', "the top level is a JSON string"),
    ("", "empty file"), ("{", "not JSON"), ('{"format": "something else"}',
                                            "not a sensor profile: field 'format'"),
    ("{}", "not a sensor profile: field 'format' missing")])
def test_not_a_profile_at_all(text, what, tmp_path):
    path = tmp_path / "sensor.json"
    path.write_text(text)
    assert what in refused(path)
    path.write_bytes(b"\xff\xfe{}")
    assert "not UTF-8" in refused(path)


def test_the_version_1_layout_of_the_previous_noise_save_is_refused(doc, tmp_path):
    """What ``noise --save`` wrote before: terms as [x, y] lists at the top, no checksum."""
    x, y = doc["axes"]["x"], doc["axes"]["y"]
    v1 = {"format": "tiltbench-sensor", "format_version": 1,
          "tool": {"name": "tiltbench", "version": "0.1.0"}, "sample_rate": 50.0,
          "axes": ["x", "y"],
          "white_noise_density": [x["white_noise_density"], y["white_noise_density"]],
          "bias_instability": None, "rate_random_walk": None, "quantization_step": [0.005, None],
          "calibration": None, "source": doc["source"],
          "extra": {"unresolved_upper_bounds": {}, "level": 0.683}, "units": {}}
    line = refused(write(tmp_path / "old.json", v1))
    assert "field 'format_version' is 1" in line and "version 2 only" in line
    assert "re-run `tiltbench noise STATIC_LOG --save sensor.json`" in line


# ------------------------------------------------------------------ the class of edits
BAD_VALUES = (-1.0, 0.0, 1e300, math.nan, "x", None, True, [], {})


def _nodes(obj: Any, path: str = "") -> Iterator[tuple[str, Any, Any]]:
    """(dotted path as the messages write it, container, key) of every value below ``obj``."""
    items = obj.items() if isinstance(obj, dict) else enumerate(obj)
    for k, v in items:
        p = f"{path}[{k}]" if isinstance(obj, list) else f"{path}.{k}".lstrip(".")
        yield p, obj, k
        if isinstance(v, (dict, list)) and v:
            yield from _nodes(v, p)


def _names_it(field: str | None, edited: str) -> bool:
    """The message names the edited field, one that holds it or one inside it (a key missing
    from an edited object), or the checksum (a value that passes every check, changed under
    the checksum)."""
    if field is None:
        return False
    return (field in ("checksum", edited) or edited.startswith((field + ".", field + "["))
            or field.startswith((edited + ".", edited + "[")))


def test_every_field_replaced_or_deleted_is_one_line_naming_it(doc, tmp_path):
    """Each value of a real profile, container or number, replaced by each of
    :data:`BAD_VALUES` or deleted: never a traceback, always one line naming the file and the
    field (only ``tool`` is cosmetic and loads)."""
    path = tmp_path / "sensor.json"
    paths = [p for p, _, _ in _nodes(doc) if not p.startswith("tool")]
    assert len(paths) > 100
    edits = same = 0
    for p in paths:
        for value in (*BAD_VALUES, "<delete>"):
            d = copy.deepcopy(doc)
            container, key = next((c, k) for q, c, k in _nodes(d) if q == p)
            if json.dumps(container[key]) == json.dumps(value):  # a null left null
                same += 1
                continue
            if value == "<delete>":
                del container[key]
            else:
                container[key] = copy.deepcopy(value)
            try:
                load_profile(write(path, d))
            except DataError as exc:
                line = str(exc)
            else:
                raise AssertionError(f"{p} = {value!r} loaded")
            edits += 1
            assert "\n" not in line and str(path) in line, line
            assert _names_it(named_field(line), p), (p, value, line)
    assert edits + same == len(paths) * (len(BAD_VALUES) + 1) and edits > 1000


# ------------------------------------------------------------------ the consumers
CLI_CASES = ("negative N", "1e9 Hz sample rate", "one axis of two",
             "params shorter than param_names (was: zip() argument 2 is shorter)",
             "hand-edited value, old checksum", "version 1")


@pytest.fixture
def spy(monkeypatch) -> list[Path]:
    """Every path the one loader is called with (generate and gap import it when they run)."""
    calls: list[Path] = []
    real = sp.load_profile

    def load(path):
        calls.append(Path(path))
        return real(path)

    monkeypatch.setattr(sp, "load_profile", load)
    return calls


@pytest.mark.parametrize("case", CLI_CASES, ids=str)
def test_generate_sensor_refuses_through_the_loader(case, doc, tmp_path, capsys, spy):
    edit, field = KNOWN[case]
    edit(doc)
    bad = write(tmp_path / "bad.json", doc)
    for argv in (["generate", "static", "--sensor", bad, "--out", tmp_path / "o"],
                 ["generate", "calibration", "--sensor", bad, "--positions", "4",
                  "--out", tmp_path / "o"]):
        line = one_line_error(capsys, *argv)
        assert str(bad) in line and f"field '{field}'" in line, line
        assert not (tmp_path / "o").exists()
    assert spy and all(p == bad for p in spy)


@pytest.mark.parametrize("case", ["N = 1e6", "one axis of two", "hand-edited value, old checksum"],
                         ids=str)
def test_gap_sensor_refuses_through_the_loader(case, doc, course_dir, tmp_path, capsys, spy):
    edit, field = KNOWN[case]
    edit(doc)
    bad = write(tmp_path / "bad.json", doc)
    line = one_line_error(capsys, "gap", course_dir / "ensayo.mat", "--noise-var", "0.25,0.64",
                          "--sensor", bad, "--report", tmp_path / "r")
    assert str(bad) in line and f"field '{field}'" in line, line
    assert spy == [bad] and not (tmp_path / "r").exists()


def test_generate_sensor_reads_the_saved_profile(made, tmp_path, capsys, spy):
    rc, _, err = run(capsys, "generate", "static", "--sensor", made["sensor"], "--duration",
                     "10", "--out", tmp_path / "o")
    assert rc == 0, err
    truth = json.loads((tmp_path / "o" / "truth.json").read_text())
    prof = load_profile(made["sensor"])
    assert truth["sensor_profile"]["white_noise_density"] == [
        prof.white_noise_density[0].value, prof.white_noise_density[1].value]
    assert truth["sensor"]["x"]["bias"] == prof.calibration["params"][0]
    assert spy and spy[0] == made["sensor"]


def test_the_twin_checks_a_profile_object():
    """:mod:`bench.sensor_twin` on profiles built in Python: one line naming the field, where
    an IndexError, a zip() error or a silent twin with a negative variance came before."""
    from bench.sensor_twin import calibration_pairs, twin_sensor, twin_truth

    good = dict(sample_rate=50.0, white_noise_density=(term(2e-3), term(3e-3)))
    cases = [
        (dict(axes=("x",), white_noise_density=(term(2e-3),)), "axes.y"),
        (dict(white_noise_density=(term(2e-3),)), "white_noise_density"),
        (dict(white_noise_density=(NoiseTerm(-2e-3, (-3e-3, -1e-3), (0.02, 10.0)),
                                   term(3e-3))), "axes.x.white_noise_density.value"),
        (dict(sample_rate=1e9), "sample_rate"),
        (dict(quantization_step=(5.0, None)), "axes.x.quantization_step"),
        (dict(calibration={"param_names": ["bias_x", "scale_x", "bias_y", "scale_y"],
                           "params": [0.1, 0.0, 0.1], "cov": np.eye(4).tolist()}),
         "calibration.params"),
        (dict(calibration={"bias": [1e6, 0.0], "scale": [0.0, 0.0]}), "calibration.bias.x"),
        (dict(extra={"notes": "x"}), "extra.notes"),
    ]
    for kw, field in cases:
        prof = SensorProfile(**{**good, **kw})
        for call in (lambda p: twin_sensor(p), lambda p: twin_truth(p, 50.0),
                     calibration_pairs):
            with pytest.raises(DataError) as exc:
                call(prof)
            line = str(exc.value)
            assert "\n" not in line and line.startswith("<memory>: ") and (
                f"field '{field}'" in line), line
    assert twin_sensor(SensorProfile(**good)).x.noise_var == pytest.approx((2e-3) ** 2 * 50)


def test_the_saver_writes_nothing_when_a_check_fails(tmp_path):
    bad = SensorProfile(sample_rate=50.0, white_noise_density=(term(2e-3), term(3e-3)),
                        quantization_step=(5.0, None))
    with pytest.raises(DataError, match=r"sensor\.json \(not written\): field "
                                        r"'axes\.x\.quantization_step' is 5 m/s²"):
        save_profile(tmp_path / "sensor.json", bad)
    assert list(tmp_path.iterdir()) == []


def test_noise_save_refuses_a_profile_outside_the_ranges_and_writes_nothing(tmp_path, capsys):
    """A log on a 2.5 m/s² lattice (coarser than any accelerometer's LSB: a unit mistake):
    the fit runs, the saver refuses the profile in one line, neither --save nor --plot is
    written."""
    rng = np.random.default_rng(7)
    n, rate = 4096, 50.0
    acc = np.column_stack([2.5 * np.round(1.5 * rng.standard_normal(n) / 2.5),
                           -9.8 + 0.02 * rng.standard_normal(n)])
    log = tmp_path / "coarse.mat"
    scipy.io.savemat(log, {"t": (np.arange(n) / rate)[:, None], "Aerr": acc})
    save, plot = tmp_path / "sensor.json", tmp_path / "allan.png"
    line = one_line_error(capsys, "noise", log, "--save", save, "--plot", plot)
    assert f"{save} (not written): field 'axes.x.quantization_step' is 2.5 m/s²" in line
    assert not save.exists() and not plot.exists()


def test_constants_shared_with_the_calibration_file_stay_equal():
    """The noise wing may not import the calibration wing (tests/test_imports.py): its copies
    of the calibration file's limits are kept equal here."""
    from calib.calibration import calfile
    from calib.calibration.tilt_plane import METHODS
    from calib.noise.allan import MIN_SAMPLES
    from calib.noise.allan_model import TERM_NAMES

    assert sp.GAIN_RANGE == calfile.GAIN_RANGE and sp.G_RANGE == calfile.G_RANGE
    assert sp.SIGMA2_RANGE == calfile.SIGMA2_RANGE
    assert sp.CORRELATION_EIG_MIN == calfile.CORRELATION_EIG_MIN
    assert sp.CALIBRATION_METHODS == METHODS
    assert sp.N_RANGE[0] == MIN_SAMPLES and sp.TERM_NAMES == TERM_NAMES
    # tighter than cal.json's reading limit, on purpose (module docstring)
    assert sp.MAX_ABS_CALIBRATION_BIAS < calfile.MAX_ABS_BIAS
