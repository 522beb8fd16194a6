"""``tiltbench noise --datasheet`` (:mod:`calib.noise.datasheet`, the unit reader of
:mod:`calib.noise.term_units`): datasheet values read with their units and converted to SI
(checked by hand arithmetic: 1 µg = 9.80665e-6 m/s², 1 °/√h = (π/180)/60 rad/√s, 1 °/h =
(π/180)/3600 rad/s, 1 °/h/√h = (π/180)/3600/60 rad/s/√s), every refusal in one line naming the
item or field and what is accepted, the verdict rule (meets / exceeds / inconclusive / not
measured), round trips, and the command end to end on a small still IMU log.

The log: 2048 samples at 50 Hz of white noise, 0.02 m/s² per sample on the accelerometer and
0.002 rad/s on the gyro, so N = σ/√fs = 2.828e-3 (m/s²)/√Hz = 288.4 µg/√Hz and 2.828e-4 rad/√s
= 0.972 °/√h; a datasheet of 400 µg/√Hz and 2 °/√h is met, one of 100 µg/√Hz and 0.2 °/√h is
exceeded (by about 2.9× and 4.9×: far outside the ~2 % intervals of 2048 samples).
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from scipy.io import savemat

from calib.noise.allan import NoiseCharacterization, TermFit
from calib.noise.datasheet import (
    Datasheet,
    DatasheetCheck,
    DatasheetValue,
    TermCheck,
    check_datasheet,
    compare_term,
    datasheet_from_dict,
    load_datasheet,
    parse_datasheet,
    read_datasheets,
    verdict,
)
from calib.noise.term_units import (
    DATASHEET,
    SI_UNITS,
    TERM_DIMENSIONS,
    parse_unit,
    unit_factor,
)
from tests.cli import one_line_error, run

UG = 9.80665e-6
"""1 µg in m/s² (the standard gravity datasheets mean)."""
DEG = math.pi / 180.0
ARW = DEG / 60.0
"""1 °/√h in rad/√s: (π/180) rad / √(3600 s)."""
DPH = DEG / 3600.0
"""1 °/h in rad/s."""
RRW = DEG / 3600.0 / 60.0
"""1 °/h/√h in rad/s/√s."""


def _si(spec: str) -> float:
    (value,) = parse_datasheet(spec).values
    return value.si


# ------------------------------------------------------------------ units and conversion
@pytest.mark.parametrize("spec, expected", [
    ("N=60ug/rtHz", 60 * UG), ("N=60µg/√Hz", 60 * UG), ("N=60 μg/√Hz", 60 * UG),
    ("N=60ug/sqrt(Hz)", 60 * UG), ("N=60 ug / rt(Hz)", 60 * UG), ("N=60UG/RTHZ", 60 * UG),
    ("N=60ug*Hz^-0.5", 60 * UG), ("N=60ug/Hz^(1/2)", 60 * UG), ("N=0.06mg/√Hz", 60 * UG),
    ("N=5.884e-4(m/s^2)/sqrt(Hz)", 5.884e-4), ("N=5.884e-4 m/s²/√Hz", 5.884e-4),
    ("VRW=0.06 m/s/√h", 0.06 / 60), ("acc.noise_density=60ug/rtHz", 60 * UG),
    ("B=20ug", 20 * UG), ("BI=0.02mg", 20 * UG), ("B=2e-5g", 20 * UG), ("B=1.5e-4 m/s^2", 1.5e-4),
    ("K=3ug/rt(s)", 3 * UG), ("RRW=3µg/√s", 3 * UG), ("K=3e-5 m/s^2/sqrt(s)", 3e-5),
    ("ARW=0.2deg/rth", 0.2 * ARW), ("N=0.2°/√h", 0.2 * ARW), ("gyro.N=0.2deg/sqrt(hr)", 0.2 * ARW),
    ("N=0.01dps/rtHz", 0.01 * DEG), ("N=10mdps/√Hz", 0.01 * DEG), ("N=0.01 °/s/√Hz", 0.01 * DEG),
    ("N=1e-4 (rad/s)/sqrt(Hz)", 1e-4),
    ("BI=5deg/h", 5 * DPH), ("B=5 °/hr", 5 * DPH), ("B=5dph", 5 * DPH), ("B=0.001dps", 1e-3 * DEG),
    ("B=2e-5 rad/s", 2e-5),
    ("RRW=3°/h/√h", 3 * RRW), ("K=3deg/h^1.5", 3 * RRW), ("K=3 deg/h/rt(h)", 3 * RRW),
    ("K=3deg/hr**(3/2)", 3 * RRW),
])
def test_values_are_read_with_their_units_into_si(spec, expected):
    assert _si(spec) == pytest.approx(expected, rel=1e-12)


def test_the_kind_comes_from_the_unit_scope_or_name():
    sheet = parse_datasheet("N=60ug/rtHz,B=20ug,ARW=0.2deg/rth,BI=5deg/h,x.N=45ug/rtHz,"
                            "gyro_z.K=3deg/h/rt(h)")
    got = [(v.scope, v.kind, v.term) for v in sheet.values]
    assert got == [("accelerometer", "accelerometer", "white_noise_density"),
                   ("accelerometer", "accelerometer", "bias_instability"),
                   ("gyro", "gyro", "white_noise_density"), ("gyro", "gyro", "bias_instability"),
                   ("x", "accelerometer", "white_noise_density"),
                   ("gyro_z", "gyro", "rate_random_walk")]
    # the axis's own value wins over its kind's; other axes take the kind's
    assert sheet.lookup("x", "accelerometer", "white_noise_density").value == 45.0
    assert sheet.lookup("y", "accelerometer", "white_noise_density").value == 60.0
    assert sheet.lookup("gyro_x", "gyro", "rate_random_walk") is None


def test_units_show_in_the_datasheet_spelling_when_they_are_its_unit():
    ug, mg, dps = parse_datasheet("N=60ug/rtHz,x.N=0.06mg/rtHz,ARW=0.01dps/rtHz").values
    assert (ug.unit, ug.display_unit) == ("ug/rtHz", "µg/√Hz")
    assert mg.display_unit == "mg/rtHz" and dps.display_unit == "dps/rtHz"
    assert parse_datasheet("ARW=0.2deg/rt(h)").values[0].display_unit == "°/√h"


def test_every_si_and_datasheet_unit_of_term_units_reads_back():
    """One home of the factors: each unit string of :mod:`calib.noise.term_units` parses to
    its term's dimension, the SI ones with factor 1, the datasheet ones with 1/factor."""
    for kind, terms in DATASHEET.items():
        for name, (unit, factor) in terms.items():
            f, dim = parse_unit(unit)
            assert dim == TERM_DIMENSIONS[kind][name], (kind, name, unit)
            assert f * factor == pytest.approx(1.0, rel=1e-12), (kind, name, unit)
            f, dim = parse_unit(SI_UNITS[kind][name])
            assert (f, dim) == (1.0, TERM_DIMENSIONS[kind][name]), (kind, name)
    assert unit_factor("°/√h", "gyro", "white_noise_density") == pytest.approx(ARW, rel=1e-15)


