"""The GNSS receiver on the MuJoCo vehicle (issue 13, part 1): fix times (rate, latency,
outages), noise statistics, agreement with MuJoCo's state, ``gps.mat`` and ``truth.json``, the
seed, and outputs unchanged without the ``--gps`` options."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from scipy import stats

from bench.cli import main
from bench.gnss import (
    GNSS_STREAM,
    GPS_UNITS,
    GnssFixes,
    Receiver,
    fix_epochs,
    fixes_for_seed,
    gnss_rng,
    simulate_fixes,
)
from bench.vehicle import VehicleConfig, simulate_vehicle
from calib.units import missing_units
from tests.cli import unwrap

SEED = 20260513


@pytest.fixture(scope="module")
def truth():
    """MuJoCo's course run (60 s at 100 Hz)."""
    return simulate_vehicle(VehicleConfig())


def _synthetic(n: int, rate: float):
    """A truth-shaped trajectory of ``n`` samples at ``rate`` Hz (for the noise statistics)."""
    t = np.arange(n) / rate
    pos = np.column_stack([np.sin(t), 0.5 * t])
    vel = np.column_stack([np.cos(t), np.full(n, 0.5)])
    return t, pos, vel


def _run(*argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in argv])
        except SystemExit as exc:
            rc = exc.code
    return rc, out.getvalue(), err.getvalue()


def _mat(path: Path) -> dict:
    return {k: v for k, v in scipy.io.loadmat(path).items() if not k.startswith("__")}


# --- the receiver model --------------------------------------------------------------------

def test_receiver_defaults_and_validation():
    r = Receiver()
    assert (r.rate_hz, r.pos_sigma_m, r.vel_sigma_mps, r.latency_s, r.outages) == (
        1.0, 3.0, None, 0.0, ())
    assert Receiver(outages=[[1, 2]]).outages == ((1.0, 2.0),)
    for bad in ({"rate_hz": 0}, {"rate_hz": float("inf")}, {"pos_sigma_m": -1},
                {"pos_sigma_m": float("nan")}, {"vel_sigma_mps": -0.1}, {"latency_s": -0.01},
                {"outages": [(5, 1)]}, {"outages": [(0, float("inf"))]}, {"outages": [(1,)]}):
        with pytest.raises(ValueError, match="Receiver"):
            Receiver(**bad)
    with pytest.raises(AttributeError):
        r.rate_hz = 2.0  # frozen


def test_fix_times_at_the_rate(truth):
    fx = simulate_fixes(Receiver(), truth.t, truth.pos, truth.vel, gnss_rng(SEED))
    np.testing.assert_array_equal(fx.t_gps, np.arange(60.0))  # 0 … 59 s within 0 … 59.99 s
    fx10 = simulate_fixes(Receiver(rate_hz=10), truth.t, truth.pos, truth.vel, gnss_rng(SEED))
    np.testing.assert_allclose(fx10.t_gps, np.arange(600) / 10, rtol=0, atol=1e-12)
    assert fx.vel is None and fx10.vel is None


def test_latency_reports_the_earlier_state(truth):
    r = Receiver(pos_sigma_m=0.0, vel_sigma_mps=0.0, latency_s=0.25)
    fx = simulate_fixes(r, truth.t, truth.pos, truth.vel, gnss_rng(SEED))
    np.testing.assert_array_equal(fx.t_gps, np.arange(1.0, 60.0))  # t = 0 has no past state
    idx = np.rint((fx.t_gps - 0.25) * 100).astype(int)
    np.testing.assert_array_equal(fx.pos, truth.pos[idx])
    np.testing.assert_array_equal(fx.vel, truth.vel[idx])
    # not the state at t: the vehicle moves >= 1.8 m/s, so 0.25 s later it is >= 0.45 m away
    assert np.all(np.linalg.norm(fx.pos - truth.pos[idx + 25], axis=1) > 0.4)


def test_outages_remove_closed_intervals_and_keep_the_other_fixes(truth):
    base = Receiver(vel_sigma_mps=0.1)
    cut = Receiver(vel_sigma_mps=0.1, outages=((10.0, 20.0), (40.5, 41.5), (55.0, 100.0)))
    a = simulate_fixes(base, truth.t, truth.pos, truth.vel, gnss_rng(SEED))
    b = simulate_fixes(cut, truth.t, truth.pos, truth.vel, gnss_rng(SEED))
    expect = [t for t in range(60) if not (10 <= t <= 20 or t == 41 or t >= 55)]
    np.testing.assert_array_equal(b.t_gps, expect)
    sel = np.isin(a.t_gps, b.t_gps)
    np.testing.assert_array_equal(b.pos, a.pos[sel])  # same noise at the surviving epochs
    np.testing.assert_array_equal(b.vel, a.vel[sel])


def test_fixes_off_the_imu_grid_or_none_left_are_refused(truth):
    for r in (Receiver(rate_hz=3), Receiver(latency_s=0.005), Receiver(rate_hz=200)):
        with pytest.raises(ValueError, match="grid"):
            fix_epochs(r, truth.t)
    for r in (Receiver(latency_s=61), Receiver(outages=((0, 60),))):
        with pytest.raises(ValueError, match="no fix"):
            fix_epochs(r, truth.t)


