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


# ------------------------------------------------------------------ every axis, the gyro, units
HEADER = "t (s),ax (m/s^2),ay (m/s^2),az (m/s^2),gx (rad/s),gy (rad/s),gz (rad/s)"


def _imu_csv(path, n: int = 6000, rate: float = 50.0, seed: int = 5):
    """A still 3-axis accelerometer + 3-axis gyro log: white noise 0.02 m/s² and 0.002 rad/s
    per sample, gravity on -z."""
    rng = np.random.default_rng(seed)
    acc = 0.02 * rng.standard_normal((n, 3)) + [0.0, 0.0, -9.8]
    gyro = 0.002 * rng.standard_normal((n, 3))
    rows = np.column_stack([np.arange(n) / rate, acc, gyro])
    path.write_text(HEADER + "\n" + "".join(",".join(f"{v:.6f}" for v in r) + "\n"
                                            for r in rows))
    return path


def test_every_accelerometer_axis_and_the_gyro_with_datasheet_units(tmp_path, capsys):
    """x, y, z and the gyro's x, y, z, each with its kind, SI unit and datasheet unit
    (white noise: (m/s^2)/sqrt(Hz) and µg/√Hz; (rad/s)/sqrt(Hz) and °/√h — the factor
    checked by hand here: 1 µg = 9.80665e-6 m/s², 1 rad/√s = (180/π)·60 °/√h); the twin
    closure for every axis; the figure one panel per kind; the profile holds all six."""
    log = _imu_csv(tmp_path / "imu.csv")
    save, plot = tmp_path / "sensor.json", tmp_path / "allan.png"
    rc, out, err = run(capsys, "noise", log, "--json", "--twin", "--save", save, "--plot", plot)
    assert rc == 0, err
    doc = json.loads(out)
    assert set(doc["axes"]) == {"x", "y", "z", "gyro_x", "gyro_y", "gyro_z"}  # keys sorted
    for name, axis in doc["axes"].items():
        gyro = name.startswith("gyro")
        assert axis["kind"] == ("gyro" if gyro else "accelerometer")
        assert axis["unit"] == ("rad/s" if gyro else "m/s^2") and axis["fit_ok"]
        white = axis["terms"]["white_noise_density"]
        assert white["unit"] == ("(rad/s)/sqrt(Hz)" if gyro else "(m/s^2)/sqrt(Hz)")
        ds = white["datasheet"]
        factor = 180 / np.pi * 60 if gyro else 1 / 9.80665e-6
        assert ds["unit"] == ("°/√h" if gyro else "µg/√Hz")
        assert ds["value"] == pytest.approx(white["value"] * factor, rel=1e-12)
        sigma = 0.002 if gyro else 0.02
        lo, hi = white["interval"]
        assert lo / 1.2 < sigma / np.sqrt(50.0) < hi * 1.2  # per-sample σ = N·√fs
        bi = axis["terms"]["bias_instability"]["datasheet"]["unit"]
        assert bi == ("°/h" if gyro else "µg")
        closure = doc["twin"][name]
        assert closure["dof"] == len(axis["taus"]) and 0 <= closure["p"] <= 1
    assert sum(c["reject"] for c in doc["twin"].values()) <= 2  # α = 0.05 on six white axes
    assert doc["units"]["twin.*.p"] == "1" and doc["units"]["axes.*.taus"] == "s"
    profile = load_profile(save)
    assert profile.axes == ("x", "y", "z", "gyro_x", "gyro_y", "gyro_z")
    assert all(profile.fit_ok(a) for a in profile.axes)
    assert profile.fit_tau_range[0][0] == pytest.approx(0.02)
    assert plot.read_bytes()[:4] == b"\x89PNG"
    from bench.figures.allan import allan_figure
    from calib.noise.allan import NoiseCharacterization

    fig = allan_figure(NoiseCharacterization.from_dict(doc))
    assert len(fig.axes) == 2  # accelerometer, gyro
    import matplotlib.pyplot as plt

    plt.close(fig)
    # readable output: datasheet units beside SI, the closure per axis
    rc, out, _ = run(capsys, "noise", log, "--twin")
    assert rc == 0 and "µg/√Hz" in out and "°/√h" in out and "twin closure, axis gyro_z" in out


def _sine_log(path, n: int = 512, rate: float = 100.0):
    """White noise and a sine of period 16 samples: an Allan curve no model describes
    (tests/test_allan_rules.py)."""
    rng = np.random.default_rng(11)
    t = np.arange(n) / rate
    acc = np.column_stack([0.01 * rng.standard_normal(n) + 0.1 * np.sin(2 * np.pi * t / 0.16),
                           -9.8 + 0.01 * rng.standard_normal(n)])
    from scipy.io import savemat

    savemat(path, {"t": t[:, None], "Aerr": acc})
    return path


def test_a_failed_fit_is_not_saved_without_saying_so(tmp_path, capsys, course_dir):
    """``--save`` refuses in one line (nothing written, the figure neither); with
    ``--save-failed-fit`` the profile says ``fit_ok: false``; ``generate --sensor`` and
    ``gap --sensor`` refuse it, naming the field and the flag, unless ``--allow-failed-fit``."""
    log = _sine_log(tmp_path / "sine.mat")
    save, plot = tmp_path / "sensor.json", tmp_path / "allan.png"
    line = one_line_error(capsys, "noise", log, "--save", save, "--plot", plot)
    assert f"{save} not written" in line and "axis x" in line
    assert "--save-failed-fit" in line and "--allow-failed-fit" in line
    assert not save.exists() and not plot.exists()
    assert "--save" in one_line_error(capsys, "noise", log, "--save-failed-fit")
    rc, out, err = run(capsys, "noise", log, "--save", save, "--save-failed-fit")
    assert rc == 0, err
    assert "NO model of the rule describes this curve" in out and "fit_ok: false" in out
    doc = json.loads(save.read_text())
    assert doc["axes"]["x"]["fit_ok"] is False and doc["axes"]["y"]["fit_ok"] is True
    for argv in (["generate", "static", "--sensor", save, "--duration", "10", "--out",
                  tmp_path / "o"],
                 ["gap", course_dir / "ensayo.mat", "--noise-var", "0.25,0.64", "--sensor",
                  save, "--report", tmp_path / "r"]):
        line = one_line_error(capsys, *argv)
        assert str(save) in line and "field 'axes.x.fit_ok' is false" in line
        assert "--allow-failed-fit" in line
    assert not (tmp_path / "o").exists() and not (tmp_path / "r").exists()
    rc, _, err = run(capsys, "generate", "static", "--sensor", save, "--duration", "10",
                     "--out", tmp_path / "o", "--allow-failed-fit")
    assert rc == 0, err