def test_a_json_file_and_specs_merge_in_order(tmp_path):
    path = tmp_path / "sheet.json"
    path.write_text(json.dumps({
        "name": "ADXL-test",
        "accelerometer": {"white_noise_density": {"value": 60, "unit": "µg/√Hz"},
                          "bias_instability": "20 µg"},
        "gyro": {"ARW": "0.2 °/√h", "BI": {"value": 5, "unit": "deg/h"}},
        "x": {"N": "45 ug/rtHz"}}, ensure_ascii=False), encoding="utf-8")
    sheet = load_datasheet(path)
    assert sheet.name == "ADXL-test" and len(sheet.values) == 5
    assert sheet.lookup("y", "accelerometer", "white_noise_density").si == pytest.approx(60 * UG)
    assert sheet.lookup("gyro_y", "gyro", "bias_instability").si == pytest.approx(5 * DPH)
    assert sheet.lookup("x", "accelerometer", "white_noise_density").si == pytest.approx(45 * UG)
    merged = read_datasheets([str(path), "N=70ug/rtHz,y.B=30ug"])
    assert merged.name == "ADXL-test" and len(merged.values) == 6
    assert merged.lookup("z", "accelerometer", "white_noise_density").value == 70.0  # replaced
    assert merged.lookup("x", "accelerometer", "white_noise_density").value == 45.0
    assert merged.lookup("y", "accelerometer", "bias_instability").value == 30.0
    assert Datasheet.from_dict(json.loads(json.dumps(merged.to_dict()))) == merged