def test_positions_match_the_mujoco_truth(truth):
    exact = simulate_fixes(Receiver(pos_sigma_m=0.0, vel_sigma_mps=0.0), truth.t, truth.pos,
                           truth.vel, gnss_rng(SEED))
    idx = np.arange(60) * 100
    np.testing.assert_array_equal(exact.pos, truth.pos[idx])
    np.testing.assert_array_equal(exact.vel, truth.vel[idx])
    noisy = fixes_for_seed(Receiver(vel_sigma_mps=0.1), truth, SEED)
    # 240 standardized errors: every one within 5σ (P(any beyond) ≈ 1.4e-4); their sum of
    # squares is χ²(240) — inside its 0.1 % two-sided band.
    z = np.concatenate([((noisy.pos - truth.pos[idx]) / 3.0).ravel(),
                        ((noisy.vel - truth.vel[idx]) / 0.1).ravel()])
    assert np.all(np.abs(z) < 5)
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], z.size)
    assert lo < np.sum(z**2) < hi


@pytest.mark.parametrize("which", ["pos", "vel"])
def test_noise_std_within_chi2_bounds_over_a_long_run(which):
    """R = 20000 fixes, 2 axes: Σe²/σ² ~ χ²(2R) per the model (white, N(0, σ²) per axis);
    the band is its 0.1 % two-sided quantiles, so a correct σ fails 1 in 1000 seeds, and a σ
    off by 2 % falls outside it (the band is ±2.3 % in σ² at this size). Per axis too, with
    the band of χ²(R)."""
    t, pos, vel = _synthetic(20000, 10.0)
    r = Receiver(rate_hz=10, pos_sigma_m=3.0, vel_sigma_mps=0.1)
    fx = simulate_fixes(r, t, pos, vel, gnss_rng(SEED))
    e, sigma = (fx.pos - pos, 3.0) if which == "pos" else (fx.vel - vel, 0.1)
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], e.size)
    assert lo < np.sum((e / sigma) ** 2) < hi
    lo1, hi1 = stats.chi2.ppf([0.0005, 0.9995], e.shape[0])
    for k in range(2):
        assert lo1 < np.sum((e[:, k] / sigma) ** 2) < hi1
    assert abs(np.corrcoef(e[:, 0], e[:, 1])[0, 1]) < 4 / np.sqrt(e.shape[0])  # axes independent
    assert abs(np.mean(e) / (sigma / np.sqrt(e.size))) < 4  # zero mean


def test_the_noise_stream_is_the_seeds_own_child():
    ss = np.random.SeedSequence(SEED)
    direct = np.random.default_rng(np.random.SeedSequence(SEED, spawn_key=(GNSS_STREAM,)))
    assert gnss_rng(SEED).standard_normal(4).tolist() == direct.standard_normal(4).tolist()
    assert GNSS_STREAM not in range(3)  # the course's children 0–2 are not reused
    for child in ss.spawn(3):
        assert child.spawn_key != (GNSS_STREAM,)


def test_fixes_are_read_only():
    t, pos, vel = _synthetic(100, 10.0)
    fx = simulate_fixes(Receiver(rate_hz=10), t, pos, vel, gnss_rng(0))
    assert isinstance(fx, GnssFixes) and fx.n == 100
    with pytest.raises(ValueError):
        fx.pos[0, 0] = 1.0


# --- the command line and the files --------------------------------------------------------

def test_generate_vehicle_writes_gps_mat_and_the_receiver(tmp_path, truth):
    out = tmp_path / "v"
    rc, stdout, err = _run("generate", "vehicle", "--out", out, "--seed", 3, "--json",
                           "--gps-vel-sigma", "0.1", "--gps-latency", "0.2",
                           "--gps-outage", "10,20", "--gps-outage", "30,31")
    assert rc == 0, err
    summary = json.loads(stdout)
    mat = _mat(out / "gps.mat")
    assert set(mat) == {"t_gps", "pos", "vel"}
    m = summary["n_gps"]
    assert mat["t_gps"].shape == (m, 1) and mat["pos"].shape == (m, 2)
    assert mat["vel"].shape == (m, 2)
    assert all(v.dtype == np.float64 for v in mat.values())
    assert (out / "gps.mat").read_bytes().startswith(b"MATLAB 5.0 MAT-file, written by tiltbench")
    expect = [t for t in range(1, 60) if not (10 <= t <= 20 or 30 <= t <= 31)]
    np.testing.assert_array_equal(mat["t_gps"].ravel(), expect)
    # the file's fixes are MuJoCo's state 0.2 s earlier plus noise from the seed's GNSS stream
    r = Receiver(vel_sigma_mps=0.1, latency_s=0.2, outages=((10, 20), (30, 31)))
    fx = fixes_for_seed(r, truth, 3)
    np.testing.assert_array_equal(mat["pos"], fx.pos)
    np.testing.assert_array_equal(mat["vel"], fx.vel)

    tj = json.loads((out / "truth.json").read_text())
    assert tj["gps"]["rate_hz"] == 1.0 and tj["gps"]["pos_sigma_m"] == 3.0
    assert tj["gps"]["vel_sigma_mps"] == 0.1 and tj["gps"]["latency_s"] == 0.2
    assert tj["gps"]["outages"] == [[10.0, 20.0], [30.0, 31.0]]
    assert tj["gps"]["n_fixes"] == m
    for key, unit in GPS_UNITS.items():
        assert tj["units"][key] == unit
    assert missing_units(tj) == [] and missing_units(summary) == []


