"""Bounded work (issue 23, part 4): the fast subset of ``validation.fuzz`` whose faults were
fixed — a runaway turned into bounded work, divisions by zero on small valid runs, NaN / Inf /
absurd numeric options of every command. Each case: no traceback, no last-resort message,
exit 0 with a finite result or exit 2 with one error line, and no hang (a wall-clock bound).
"""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest
import scipy.io

from calib.gap.quantization import SHEPPARD_RATIO, quantized_moments
from tests.cli import one_line_error, run

LAST_RESORT = ("please report", "would be nan", "singular matrix", "overflowerror")


def _refuse_constant(name: str):
    raise AssertionError(f"non-finite number {name} in the JSON output")


def _clean_result(rc: int, out: str, err: str) -> dict:
    """Exit 0, one finite JSON object, no traceback or last-resort message."""
    assert rc == 0, err
    assert "Traceback" not in err
    assert not any(m in err.lower() for m in LAST_RESORT), err
    obj = json.loads(out, parse_constant=_refuse_constant)
    assert isinstance(obj, dict)
    return obj


def _ensayo(path, n: int, rng=None, lsb: float | None = None):
    """A course ensayo.mat of N samples over a turn (noise σ = 0.5, 0.8 m/s² if ``rng``;
    readings rounded to ``lsb`` if given)."""
    tita = np.linspace(0.0, 2 * np.pi, n, endpoint=n > 4)
    datos = 1.01 * np.column_stack([-9.8 * np.sin(tita), -9.8 * np.cos(tita)]) + [0.08, -0.02]
    if rng is not None:
        datos = datos + rng.normal(0.0, [0.5, 0.8], datos.shape)
    if lsb is not None:
        datos = lsb * np.round(datos / lsb)
    scipy.io.savemat(path, {"tita": tita[:, None], "datos": datos})
    return path


# ---------------------------------------------------------------- the gap runaway
def test_quantized_moments_bounded_and_exact():
    """σ/lsb = 10⁴ (the runaway: 80 000 lattice terms per sample) takes Sheppard's moments,
    and they agree with the exact lattice sum at the switch, σ = SHEPPARD_RATIO·lsb, to
    rounding (the neglected terms carry exp(−2π²·4) ≈ 5e-35)."""
    mu = np.linspace(-0.05, 0.05, 201)
    lsb = 0.01
    t0 = time.perf_counter()
    m1, var = quantized_moments(mu, 1e4 * lsb**2 * 1e4, lsb)
    assert time.perf_counter() - t0 < 0.5
    np.testing.assert_array_equal(m1, mu)
    np.testing.assert_allclose(var, 1e8 * lsb**2 + lsb**2 / 12, rtol=1e-15)
    s2 = (SHEPPARD_RATIO * lsb) ** 2
    s2_below = (0.999 * SHEPPARD_RATIO * lsb) ** 2  # the lattice sum, just below the switch
    m1s, vs = quantized_moments(mu, s2_below, lsb)
    np.testing.assert_allclose(m1s, mu, atol=1e-15)
    np.testing.assert_allclose(vs, s2_below + lsb**2 / 12, rtol=1e-13)
    m1e, ve = quantized_moments(mu, s2, lsb)
    np.testing.assert_allclose(ve, s2 + lsb**2 / 12, rtol=1e-15)


def test_gap_absurd_noise_on_a_quantized_run_is_bounded(tmp_path, capsys):
    """The issue's runaway: ``gap … --noise-var 100,100`` on a quantized run (lsb 0.002,
    N = 2001; before the fix ≈ 8·10⁴ normal CDFs per sample: killed after 100 s here) ends
    in about a second; the bound asserted is the harness's hang limit."""
    path = _ensayo(tmp_path / "q.mat", 2001, np.random.default_rng(5), lsb=0.002)
    t0 = time.perf_counter()
    _clean_result(*run(capsys, "gap", path, "--noise-var", "100,100", "--json"))
    assert time.perf_counter() - t0 < 60.0