# ------------------------------------------------------------------ refusals
@pytest.mark.parametrize("spec, said", [
    ("Q=3ug", ["unknown term 'Q'", "N (noise density", "RRW"]),
    ("N=60ug", ["unit 'ug' is m·s^-2", "neither", "accepted units: µg/√Hz", "°/√h"]),
    ("x.N=60ug", ["accelerometer's white noise density is m·s^-3/2", "accepted units: µg/√Hz"]),
    ("B=20ug/rtHz", ["neither", "accepted units: µg, ug, mg, g, m/s^2", "°/h"]),
    ("gyro.BI=5ug", ["gyro's bias instability is rad·s^-1", "accepted units: °/h"]),
    ("ARW=0.2ug/rtHz", ["gyro's white noise density", "accepted units: °/√h"]),
    ("N=-60ug/rtHz", ["-60", "not a positive finite number"]),
    ("N=0ug/rtHz", ["not a positive finite number"]),
    ("N=nan ug/rtHz", ["nan", "not a positive finite number"]),
    ("N=inf ug/rtHz", ["inf", "not a positive finite number"]),
    ("N=1e999ug/rtHz", ["not a positive finite number"]),
    ("N=60", ["no unit", "never guessed", "µg/√Hz", "°/√h"]),
    ("N=60 furlongs/rtHz", ["unknown unit name 'furlongs'"]),
    ("N=60ug/(rtHz", ["ends too early"]),
    ("w.N=60ug/rtHz", ["unknown scope 'w'", "gyro_x"]),
    ("acc.ARW=0.2deg/rth", ["ARW is the gyro's white noise density", "not an accelerometer's"]),
    ("gyro_z.VRW=60ug/rtHz", ["gyro_z is a gyro axis"]),
    ("N=60ug/rtHz,VRW=50ug/rtHz", ["given twice"]),
    ("N=ug/rtHz", ["no number"]),
    ("N:60ug/rtHz", ["expected [SCOPE.]TERM=VALUE UNIT"]),
])
def test_a_bad_spec_is_refused_in_one_line_naming_the_item(spec, said):
    with pytest.raises(ValueError) as err:
        parse_datasheet(spec)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("item '")
    for words in said:
        assert words in msg, msg


@pytest.mark.parametrize("doc, said", [
    ([1, 2], ["expected a JSON object"]),
    ({}, ["no datasheet value"]),
    ({"accel": {"N": "abc"}}, ["field 'accel.N'", "expected \"VALUE UNIT\""]),
    ({"accelerometer": {"N": {"value": True, "unit": "ug/rtHz"}}}, ["not a number"]),
    ({"accelerometer": {"N": {"value": "60", "unit": "ug/rtHz"}}}, ["not a number"]),
    ({"accelerometer": {"N": {"value": 60}}}, ["field 'accelerometer.N'", "\"unit\""]),
    ({"accelerometer": {"N": {"value": 60, "unit": "ug"}}}, ["accepted units: µg/√Hz"]),
    ({"accelerometer": {"N": {"value": -1.0, "unit": "ug/rtHz"}}}, ["positive finite"]),
    ({"accelerometer": {"N": {"value": float("nan"), "unit": "ug/rtHz"}}}, ["positive finite"]),
    ({"accelerometer": {"Q": "3 ug"}}, ["unknown term 'Q'"]),
    ({"magnetometer": {"N": "3 ug/rtHz"}}, ["unknown field 'magnetometer'", "gyro"]),
    ({"name": 3, "gyro": {"N": "1 deg/rth"}}, ["field 'name'"]),
    ({"gyro": {"N": "1 deg/rth", "ARW": "2 deg/rth"}}, ["given twice"]),
])
def test_a_bad_file_is_refused_naming_the_field(doc, said, tmp_path):
    path = tmp_path / "sheet.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ValueError) as err:
        load_datasheet(path)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(str(path))
    for words in said:
        assert words in msg, msg


def test_a_missing_or_broken_file_is_refused(tmp_path):
    with pytest.raises(ValueError, match="datasheet file not found"):
        load_datasheet(tmp_path / "none.json")
    (tmp_path / "bad.json").write_text("{N=60")
    with pytest.raises(ValueError, match="not a JSON datasheet"):
        read_datasheets([str(tmp_path / "bad.json")])
    with pytest.raises(ValueError, match="no TERM=VALUE UNIT item"):
        parse_datasheet(" , ")
    with pytest.raises(ValueError, match="an empty value"):
        read_datasheets([" "])
    assert datasheet_from_dict({"x": {"N": "1 ug/rtHz"}}).values[0].scope == "x"


