"""The twin loop (issue 19, item 8; docs/real-data.md "The twin loop"), end to end from the
command line in-process (tests/cli.py), in a temporary directory:

    real log → import → noise (a static stretch) + calibrate --save cal.json
             → noise --calibration cal.json --save sensor.json
             → generate calibration --sensor sensor.json --theta-from <the import's ensayo.mat>
             → gap of the real run (and, for the real log, of its twin) → design for that sensor

Which log runs the loop is one constant per case (:data:`REAL` — a shipped real log — and
:data:`MULTIPOSE`), so a better log is one line to change. Each step's output is checked
(files exist, JSON fields sane, units present) and its numbers against a reference computed
without the code under test where one exists:

* the real log (``data/real/yei-3space-z-flip.csv``, a YEI 3-Space sensor flat, turned over,
  flat again, with a gyro): per-pose means, stds, the time column and the 1/4096 g step of
  ``tests/reference/real_data.py`` (plain csv + numpy) and its README. Its held poses are 180°
  apart only, so with θ from the poses the tilt plane's x axis never sees gravity change and
  ``calibrate`` refuses naming ``scale_x``; with ``--theta-source gyro`` (θ(t) of every sample
  integrated from the gyro about the tilt axis, :mod:`calib.logs.gyro_angle`) the turns sweep θ and
  both axes are identifiable. The run is then a timed sweep turned by hand: ``gap`` of it
  (``--sensor``: the profile's terms) finds what the twin lacks — whatever it finds, the real
  residuals are far beyond the sensor's noise (taps, the hand's accelerations), while ``gap``
  of the twin (the same θ, the profile's noise and quantization, the fitted calibration) finds
  nothing it was not simulated with.
* the multi-pose stand-in (``tests/logfixtures.py``: five held poses, white noise 0.02 m/s²
  per sample at 100 Hz, no bias or scale error): every step runs; references are its known
  truth.

Tolerances: estimates are compared with a reference within 4 of their stated std (a normal
estimate leaves that band with probability 6e-5; seeds are fixed, so the outcome is
deterministic); equal computations to 1e-9.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from calib.calibration.ls import fit_axis
from calib.conventions import STANDARD_GRAVITY
from calib.logs.gyro_angle import CLOSURE_BOUND_DEG
from tests import logfixtures as fx
from tests.cli import one_line_error, run
from tests.reference import real_data as ref

G = 9.8  # m/s²: the commands' default local g (makes A_r; the unit g is 9.80665 m/s²)
K = 4.0  # band, in stated std, for an estimate against its reference


@dataclass(frozen=True)
class LoopLog:
    """One log through the loop: where it is, how it is read, the poses' angles in order of
    occurrence (deg) and where θ comes from, the data rows of one static stretch
    ``[start, stop)`` for ``noise``, and whether ``gap`` takes the noise and the walk from the
    sensor profile (``--noise-var`` N²·fs, ``--sensor``) and runs on the twin too."""

    path: Path
    read: tuple[str, ...]
    poses: tuple[str, ...]
    still: tuple[int, int]
    gap_from_profile: bool


REAL = LoopLog(
    path=ref.REAL_DIR / "yei-3space-z-flip.csv",
    read=("--units", "g", "--gyro-unit", "rad/s", "--axes", "x,-z"),
    # five holds of at least 0.5 s: flat, flat, turned over, flat, flat; θ of
    # every sample from the gyro about the tilt axis, anchored to them
    poses=("--min-hold", "0.5", "--poses", "0,0,180,0,0", "--angle-unit", "deg",
           "--theta-source", "gyro"),
    # the reference's z_down pose (data/real/README.md): the quietest hold, resting on the
    # table; the longest (rows 2158–2592) is held by hand, its x noise 4× larger
    still=(1090, 1250),
    gap_from_profile=True,
)
MULTIPOSE = LoopLog(
    path=Path("log.csv"),  # written by the fixture below, inside the test's tmp dir
    read=(),
    poses=("--poses", ",".join(f"{a:g}" for a in fx.ANGLES_DEG), "--angle-unit", "deg"),
    still=fx.simulated()[4][0],
    gap_from_profile=False,
)


def _ok(capsys, *argv) -> tuple[str, str]:
    rc, out, err = run(capsys, *argv)
    assert rc == 0, err
    return out, err


def _cut(src: Path, dst: Path, rows: tuple[int, int]) -> Path:
    """The header line and data rows ``[start, stop)`` of a one-line-header CSV, as bytes —
    what a user does with ``head``/``sed`` to keep a static stretch."""
    lines = src.read_bytes().splitlines(keepends=True)
    dst.write_bytes(b"".join([lines[0], *lines[1 + rows[0]:1 + rows[1]]]))
    return dst


def _units_present(doc: dict) -> None:
    assert isinstance(doc.get("units"), dict) and doc["units"], "no units map"


def loop(capsys, log: LoopLog, d: Path) -> dict:
    """Run the loop in ``d``; return every step's parsed output."""
    out = {}
    # 1. import: the course files plus the provenance
    text, _ = _ok(capsys, "import", log.path, *log.read, *log.poses, "--out", d / "imp",
                  "--json")
    out["import"] = json.loads(text)
    _units_present(out["import"])
    ensayo = d / "imp" / "ensayo.mat"
    assert ensayo.exists() and (d / "imp" / "provenance.json").exists()
    # 2. noise on a static stretch (the profile gets no calibration yet)
    still = _cut(log.path, d / "still.csv", log.still)
    text, _ = _ok(capsys, "noise", still, *log.read, "--json")
    out["noise"] = json.loads(text)
    _units_present(out["noise"])
    # 3. calibrate
    text, _ = _ok(capsys, "calibrate", ensayo, "--save", d / "cal.json", "--plot",
                  d / "cal.png", "--json")
    out["calibrate_json"] = json.loads(text)
    _units_present(out["calibrate_json"])
    out["calibrate"] = json.loads((d / "cal.json").read_text())
    assert (d / "cal.png").exists()
    # 4. the sensor profile
    _ok(capsys, "noise", still, *log.read, "--calibration", d / "cal.json", "--save",
        d / "sensor.json", "--plot", d / "allan.png")
    out["sensor"] = json.loads((d / "sensor.json").read_text())
    assert (d / "allan.png").exists()
    # 5. its twin: the same θ, sample for sample
    _ok(capsys, "generate", "calibration", "--sensor", d / "sensor.json", "--theta-from",
        ensayo, "--seed", "19", "--out", d / "twin")
    out["twin_truth"] = json.loads((d / "twin" / "truth.json").read_text())
    out["twin"] = scipy.io.loadmat(d / "twin" / "ensayo.mat")
    fs = out["sensor"]["sample_rate"]
    nv = [out["sensor"]["axes"][a]["white_noise_density"]["value"] ** 2 * fs for a in "xy"]
    # 6. gap of the real run (gap simulates its own twin with the fitted parameters); with
    # the profile: its per-sample noise N²·fs and (--sensor) its walk, and gap of the twin
    if log.gap_from_profile:
        noise = [f"--noise-var={float(nv[0])!r},{float(nv[1])!r}"]
        text, _ = _ok(capsys, "gap", ensayo, *noise, "--sensor", d / "sensor.json",
                      "--report", d / "gap", "--json")
        out["gap"] = json.loads(text)
        text, _ = _ok(capsys, "gap", d / "twin" / "ensayo.mat", *noise, "--json")
        out["gap_twin"] = json.loads(text)
        _units_present(out["gap_twin"])
    else:
        text, _ = _ok(capsys, "gap", ensayo, "--report", d / "gap", "--json")
        out["gap"] = json.loads(text)
    _units_present(out["gap"])
    assert (d / "gap" / "gap.md").exists() and (d / "gap" / "gap.png").exists()
    # 7. design for that sensor: its per-sample noise variance (N²·fs) on each axis
    n = out["twin"]["datos"].shape[0]
    text, _ = _ok(capsys, "design", f"--noise-var={float(nv[0])!r},{float(nv[1])!r}", "--designs",
                  "held,uniform", "--count", str(n), "--runs", "0", "--json")
    out["design"] = json.loads(text)
    _units_present(out["design"])
    return out


