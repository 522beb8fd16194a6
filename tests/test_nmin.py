"""How many calibration samples: scaling law, crossings, course subsampling, Monte Carlo."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bench.cli import main
from calib.calibration.tilt_plane import calibrate
from calib.vehicle.nmin import (
    PositionCovModel,
    VehicleCase,
    crossing_n,
    design_nmin,
    posterior_nrange,
    simulate_decisions,
    subsample_analysis,
    synthetic_calibration,
    uniform_design_cov,
)
from calib.vehicle.region import arrival_region, chi2_2dof
from tests.reference import course_2009 as ref

# Course report LS, section 3.2.4: subsampling every 13th sample leaves N = 1539 and the
# decision (C) is still unique; every 14th, N = 1429, and it is not (regions overlap).
REPORT_STEPS = {1: 20001, 2: 10001, 13: 1539, 14: 1429}



@pytest.mark.parametrize("n", [3, 7, 100, 1001])
def test_uniform_design_covariance_is_exact(n):
    """calib's QR covariance for θ_i = 2πi/N equals diag(σ², 2σ²/g², …)/N (the 1/N law)."""
    rng = np.random.default_rng(n)
    e = synthetic_calibration(n, [0.1, -0.1], [0.01, 0.02], ref.NOISE_VAR, rng)
    cal = calibrate(e, ref.NOISE_VAR)
    np.testing.assert_allclose(cal.cov, uniform_design_cov(n, ref.NOISE_VAR), rtol=1e-9,
                               atol=1e-15 / n)


def _d2(delta, model, n):
    return float(delta @ np.linalg.solve(model.cov(n), delta))


def test_crossing_is_the_first_integer_above_threshold():
    rng = np.random.default_rng(0)
    for _ in range(20):
        a = rng.normal(size=(2, 2))
        b = rng.normal(size=(2, 2))
        model = PositionCovModel(A=a @ a.T * 1e4, B=b @ b.T)
        delta = rng.normal(size=2) * 20
        thr = chi2_2dof(0.95)
        n = crossing_n(delta, model, thr)
        if n is None:
            assert _d2(delta, model, 10**12) <= thr
        elif n > 3:
            assert _d2(delta, model, n - 1) <= thr < _d2(delta, model, n)
        else:
            assert _d2(delta, model, 3) > thr


def test_design_none_when_noise_alone_cannot_separate():
    """Two candidates closer than 2r in the vehicle-noise metric: no N suffices."""
    model = PositionCovModel(A=np.eye(2) * 1e6, B=np.eye(2) * 100.0)  # σ_noise = 10 m
    r = np.sqrt(chi2_2dof(0.95))
    close = {"A": np.zeros(2), "B": np.array([0.9 * 2 * r * 10, 0.0])}
    far = {"A": np.zeros(2), "B": np.array([1.1 * 2 * r * 10, 0.0])}
    assert design_nmin(close, model, 0.95)["n"] is None
    n = design_nmin(far, model, 0.95)["n"]
    assert n is not None
    assert np.sqrt(_d2(far["B"], model, n)) > 2 * r >= np.sqrt(_d2(far["B"], model, n - 1))


@pytest.mark.parametrize("level", [0.95, 0.997])
def test_posterior_range_on_course_estimate(course, level):
    """At n_min exactly one candidate is inside; just below it, more than one."""
    _, _, puntos, cal, traj = course
    reg = arrival_region(traj, cal, puntos, ref.NOISE_VAR, level)
    model = PositionCovModel.from_region(reg)
    res = posterior_nrange(reg.estimate, puntos, model, level)
    assert res["letter"] == "C" and res["n_min"] is not None

    def inside(n):
        inv = np.linalg.inv(model.cov(n))
        return [k for k, c in puntos.items()
                if (c - reg.estimate) @ inv @ (c - reg.estimate) <= chi2_2dof(level)]

    assert inside(res["n_min"]) == ["C"]
    assert len(inside(res["n_min"] - 1)) > 1
    assert res["n_min"] <= cal.n  # the course run itself decides


def test_course_subsampling_reproduces_the_report(course):
    ensayo, acel, puntos, _, _ = course
    rows = subsample_analysis(ensayo, acel, VehicleCase(puntos, level=0.997),
                              tuple(REPORT_STEPS), noise_var=ref.NOISE_VAR)
    by_step = {r.step: r for r in rows}
    for step, n in REPORT_STEPS.items():
        assert by_step[step].n == n
    # course criterion (3σ box ellipses around candidates): still unique at 13, not at 14
    for step in (1, 2, 13):
        assert by_step[step].course_decision == "C"
    assert by_step[14].course_decision is None and len(by_step[14].course_inside) > 1
    # ours never names another letter; with the full data it decides C
    assert all(r.decision in ("C", None) for r in rows)
    assert by_step[1].decision == by_step[2].decision == "C"


def test_fresh_runs_at_design_n_decide_right_at_least_at_level(course):
    """At the design N the regions around the candidates are disjoint, so P(right) ≥ L.
    R runs: right/R ≥ L - 4 sqrt(L(1-L)/R); wrong ≤ R(1-L) + 4 sqrt(R L (1-L))."""
    _, acel, puntos, cal, traj = course
    level, runs = 0.95, 200
    reg = arrival_region(traj, cal, puntos, ref.NOISE_VAR, level)
    design = design_nmin(puntos, PositionCovModel.from_region(reg), level)
    assert design["n"] is not None
    shift = reg.estimate - puntos["C"]  # the truth sits on C; geometry kept
    moved = VehicleCase({k: c + shift for k, c in puntos.items()}, level=level)
    row = simulate_decisions(moved, acel.t, traj.acc_corrected, truth="C", n=design["n"],
                             runs=runs, seed=7, bias=cal.bias, scale=cal.scale,
                             noise_var=ref.NOISE_VAR)
    assert row.right / runs >= level - 4 * np.sqrt(level * (1 - level) / runs)
    assert row.wrong <= runs * (1 - level) + 4 * np.sqrt(runs * level * (1 - level))


def test_nmin_cli_json(course_dir, capsys):
    files = ["--ensayo", str(course_dir / "ensayo.mat"), "--acel", str(course_dir / "acel.mat"),
             "--puntos", str(course_dir / "puntos.mat"), "--datos",
             str(course_dir / "datos.txt")]
    assert main(["nmin", *files, "--runs", "0", "--steps", "13,14", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) >= {"design", "posterior", "posterior_course_box", "subsample", "notes"}
    assert [r["n"] for r in out["subsample"]] == [1539, 1429]
    assert any("no N can guarantee" in n for n in out["notes"])
    assert main(["nmin", *files, "--runs", "0", "--steps", "1"]) == 0
    text = capsys.readouterr().out
    assert "design" in text and "no N can guarantee" in text