# ---------------------------------------------------------------- small valid runs
@pytest.mark.parametrize("n", [3, 4])
@pytest.mark.parametrize("noise", [True, False])
def test_small_runs_calibrate(tmp_path, capsys, n, noise):
    """N = 3 and 4, noisy or exact (RSS = 0: σ² estimated as 0, χ² = dof by definition)."""
    path = _ensayo(tmp_path / "e.mat", n, np.random.default_rng(n) if noise else None)
    obj = _clean_result(*run(capsys, "calibrate", path, "--json"))
    for a in ("x", "y"):  # σ² estimated: χ²/dof is 1 by construction
        assert math.isclose(obj["axes"][a]["chi2_dof"], 1.0, rel_tol=1e-12)
    _clean_result(*run(capsys, "calibrate", path, "--noise-var", "0.25,0.64", "--json"))


def test_exact_run_joint_wls_is_refused_in_one_line(tmp_path, capsys):
    """The joint WLS weights by the estimated σ²: zero on exact data (these four θ leave the
    y residuals exactly 0, checked first), refused by name instead of a division."""
    from calib.calibration.ls import fit_axis

    tita = np.linspace(0.0, 6.28, 4)
    datos = np.column_stack([-9.8 * np.sin(tita), -9.8 * np.cos(tita)]) + 0.1
    assert fit_axis(tita, datos[:, 1], "y").sigma2 == 0.0
    path = tmp_path / "e.mat"
    scipy.io.savemat(path, {"tita": tita[:, None], "datos": datos})
    _clean_result(*run(capsys, "calibrate", path, "--json"))  # OLS: exact, std 0
    msg = one_line_error(capsys, "calibrate", path, "--method", "wls", ignore=("note:",))
    assert "noiseless" in msg and "noise variances" in msg


@pytest.mark.parametrize("n", [3, 4])
def test_small_runs_gap(tmp_path, capsys, n):
    """N = 3 used to divide by zero (σ² named with no degree of freedom left)."""
    path = _ensayo(tmp_path / "e.mat", n, np.random.default_rng(n))
    res = _clean_result(*run(capsys, "gap", path, "--noise-var", "0.25,0.64", "--json"))
    # bias and scale only: nothing to find, and no noise level named without a dof for it
    assert res["verdict"] == "nothing_detected"
    assert res["effects"] == []


# ---------------------------------------------------------------- numeric options
@pytest.fixture(scope="module")
def course(tmp_path_factory):
    """A small course set: ensayo.mat (200), acel.mat (300), puntos.mat, gps.mat."""
    d = tmp_path_factory.mktemp("course")
    _ensayo(d / "ensayo.mat", 200, np.random.default_rng(3))
    t = np.arange(300) * 0.01
    scipy.io.savemat(d / "acel.mat", {"t": t[:, None], "Aerr": np.zeros((t.size, 2))})
    scipy.io.savemat(d / "puntos.mat", {"A": np.array([[3.0, 9.0]]),
                                        "B": np.array([[50.0, 50.0]])})
    scipy.io.savemat(d / "gps.mat", {"t_gps": np.array([[0.0], [1.0], [2.0]]),
                                     "pos": np.zeros((3, 2))})
    return d


def _veh(d) -> list:
    return ["--ensayo", d / "ensayo.mat", "--acel", d / "acel.mat", "--puntos",
            d / "puntos.mat"]