def _check_common(out: dict, log: LoopLog, fs_ref: float, sigma_ref: tuple[float, float]):
    """Checks every log gets: the noise result and the profile against the static stretch's
    independent std and rate; the twin's θ is the import's; design ran on the profile."""
    noise, sensor = out["noise"], out["sensor"]
    assert sensor["format"] == "tiltbench-sensor" and sensor["units"]["white_noise_density"]
    assert abs(sensor["sample_rate"] / fs_ref - 1) < 1e-6
    for i in range(2):
        w = sensor["axes"]["xy"[i]]["white_noise_density"]
        lo, hi = w["interval"]
        assert lo <= w["value"] <= hi and w["level"] == pytest.approx(0.683)
        # white noise: per-sample std = N·√fs; the interval's half-width as its std
        std = 0.5 * (hi - lo) * math.sqrt(fs_ref)
        assert abs(w["value"] * math.sqrt(fs_ref) - sigma_ref[i]) <= K * std, (i, w)
    assert noise["axes"]["x"]["adev"] and len(noise["axes"]["x"]["adev_ci"]) == len(
        noise["axes"]["x"]["adev"])
    mat = scipy.io.loadmat(Path(out["import"]["files"][0]))
    assert np.array_equal(out["twin"]["tita"], mat["tita"])
    assert out["twin_truth"]["sensor_profile"]["source"] == "sensor.json"
    design = out["design"]
    fs = sensor["sample_rate"]
    nv = [sensor["axes"][a]["white_noise_density"]["value"] ** 2 * fs for a in "xy"]
    assert design["settings"]["noise_var"] == pytest.approx(nv, rel=1e-12)
    n = out["twin"]["datos"].shape[0]
    uniform = next(e for e in design["experiments"] if e["design"] == "uniform")
    # uniform θ over a full turn, OLS of [1, A_r]: std(bias) = σ/√n, std(scale) = σ/(g·√(n/2))
    for i, axis in enumerate("xy"):
        got = uniform["nominal_std"][axis]
        assert uniform["n"] == n
        assert got["bias"] == pytest.approx(math.sqrt(nv[i] / n), rel=0.02)
        assert got["scale"] == pytest.approx(math.sqrt(nv[i] / (n / 2)) / G, rel=0.02)


