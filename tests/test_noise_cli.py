"""``tiltbench noise`` and ``tiltbench generate static|calibration --sensor`` from the command
line (in-process, :mod:`tests.cli`): outputs, files, refusals with one-line errors and nothing
written."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.io import loadmat

from calib.noise.sensor_profile import NoiseTerm, SensorProfile, load_profile, save_profile
from tests.cli import one_line_error, run


def _profile(tmp_path, **kw):
    t = lambda v: NoiseTerm(v, (0.9 * v, 1.1 * v), (0.01, 10.0))  # noqa: E731
    base = dict(sample_rate=50.0, white_noise_density=(t(2e-3), t(3e-3)),
                bias_instability=(t(1e-3), None), rate_random_walk=(None, t(4e-4)),
                quantization_step=(0.005, None))
    base.update(kw)
    return save_profile(tmp_path / "sensor.json", SensorProfile(**base))


@pytest.fixture(scope="module")
def static_log(tmp_path_factory):
    """A 120 s static log at 50 Hz of a twin (generate static --sensor)."""
    tmp = tmp_path_factory.mktemp("noise")
    prof = _profile(tmp)
    from bench.cli import main

    assert main(["generate", "static", "--sensor", str(prof), "--duration", "120",
                 "--theta", "0.4", "--seed", "3", "--out", str(tmp / "s")]) == 0
    return tmp / "s" / "static.mat", prof


def test_generate_static_writes_a_readable_seeded_log(static_log, tmp_path, capsys):
    path, prof = static_log
    mat = loadmat(path)
    assert mat["Aerr"].shape == (6000, 2) and mat["t"].shape == (6000, 1)
    truth = json.loads((path.parent / "truth.json").read_text())
    assert truth["kind"] == "static" and truth["theta"] == 0.4 and truth["rate"] == 50.0
    assert truth["sensor_profile"]["bias_instability"] == [1e-3, None]
    terms = {t["name"]: t for t in truth["sensor"]["x"]["terms"]}
    assert terms["bias_instability"] == {"name": "bias_instability", "b": 1e-3}
    assert truth["units"]["sensor.*.terms.b"] == "m/s²" and truth["units"]["theta"] == "rad"
    rc, out, _ = run(capsys, "generate", "static", "--sensor", prof, "--duration", "120",
                     "--theta", "0.4", "--seed", "3", "--out", tmp_path / "again", "--json")
    assert rc == 0 and json.loads(out)["units"]["rate"] == "Hz"
    assert (tmp_path / "again" / "static.mat").read_bytes() == path.read_bytes()


def test_noise_json_profile_and_plot(static_log, tmp_path, capsys):
    path, _ = static_log
    save, plot = tmp_path / "twin.json", tmp_path / "allan.png"
    rc, out, err = run(capsys, "noise", path, "--json", "--save", save, "--plot", plot,
                       "--level", "0.95")
    assert rc == 0, err
    doc = json.loads(out)
    assert doc["sample_rate"] == 50.0 and doc["n"] == 6000 and doc["level"] == 0.95
    assert doc["units"]["terms.white_noise_density.value"] == "(m/s^2)/sqrt(Hz)"
    assert doc["files"] == {"profile": str(save), "plot": str(plot)}
    x = doc["axes"]["x"]
    lo, hi = x["terms"]["white_noise_density"]["interval"]
    assert lo < 2e-3 * np.sqrt(1 + 0.005 ** 2 / 12 / 50 / 2e-3 ** 2) < hi
    assert x["quantization_step"] == pytest.approx(0.005)
    assert doc["static_check"]["max_shift"] < doc["static_check"]["shift"]
    prof = load_profile(save)
    assert prof.sample_rate == 50.0 and prof.source["name"] == "static.mat"
    assert prof.white_noise_density[1].value == doc["axes"]["y"]["terms"][
        "white_noise_density"]["value"]
    assert plot.read_bytes()[:4] == b"\x89PNG"
    # readable output: the terms with units, the static check, the files
    rc, out, _ = run(capsys, "noise", path)
    assert rc == 0 and "white_noise_density" in out and "static check" in out
    # existing outputs: refused before any work, files untouched
    before = save.read_bytes()
    line = one_line_error(capsys, "noise", path, "--save", save)
    assert str(save) in line and "--force" in line
    assert save.read_bytes() == before


def test_noise_takes_a_calibration(static_log, course_dir, tmp_path, capsys):
    path, _ = static_log
    cal = tmp_path / "cal.json"
    rc, _, err = run(capsys, "calibrate", course_dir / "ensayo.mat", "--save", cal)
    assert rc == 0, err
    rc, _, err = run(capsys, "noise", path, "--calibration", cal, "--save", tmp_path / "p.json")
    assert rc == 0, err
    entry = load_profile(tmp_path / "p.json").calibration
    assert entry["param_names"] == ["bias_x", "scale_x", "bias_y", "scale_y"]
    assert np.asarray(entry["cov"]).shape == (4, 4)
    assert entry["source"]["name"] == "cal.json" and len(entry["source"]["sha256"]) == 64
    from calib.calibration.calfile import load_calibration

    assert entry["params"] == load_calibration(cal).params.tolist()


def test_generate_calibration_with_a_sensor(tmp_path, capsys):
    prof = _profile(tmp_path, calibration={"bias": [0.07, -0.02], "scale": [-0.03, 0.01]})
    rc, _, err = run(capsys, "generate", "calibration", "--sensor", prof, "--positions", "4",
                     "--per-position", "50", "--out", tmp_path / "c")
    assert rc == 0, err
    truth = json.loads((tmp_path / "c" / "truth.json").read_text())
    assert truth["sensor"]["x"]["bias"] == 0.07 and truth["sensor"]["y"]["scale"] == 0.01
    assert truth["sensor"]["x"]["noise_var"] == pytest.approx((2e-3 * np.sqrt(50.0)) ** 2)
    assert truth["sensor_profile"]["run_rate"] == 50.0
    # a calibration run holds several poses: `noise` refuses it, writing nothing
    line = one_line_error(capsys, "noise", tmp_path / "c" / "ensayo.mat", "--rate", "50",
                          "--save", tmp_path / "no.json")
    assert "θ varies" in line and "ensayo.mat" in line
    assert not (tmp_path / "no.json").exists()


def test_refusals(course_dir, static_log, tmp_path, capsys):
    path, _ = static_log
    # the course's vehicle run moves: not a static log
    line = one_line_error(capsys, "noise", course_dir / "acel.mat", "--plot", tmp_path / "a.png")
    assert "not a static log" in line and "acel.mat" in line
    assert not (tmp_path / "a.png").exists()
    assert "--alpha" in one_line_error(capsys, "noise", path, "--alpha", "0.7")
    assert "--level" in one_line_error(capsys, "noise", path, "--level", "1.5")
    line = one_line_error(capsys, "noise", path, "--tau-range", "5,1")
    assert "--tau-range" in line
    line = one_line_error(capsys, "noise", path, "--tau-range", "1,2")
    assert "octave" in line
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "something else"}')
    line = one_line_error(capsys, "generate", "static", "--sensor", bad, "--out", tmp_path / "o")
    assert "bad.json" in line and "not a sensor profile" in line
    assert not (tmp_path / "o").exists()
    line = one_line_error(capsys, "generate", "static", "--duration", "-1", "--out",
                          tmp_path / "o")
    assert "--duration" in line