OPTION_CASES = [
    # (command and its fixed arguments as a function of the course folder, option, value)
    (lambda d: ["fuse", *_veh(d), "--gps", d / "gps.mat"], "--psi0", "nan"),
    (lambda d: ["fuse", *_veh(d), "--gps", d / "gps.mat"], "--psi0", "inf"),
    (lambda d: ["fuse", *_veh(d), "--gps", d / "gps.mat"], "--psi0-sigma", "1e300"),
    (lambda d: ["fuse", *_veh(d), "--gps", d / "gps.mat"], "--gps-sigma", "nan"),
    (lambda d: ["fuse", *_veh(d), "--gps", d / "gps.mat"], "--gps-sigma", "1e-300"),
    (lambda d: ["fuse", *_veh(d), "--gps", d / "gps.mat"], "--p0-std", "inf"),
    (lambda d: ["fuse", *_veh(d), "--gps", d / "gps.mat"], "--gyro-sigma", "1e300"),
    (lambda d: ["trajectory", *_veh(d)], "--g", "nan"),
    (lambda d: ["trajectory", *_veh(d)], "--g", "1e-300"),
    (lambda d: ["trajectory", *_veh(d)], "--level", "1e-300"),
    (lambda d: ["calibrate", d / "ensayo.mat"], "--level", "nan"),
    (lambda d: ["calibrate", d / "ensayo.mat"], "--g", "-inf"),
    (lambda d: ["gap", d / "ensayo.mat", "--noise-var", "0.25,0.64"], "--g", "nan"),
    (lambda d: ["validate", "--truth", d / "t.json", "--estimates", d / "e.json"],
     "--level", "nan"),
    (lambda d: ["design", "--effects", "misalignment", "--designs", "uniform"],
     "--alpha", "nan"),
    (lambda d: ["design", "--effects", "misalignment", "--designs", "uniform"],
     "--scale", "inf"),
    (lambda d: ["noise", d / "ensayo.mat"], "--static-shift", "nan"),
    (lambda d: ["generate", "vehicle", "--gps", "--out", d / "o"], "--gps-latency", "inf"),
    (lambda d: ["generate", "vehicle", "--gps", "--out", d / "o"], "--gps-sigma", "1e300"),
    (lambda d: ["import", d / "ensayo.mat", "--out", d / "o"], "--min-hold", "nan"),
    (lambda d: ["calibrate", d / "ensayo.mat"], "--static-window", "1e300"),
    (lambda d: ["import", d / "ensayo.mat", "--out", d / "o"], "--min-hold", "1e300"),
]


@pytest.mark.parametrize("make, option, value", OPTION_CASES,
                         ids=[f"{i}:{o}={v}" for i, (_, o, v) in enumerate(OPTION_CASES)])
def test_numeric_options_refused_in_one_line(course, capsys, make, option, value):
    """Refused on parsing, before any file is read or written, naming the option."""
    msg = one_line_error(capsys, *make(course), f"{option}={value}")
    assert option in msg
    assert not (course / "o").exists()


def test_fixes_of_absurd_size_are_refused_by_name(course, tmp_path, capsys):
    """gps.mat positions of 1e300 m (before: NaN state estimates, a last-resort message)."""
    bad = tmp_path / "gps.mat"
    scipy.io.savemat(bad, {"t_gps": np.array([[0.0], [1.0]]), "pos": np.full((2, 2), 1e300)})
    msg = one_line_error(capsys, "fuse", *_veh(course), "--gps", bad, "--json")
    assert "'pos'" in msg and "gps.mat" in msg


def test_design_power_with_a_tiny_stated_variance(capsys):
    """σx² = 1e-50: the non-centrality is astronomically large and the power exactly 1
    (scipy's ncx2.sf returned NaN there: "would be nan")."""
    from calib.design.power import LAMBDA_SURE, power_from_lambda

    assert power_from_lambda(np.array([LAMBDA_SURE * 10, 1e300]), 1, 30.0).tolist() == [1, 1]
    obj = _clean_result(*run(capsys, "design", "--effects", "misalignment", "--designs",
                             "uniform", "--count", "201", "--noise-var", "1e-50,0.64", "--json",
                             "--workers", "1", "--quiet"))
    powers = [e["power"] for e in obj["effects"]["misalignment"]["per_experiment"]]
    assert powers and all(p == 1.0 for p in powers)


def test_monte_carlo_runaway_is_refused_with_its_estimate(capsys):
    """``design --runs 1e12`` (a simulated effect) planned centuries of CPU; refused in one
    line with the estimate, before any run (bench.limits.WORK_LIMIT_SECONDS)."""
    for extra in (["--runs", "1e12"], ["--runs", "40", "--mc-grid", "1e15"]):
        msg = one_line_error(capsys, "design", "--effects", "saturation", "--designs",
                             "uniform", "--count", "201", "--workers", "1", "--quiet", *extra)
        assert "CPU hours" in msg and "--runs" in msg


@pytest.mark.parametrize("argv", [
    ["generate", "calibration", "--count", "201"],
    ["design", "--effects", "misalignment", "--designs", "uniform"],
])
def test_negative_seed_is_refused_by_name(tmp_path, capsys, argv):
    out = tmp_path / "o"
    msg = one_line_error(capsys, *argv, "--seed", "-1", "--out", out) if argv[0] == "generate" \
        else one_line_error(capsys, *argv, "--seed", "-1")
    assert "--seed" in msg
    assert not out.exists()