def test_velocity_fixes_only_when_asked(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert _run("generate", "vehicle", "--out", a, "--gps")[0] == 0
    assert _run("generate", "vehicle", "--out", b, "--gps-vel-sigma", "0.1")[0] == 0
    ma, mb = _mat(a / "gps.mat"), _mat(b / "gps.mat")
    assert set(ma) == {"t_gps", "pos"} and set(mb) == {"t_gps", "pos", "vel"}
    np.testing.assert_array_equal(ma["pos"], mb["pos"])  # velocities drawn after positions
    assert json.loads((a / "truth.json").read_text())["gps"]["vel_sigma_mps"] is None


def test_course_with_gps_at_50_hz(tmp_path):
    out = tmp_path / "c"
    rc, stdout, err = _run("generate", "course", "--out", out, "--count", 501, "--rate", 50,
                           "--gps-rate", 10, "--json")
    assert rc == 0, err
    assert json.loads(stdout)["n_gps"] == 600
    assert _mat(out / "acel.mat")["t"].shape == (3000, 1)
    assert _mat(out / "gps.mat")["t_gps"].shape == (600, 1)
    tj = json.loads((out / "truth.json").read_text())
    assert tj["gps"]["rate_hz"] == 10.0 and "gps.mat" in tj["files"]
    assert missing_units(tj) == []


def test_same_seed_same_bytes(tmp_path):
    args = ("--gps-vel-sigma", "0.1", "--gps-rate", "10")
    for d in ("a", "b"):
        assert _run("generate", "vehicle", "--out", tmp_path / d, "--seed", 5, *args)[0] == 0
    assert _run("generate", "vehicle", "--out", tmp_path / "c", "--seed", 6, *args)[0] == 0
    for name in ("gps.mat", "truth.json", "acel.mat"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    assert (tmp_path / "a/gps.mat").read_bytes() != (tmp_path / "c/gps.mat").read_bytes()


@pytest.mark.parametrize("kind", ["vehicle", "course"])
def test_without_gps_options_the_outputs_are_unchanged(tmp_path, kind):
    """The other files do not depend on asking for fixes; without the options there is no
    gps.mat and truth.json is the old one (the snapshot test checks the bytes of record)."""
    extra = ("--count", "501") if kind == "course" else ()
    plain, gps = tmp_path / "plain", tmp_path / "gps"
    assert _run("generate", kind, "--out", plain, *extra)[0] == 0
    assert _run("generate", kind, "--out", gps, *extra, "--gps-vel-sigma", "0.1")[0] == 0
    assert not (plain / "gps.mat").exists()
    names = sorted(p.name for p in plain.iterdir() if p.name != "truth.json")
    assert names == sorted(p.name for p in gps.iterdir() if p.name not in ("truth.json",
                                                                           "gps.mat"))
    for name in names:
        assert (plain / name).read_bytes() == (gps / name).read_bytes(), name
    tp = json.loads((plain / "truth.json").read_text())
    tg = json.loads((gps / "truth.json").read_text())
    assert "gps" not in tp and not any(k.startswith("gps.") for k in tp["units"])
    tg.pop("gps")
    tg["units"] = {k: v for k, v in tg["units"].items() if not k.startswith("gps.")}
    if kind == "course":
        tg["files"].remove("gps.mat")
    assert tg == tp


@pytest.mark.parametrize("argv, option", [
    (["--gps-rate", "0"], "--gps-rate"),
    (["--gps-rate", "inf"], "--gps-rate"),
    (["--gps-rate", "3"], "--gps-rate"),  # 100 Hz / 3 Hz: off the IMU grid
    (["--gps-sigma", "nan"], "--gps-sigma"),
    (["--gps-sigma", "-1"], "--gps-sigma"),
    (["--gps-sigma", "1e300"], "--gps-sigma"),
    (["--gps-vel-sigma", "-0.1"], "--gps-vel-sigma"),
    (["--gps-latency", "-1"], "--gps-latency"),
    (["--gps-latency", "0.003"], "--gps-latency"),
    (["--gps-outage", "5,1"], "--gps-outage"),
    (["--gps-outage", "0,inf"], "--gps-outage"),
    (["--gps-outage", "0,100"], "--gps-outage"),  # no fix left
])
def test_bad_receiver_options_are_one_line_and_write_nothing(tmp_path, argv, option):
    out = tmp_path / "o"
    rc, stdout, err = _run("generate", "vehicle", "--out", out, *argv)
    assert rc == 2 and stdout == "" and "Traceback" not in err
    lines = unwrap(err).splitlines()
    assert len(lines) == 1 and option in lines[0], err
    assert not out.exists() or not any(out.iterdir())