# ------------------------------------------------------------------ the verdict
def test_verdict_of_an_interval_against_a_maximum():
    assert verdict(45.9, 48.3, 60.0) == "meets"
    assert verdict(45.9, 60.0, 60.0) == "meets"  # at the maximum: still within the datasheet
    assert verdict(60.0, 70.0, 60.0) == "inconclusive"  # lo = D is not above it
    assert verdict(60.1, 70.0, 60.0) == "exceeds"
    assert verdict(55.0, 65.0, 60.0) == "inconclusive"


def _fit(value, lo, hi, resolved=True, name="white_noise_density", kind="accelerometer"):
    return TermFit(name=name, resolved=resolved, value=value if resolved else None,
                   interval=(lo, hi), upper_bound=hi, tau_range=(0.02, 10.0), z=5.0,
                   p_value=1e-6, level=0.683, kind=kind)


LIMIT = parse_datasheet("N=60ug/rtHz").values[0]


@pytest.mark.parametrize("fit, expected, ratio, text", [
    (_fit(47.1 * UG, 45.9 * UG, 48.3 * UG), "meets", 47.1 / 60, "meets (0.785×)"),
    (_fit(90 * UG, 80 * UG, 100 * UG), "exceeds", 1.5, "exceeds by 1.5× (at least 1.33×)"),
    (_fit(62 * UG, 55 * UG, 70 * UG), "inconclusive", 62 / 60, "inconclusive (0.917–1.17×)"),
    (_fit(None, 0.0, 30 * UG, resolved=False), "meets", 0.5, "meets (≤ 0.5×, not resolved)"),
    (_fit(None, 0.0, 90 * UG, resolved=False), "inconclusive", 1.5,
     "inconclusive (≤ 1.5×, not resolved)"),
    # an unresolved term whose interval excludes D from below (the walk's rise rule unmet):
    # reported as its bound only, so never "exceeds"
    (_fit(None, 70 * UG, 90 * UG, resolved=False), "inconclusive", 1.5,
     "inconclusive (≤ 1.5×, not resolved)"),
])
def test_compare_term(fit, expected, ratio, text):
    check = compare_term("x", fit, LIMIT)
    assert check.verdict == expected and check.ratio == pytest.approx(ratio, rel=1e-12)
    assert check.verdict_text() == text
    assert check.level == 0.683 and check.note == ""
    line = check.summary()
    assert line.startswith("x      N ") and "vs datasheet 60 µg/√Hz: " + text in line
    d = check.to_dict()
    assert d["si"]["datasheet"] == pytest.approx(60 * UG)
    assert d["datasheet_units"]["datasheet"] == 60
    assert d["datasheet_units"]["upper_bound"] == pytest.approx(fit.upper_bound / UG, rel=1e-12)
    assert d["datasheet_units"]["unit"] == "µg/√Hz"
    assert d["si"]["unit"] == "(m/s^2)/sqrt(Hz)"
    back = TermCheck.from_dict(json.loads(json.dumps(d)))
    assert back == check and back.to_dict() == d


def test_not_measured_and_a_failed_fit():
    check = compare_term("x", None, LIMIT)
    assert check.verdict == "not measured" and check.ratio is None and "no white" in check.note
    assert TermCheck.from_dict(check.to_dict()) == check
    noted = compare_term("x", _fit(47.1 * UG, 45.9 * UG, 48.3 * UG), LIMIT, fit_ok=False)
    assert noted.verdict == "meets" and "fit_ok false" in noted.summary()
    with pytest.raises(ValueError, match="verdict"):
        TermCheck(axis="x", limit=LIMIT, verdict="passes", level=0.683)


# ------------------------------------------------------------------ the command
HEADER = "t (s),ax (m/s^2),ay (m/s^2),az (m/s^2),gx (rad/s),gy (rad/s),gz (rad/s)"
N_ACC_UG = 0.02 / math.sqrt(50.0) / UG  # 288.4 µg/√Hz
N_GYRO_ARW = 0.002 / math.sqrt(50.0) / ARW  # 0.972 °/√h


