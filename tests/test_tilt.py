"""Calibration runs end to end: generate → files → calibrate recovers the truth."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import scipy.io

from bench.cli import main
from bench.sensors import AxisErrors, SensorErrorModel
from bench.tilt import CalibrationConfig, SweepProfile, ThetaDesign, generate_calibration
from calib.calibration.tilt_plane import calibrate
from calib.files.course import read_ensayo

TRUE = SensorErrorModel(AxisErrors(0.08, -0.03, 0.25), AxisErrors(-0.02, 0.01, 0.64))


def _z(cal, sensor):
    est, std = cal.params, np.sqrt(np.diag(cal.cov))
    truth = np.array([sensor.x.bias, sensor.x.scale, sensor.y.bias, sensor.y.scale])
    return (est - truth) / std


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
@pytest.mark.parametrize("mode", ["static", "sweep"])
def test_generate_then_calibrate_recovers_truth(mode, seed):
    rng = np.random.default_rng(seed)
    sensor = SensorErrorModel.from_pairs(rng.uniform(-0.2, 0.2, 2), rng.uniform(-0.05, 0.05, 2),
                                         (0.25, 0.64))
    cfg = CalibrationConfig(mode=mode, theta=ThetaDesign(count=2001),
                            sweep=SweepProfile(duration=20.0, rate=100.0), sensor=sensor)
    run = generate_calibration(cfg, seed)
    for method in ("ols", "wls"):
        cal = calibrate(run.ensayo(), (0.25, 0.64), method)
        assert np.all(np.abs(_z(cal, sensor)) < 4)


def test_positions_design_holds_samples_per_position():
    cfg = CalibrationConfig(theta=ThetaDesign(kind="positions", positions=8, per_position=25),
                            sensor=TRUE)
    run = generate_calibration(cfg, 11)
    assert run.tita.shape == (200,) and np.unique(run.tita).size == 8
    assert np.all(np.abs(_z(calibrate(run.ensayo(), (0.25, 0.64)), TRUE)) < 4)


def test_same_seed_same_bytes_and_no_truth_in_ensayo(tmp_path):
    args = ["generate", "calibration", "--seed", "5", "--count", "500"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 0
    assert main([*args, "--out", str(tmp_path / "b")]) == 0
    for name in ("ensayo.mat", "truth.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    assert main([*args[:3], "6", *args[4:], "--out", str(tmp_path / "c")]) == 0
    assert (tmp_path / "a/ensayo.mat").read_bytes() != (tmp_path / "c/ensayo.mat").read_bytes()
    mat = scipy.io.loadmat(tmp_path / "a" / "ensayo.mat")
    assert sorted(k for k in mat if not k.startswith("__")) == ["datos", "tita"]
    assert mat["tita"].shape == (500, 1) and mat["datos"].shape == (500, 2)
    truth = json.loads((tmp_path / "a" / "truth.json").read_text())
    assert truth["seed"] == 5 and "mujoco" in truth["versions"]
    assert truth["sensor"]["x"]["bias"] == 0.08


def test_sweep_file_carries_time(tmp_path):
    assert main(["generate", "calibration", "--mode", "sweep", "--duration", "5", "--out",
                 str(tmp_path)]) == 0
    e = read_ensayo(tmp_path / "ensayo.mat")
    assert e.t is not None and e.t.shape == e.tita.shape and np.all(np.diff(e.t) > 0)


def test_existing_output_is_not_overwritten_without_force(tmp_path, capsys):
    args = ["generate", "calibration", "--count", "100", "--out", str(tmp_path)]
    assert main(args) == 0
    before = (tmp_path / "ensayo.mat").read_bytes()
    assert main([*args, "--seed", "9"]) == 2
    assert "--force" in capsys.readouterr().err
    assert (tmp_path / "ensayo.mat").read_bytes() == before
    assert main([*args, "--seed", "9", "--force"]) == 0
    assert (tmp_path / "ensayo.mat").read_bytes() != before


def test_calibrate_cli_json(course_dir, capsys):
    assert main(["calibrate", str(course_dir / "ensayo.mat"), "--datos",
                 str(course_dir / "datos.txt"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "ols" and out["g"] == 9.8
    x = out["axes"]["x"]
    assert set(x) >= {"bias", "bias_std", "scale", "scale_std", "cov", "sigma2",
                      "sigma2_source", "chi2_dof", "n"}
    assert x["sigma2_source"] == "given" and x["n"] == 20001
    assert abs(x["scale"] - -0.0301) <= 5e-5


def test_calibrate_cli_estimates_sigma_without_noise_var(course_dir, capsys):
    assert main(["calibrate", str(course_dir / "ensayo.mat"), "--json", "--method", "wls"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["axes"]["y"]["sigma2_source"] == "estimated"
    assert out["axes"]["y"]["sigma2"] == pytest.approx(0.64, rel=0.05)


def test_console_script_runs(course_dir):
    res = subprocess.run([sys.executable, "-m", "bench.cli", "calibrate",
                          str(course_dir / "ensayo.mat"), "--noise-var", "0.25,0.64"],
                         capture_output=True, text=True, check=True)
    assert "scale" in res.stdout


def test_bad_input_clear_errors(tmp_path, capsys):
    bad = tmp_path / "deg.mat"
    tita = np.linspace(0, 360, 50)  # degrees; the readings follow the angle in degrees
    rad = np.deg2rad(tita)
    datos = np.column_stack([-9.8 * np.sin(rad), -9.8 * np.cos(rad)])
    scipy.io.savemat(bad, {"tita": tita[:, None], "datos": datos})
    assert main(["calibrate", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "deg.mat" in err and "tita" in err and "degrees" in err and "radians" in err
    nan = tmp_path / "nan.mat"
    d = np.zeros((50, 2))
    d[7, 1] = np.nan
    scipy.io.savemat(nan, {"tita": np.linspace(0, 6, 50)[:, None], "datos": d})
    assert main(["calibrate", str(nan)]) == 2
    assert "datos" in capsys.readouterr().err
    short = tmp_path / "shape.mat"
    scipy.io.savemat(short, {"tita": np.linspace(0, 6, 50)[:, None], "datos": np.zeros((49, 2))})
    assert main(["calibrate", str(short)]) == 2
    assert "samples" in capsys.readouterr().err
    assert main(["calibrate", str(tmp_path / "missing.mat")]) == 2
    assert main(["calibrate", str(short), "--noise-var", "0.25"]) == 2


def test_all_equal_theta_cli_names_parameter(tmp_path, capsys):
    assert main(["generate", "calibration", "--theta-list", "0.4,0.4,0.4,0.4", "--out",
                 str(tmp_path)]) == 0
    assert main(["calibrate", str(tmp_path / "ensayo.mat"), "--noise-var", "0.25,0.64"]) == 2
    assert "scale_x" in capsys.readouterr().err


def test_files_have_the_course_layout(course_dir, tmp_path):
    """Same MATLAB v5 layout as the course file: names, classes, shapes, version and endian."""
    assert main(["generate", "calibration", "--out", str(tmp_path)]) == 0
    ours, theirs = tmp_path / "ensayo.mat", course_dir / "ensayo.mat"
    assert scipy.io.whosmat(ours) == scipy.io.whosmat(theirs)
    assert ours.read_bytes()[124:128] == theirs.read_bytes()[124:128]  # version 0x0100, 'IM'
    assert ours.read_bytes()[:10] == b"MATLAB 5.0"


def test_generate_prints_a_readable_summary_or_one_json_object(tmp_path, capsys):
    args = ["generate", "calibration", "--count", "50", "--seed", "3"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 0
    text = capsys.readouterr().out
    assert text.startswith("generate calibration: 50 samples (static), seed 3")
    assert f"ensayo  {tmp_path / 'a' / 'ensayo.mat'}" in text
    with pytest.raises(json.JSONDecodeError):
        json.loads(text)
    assert main([*args, "--out", str(tmp_path / "b"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["n"] == 50 and info["files"]["truth"] == str(tmp_path / "b" / "truth.json")