@pytest.mark.slow  # ~15 s: two gap analyses of 2715 samples, one report
def test_twin_loop_on_the_shipped_real_log(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    log = REAL
    # θ from the poses alone (held samples at 0 and 180°): x never sees gravity change
    _ok(capsys, "import", log.path, *log.read, *log.poses[:-2], "--out", tmp_path / "held")
    line = one_line_error(capsys, "calibrate", tmp_path / "held" / "ensayo.mat")
    assert "cannot identify scale_x" in line
    out = loop(capsys, log, tmp_path)
    prov = out["import"]["provenance"]
    assert prov["source"]["name"] == log.path.name
    assert prov["units"]["acc_to_m_s2"] == STANDARD_GRAVITY
    assert len(prov["poses"]["detection"]["segments"]) == 5
    # every sample kept, at the log's own times (independent reference: plain csv + numpy)
    spec = ref.SPECS[log.path.name]
    _, rows = ref.read_rows(log.path)
    t_all = np.array(rows)[:, spec.time_column] * spec.time_to_s
    real = scipy.io.loadmat(Path(out["import"]["files"][0]))
    assert prov["samples"]["kept"] == prov["samples"]["read"] == len(rows)
    assert np.allclose(real["t"].ravel(), t_all, rtol=0, atol=1e-12)
    gyro = prov["theta_from_gyro"]
    assert np.all(np.abs(gyro["closure_deg"]) < CLOSURE_BOUND_DEG)
    assert "linear in time" in gyro["correction"]
    # the static stretch: rate and std against the reference
    t = t_all[log.still[0]:log.still[1]]
    fs_ref = (t.size - 1) / (t[-1] - t[0])
    pose = ref.pose_means(log.path, g_unit=G)["poses"]["z_down"]
    assert (pose["start"], pose["stop"]) == log.still
    _check_common(out, log, fs_ref, (pose["std"]["x"], pose["std"]["z"]))
    sensor = out["sensor"]
    # a 1.45 s stretch resolves the white noise only; the rest are upper bounds, not numbers
    axes = sensor["axes"]
    assert all(axes[a][k] is None for a in "xy" for k in ("bias_instability", "rate_random_walk"))
    assert all(axes[a]["unresolved_upper_bounds"]["bias_instability"] > 0 for a in "xy")
    # the YEI's "Raw" accelerometer steps by 1/4096 g (data/real/README.md)
    for a in "xy":
        assert abs(axes[a]["quantization_step"] - STANDARD_GRAVITY / 4096) < 1e-9
    # calibrate: the turns make both axes identifiable — the design [1, A_r] of each axis
    # (columns scaled to unit length) is well conditioned; from the holds alone x's is singular
    cal = out["calibrate"]
    assert sensor["calibration"]["params"] == pytest.approx(cal["params"], rel=1e-12)
    th = real["tita"].ravel()
    for a_r in (-G * np.sin(th), -G * np.cos(th)):
        h = np.c_[np.ones_like(th), a_r]
        assert np.linalg.cond(h / np.linalg.norm(h, axis=0)) < 10
    # the turns are made by hand: the sweep's readings carry the hand's accelerations, which
    # the model lacks. The imported run keeps its pose labels, so calibrate tests the fit
    # against the scatter within the holds and says the model misses something on both axes
    # (its intervals are then those of the sensor's noise, the pure error, not of the hand;
    # the held poses' agreement with the six-position reference is in test_real_readers)
    params = dict(zip(cal["param_names"], cal["params"], strict=True))
    lof = out["calibrate_json"]["lack_of_fit"]
    assert all(lof[a]["p_value"] < 1e-6 for a in "xy"), lof
    # the twin holds the calibration: its fit lands on it within its own std
    twin = out["twin"]
    for i, axis in enumerate("xy"):
        ft = fit_axis(twin["tita"].ravel(), twin["datos"][:, i], axis, g=G)
        assert abs(ft.params[0] - params[f"bias_{axis}"]) <= K * ft.std[0], axis
        assert abs(ft.params[1] - params[f"scale_{axis}"]) <= K * ft.std[1], axis
    # gap: the real run took the profile's terms; its residuals are far beyond the sensor's
    # noise (the hand's motion and taps), the twin's are not, and the twin shows nothing it
    # was not simulated with (its quantization at most)
    gap, gap_twin = out["gap"], out["gap_twin"]
    assert gap["analysis"]["criterion"]["profile"]["terms_from_profile"]
    assert gap["verdict"] in ("nothing_detected", "explained", "unexplained")
    assert gap_twin["verdict"] in ("nothing_detected", "explained")
    assert gap_twin["unexplained"] == [] and gap_twin["consistent_after"]
    assert {e["name"] for e in gap_twin["effects"]} <= {"quantization"}
    for axis in "xy":
        before, twin_before = gap["gap_before"][axis], gap_twin["gap_before"][axis]
        assert twin_before["chi2_dof"] < 1.5
        assert before["chi2_dof"] > 100 * twin_before["chi2_dof"], axis


@pytest.mark.slow  # ~10 s: gap's search and report
def test_twin_loop_on_a_multipose_log(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    fx.write_csv(tmp_path / "log.csv")
    log = MULTIPOSE
    out = loop(capsys, log, tmp_path)
    _check_common(out, log, 100.0, (fx.NOISE, fx.NOISE))
    cal = out["calibrate"]  # cal.json
    _units_present(cal)
    assert cal["format"] == "tiltbench-calibration" and cal["source"]["name"] == "ensayo.mat"
    params = dict(zip(cal["param_names"], cal["params"], strict=True))
    std = dict(zip(cal["param_names"], cal["std"], strict=True))
    for name in ("bias_x", "scale_x", "bias_y", "scale_y"):  # the log has no bias or scale
        assert abs(params[name]) <= K * std[name], name
    sensor = out["sensor"]
    assert sensor["calibration"]["params"] == pytest.approx(cal["params"], rel=1e-12)
    truth = out["twin_truth"]["sensor"]
    assert truth["x"]["bias"] == pytest.approx(params["bias_x"], rel=1e-12)
    assert truth["y"]["scale"] == pytest.approx(params["scale_y"], rel=1e-12)
    gap = out["gap"]
    _units_present(gap)
    assert gap["verdict"] == "nothing_detected" and gap["effects"] == []
    assert (tmp_path / "gap" / "gap.md").exists() and (tmp_path / "gap" / "gap.png").exists()


def test_theta_from_copies_the_schedule_and_excludes_theta_list(capsys, tmp_path):
    """``generate calibration --theta-from E.mat``: the twin's tita is E's, sample for sample;
    given with --theta-list it is one line naming both."""
    th = np.repeat([0.0, 1.0, 2.5, 4.0], 30)
    acc = np.c_[-G * np.sin(th), -G * np.cos(th)]
    scipy.io.savemat(tmp_path / "e.mat", {"tita": th.reshape(-1, 1), "datos": acc})
    _ok(capsys, "generate", "calibration", "--theta-from", tmp_path / "e.mat", "--seed", "1",
        "--out", tmp_path / "t")
    got = scipy.io.loadmat(tmp_path / "t" / "ensayo.mat")["tita"].ravel()
    assert np.array_equal(got, th)
    line = one_line_error(capsys, "generate", "calibration", "--theta-from", tmp_path / "e.mat",
                          "--theta-list", "0,1,2", "--out", tmp_path / "u")
    assert "--theta-list" in line and "--theta-from" in line and not (tmp_path / "u").exists()