@pytest.fixture(scope="module")
def imu_log(tmp_path_factory):
    """A still 3-axis accelerometer + gyro log (module docstring), and one without the gyro."""
    tmp = tmp_path_factory.mktemp("datasheet")
    n, rate = 2048, 50.0
    rng = np.random.default_rng(20260521)
    acc = 0.02 * rng.standard_normal((n, 3)) + [0.0, 0.0, -9.8]
    gyro = 0.002 * rng.standard_normal((n, 3))
    rows = np.column_stack([np.arange(n) / rate, acc, gyro])
    path = tmp / "imu.csv"
    path.write_text(HEADER + "\n" + "".join(",".join(f"{v:.6f}" for v in r) + "\n"
                                            for r in rows))
    plane = tmp / "plane.mat"
    savemat(plane, {"t": (np.arange(n) / rate)[:, None], "Aerr": acc[:, [0, 2]]})
    return path, plane


def _json(capsys, *argv) -> dict:
    rc, out, err = run(capsys, *argv, "--json")
    assert rc == 0, err
    return json.loads(out)


def test_a_generous_datasheet_is_met(imu_log, capsys):
    log, _ = imu_log
    spec = "N=400ug/rtHz,B=1000ug,ARW=2deg/rth,BI=200deg/h"
    doc = _json(capsys, "noise", log, "--datasheet", spec)
    ds = doc["datasheet"]
    assert ds["counts"] == {"meets": 12, "exceeds": 0, "inconclusive": 0, "not measured": 0}
    assert ds["level"] == 0.683 and "maximum" in ds["rule"]
    checks = {(c["axis"], c["term"]): c for c in ds["checks"]}
    assert len(checks) == 12
    x = checks["x", "white_noise_density"]
    assert x["si"]["datasheet"] == pytest.approx(400 * UG, rel=1e-12)
    assert x["datasheet_units"] == {**x["datasheet_units"], "unit": "µg/√Hz", "datasheet": 400}
    assert x["ratio"] == pytest.approx(N_ACC_UG / 400, rel=0.1)
    # the measured term as the noise result has it, in SI and in the datasheet's unit
    term = doc["axes"]["x"]["terms"]["white_noise_density"]
    assert x["si"]["value"] == term["value"] and x["si"]["interval"] == term["interval"]
    assert x["datasheet_units"]["value"] == pytest.approx(term["value"] / UG, rel=1e-12)
    g = checks["gyro_y", "white_noise_density"]
    assert g["datasheet_units"]["unit"] == "°/√h" and g["si"]["unit"] == "(rad/s)/sqrt(Hz)"
    assert g["datasheet_units"]["value"] == pytest.approx(
        doc["axes"]["gyro_y"]["terms"]["white_noise_density"]["value"] / ARW, rel=1e-12)
    assert g["ratio"] == pytest.approx(N_GYRO_ARW / 2, rel=0.1)
    assert doc["units"]["datasheet.checks.*.ratio"] == "1"
    assert doc["units"]["datasheet.checks.*.si.*"].startswith("datasheet.checks.*.si.unit")
    assert DatasheetCheck.from_dict(ds).to_dict() == ds
    # the readable lines: one per axis and term, in the datasheet's units
    rc, out, _ = run(capsys, "noise", log, "--datasheet", spec)
    assert rc == 0
    lines = [ln for ln in out.splitlines() if " vs datasheet " in ln]
    assert len(lines) == 12 and all(": meets (" in ln for ln in lines)
    assert any(ln.startswith("x      N ") and "µg/√Hz [" in ln for ln in lines)
    assert any(ln.startswith("gyro_z N ") and "°/√h [" in ln for ln in lines)
    assert "datasheet: meets 12, exceeds 0, inconclusive 0, not measured 0" in out


def test_a_tight_datasheet_is_exceeded_and_an_axis_value_wins(imu_log, capsys, tmp_path):
    log, _ = imu_log
    doc = _json(capsys, "noise", log, "--datasheet", "N=100ug/rtHz,ARW=0.2deg/rth,y.N=0.5mg/√Hz")
    verdicts = {c["axis"]: (c["verdict"], c["ratio"]) for c in doc["datasheet"]["checks"]}
    assert verdicts["y"][0] == "meets"  # 0.5 mg/√Hz = 500 µg/√Hz for y alone
    for axis in ("x", "z"):
        assert verdicts[axis][0] == "exceeds"
        assert verdicts[axis][1] == pytest.approx(N_ACC_UG / 100, rel=0.1)
    for axis in ("gyro_x", "gyro_y", "gyro_z"):
        assert verdicts[axis][0] == "exceeds"
        assert verdicts[axis][1] == pytest.approx(N_GYRO_ARW / 0.2, rel=0.1)
    y = next(c for c in doc["datasheet"]["checks"] if c["axis"] == "y")
    assert y["datasheet_units"]["unit"] == "mg/√Hz"
    assert y["datasheet_units"]["value"] == pytest.approx(y["si"]["value"] / (1e3 * UG))
    # a JSON file with a name, and a spec after it replacing one of its values
    sheet = tmp_path / "sheet.json"
    sheet.write_text(json.dumps({"name": "tight part", "gyro": {"BI": "0.5 °/h"},
                                 "accelerometer": {"N": "100 µg/√Hz"}}, ensure_ascii=False),
                     encoding="utf-8")
    rc, out, err = run(capsys, "noise", log, "--datasheet", sheet, "--datasheet", "N=1mg/rtHz")
    assert rc == 0, err
    assert "datasheet check (tight part)" in out
    lines = [ln for ln in out.splitlines() if " vs datasheet " in ln]
    assert len(lines) == 6
    assert all(": meets (" in ln for ln in lines if ln.split()[1] == "N")
    # a gyro bias instability far below this log's reach: a bound above D, or an interval
    # that holds or exceeds it — never "meets"
    assert not any(": meets" in ln for ln in lines if ln.split()[1] == "B")


def test_values_the_log_cannot_measure(imu_log, capsys):
    _, plane = imu_log
    rc, out, err = run(capsys, "noise", plane, "--datasheet", "N=400ug/rtHz,ARW=0.2deg/rth,"
                       "gyro_x.BI=5deg/h")
    assert rc == 0, err
    assert "gyro   N not measured (the log has no gyro axis); datasheet 0.2 °/√h" in out
    assert "gyro_x B not measured (the log has no axis gyro_x); datasheet 5 °/h" in out
    assert "not measured 2" in out


def test_check_datasheet_on_a_result(imu_log, capsys):
    """The library call on the noise result: every axis of each kind takes its kind's value;
    an axis left out of the result makes its own value "not measured"."""
    log, _ = imu_log
    doc = _json(capsys, "noise", log)
    res = NoiseCharacterization.from_dict(doc)
    sheet = parse_datasheet("N=400ug/rtHz,gyro_z.N=2deg/rth")
    check = check_datasheet(res, sheet)
    # (the axes in the order of the JSON's keys, which print_json sorts)
    assert sorted((c.axis, c.verdict) for c in check.checks) == [
        ("gyro_z", "meets"), ("x", "meets"), ("y", "meets"), ("z", "meets")]
    fewer = dataclasses.replace(res, axes=tuple(a for a in res.axes if a.axis != "gyro_z"))
    check = check_datasheet(fewer, sheet)
    assert check.checks[-1].axis == "gyro_z" and check.checks[-1].verdict == "not measured"
    assert check.counts["not measured"] == 1
    assert DatasheetCheck.from_dict(json.loads(json.dumps(check.to_dict()))) == check
    assert DatasheetValue.from_dict(sheet.values[0].to_dict()) == sheet.values[0]


def test_a_bad_datasheet_is_one_line_before_the_log_is_read(imu_log, tmp_path, capsys):
    log, _ = imu_log
    plot = tmp_path / "allan.png"
    line = one_line_error(capsys, "noise", log, "--plot", plot, "--datasheet", "N=60ug")
    assert line.startswith("tiltbench noise: error: --datasheet: item 'N=60ug': unit 'ug'")
    assert "accepted units: µg/√Hz" in line and not plot.exists()
    line = one_line_error(capsys, "noise", log, "--datasheet", "N=0ug/rtHz,B=20ug")
    assert "item 'N=0ug/rtHz'" in line and "positive finite" in line
    line = one_line_error(capsys, "noise", log, "--datasheet", tmp_path / "none.json")
    assert "--datasheet" in line and "none.json: datasheet file not found" in line
    line = one_line_error(capsys, "noise", tmp_path / "no_log.csv", "--datasheet", "Z=1ug")
    assert "--datasheet" in line and "unknown term 'Z'" in line  # before the log is looked at
