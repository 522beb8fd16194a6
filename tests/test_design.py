"""``calib.design`` / ``tiltbench design``: analytic power against an independent Monte Carlo.

Acceptance (issue 14): for 3 linear effects × 3 designs the analytic power of the gap's χ²
test (non-central χ², :mod:`calib.design.power`) is compared with the fraction of R
independently simulated runs where the same statistic ``LR = (RSS_0 - RSS_1)/σ²`` exceeds
the same critical value. The data and the fits are written here from the equations (course
model ``A_m = A_r + v``, ``A_rx = -g sin θ``; misalignment ``-g sin(θ)cos δ - g cos(θ) sin δ``
… ), not with calib's regressor code. Band: under the analytic p, hits ~ Binomial(R, p);
|p̂ - p| ≤ 3.3·sqrt(p(1-p)/R) holds per cell with probability ≈ 0.999 (normal approximation,
two-sided z = 3.29), so over the 9 cells the familywise false-failure rate is ≤ 9 × 0.001
≈ 0.9 % (Bonferroni). Sizes are chosen so p is in 30–90 % (the test can fail).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import stats

from bench.cli import main
from calib.design import Experiment, analyze_design
from calib.design.power import lambda_for_power, power_from_lambda

G = 9.8
NV = (0.25, 0.64)
R = 400
N = 301
DESIGNS = ("uniform", "reversal", "accel")
SIZES = {"misalignment": 0.015, "nonlinearity_k2": 3e-3, "cross_axis": 3.2e-3}


def _signal(name: str, th: np.ndarray, size: float) -> np.ndarray:
    """Reading of the x sensor with the effect (IEEE 1293 style model, gain 1), m/s²."""
    ax, ay = -G * np.sin(th), -G * np.cos(th)
    if name == "misalignment":  # sensitive axis rotated by δ: A_rx cos δ + A_ry sin δ
        return ax * np.cos(size) + ay * np.sin(size)
    if name == "nonlinearity_k2":
        return ax + size * ax**2
    return ax + size * ax * ay  # cross_axis


def _extra_column(name: str, th: np.ndarray) -> np.ndarray:
    ax, ay = -G * np.sin(th), -G * np.cos(th)
    return {"misalignment": ay, "nonlinearity_k2": ax**2, "cross_axis": ax * ay}[name]


def _rss(h: np.ndarray, y: np.ndarray) -> np.ndarray:
    beta, *_ = np.linalg.lstsq(h, y, rcond=None)
    return np.sum((y - h @ beta) ** 2, axis=0)


@pytest.fixture(scope="module")
def analytic():
    exps = [Experiment(d, N, 0.314) for d in DESIGNS]
    return analyze_design(exps, list(SIZES), SIZES, NV, runs=0)


@pytest.mark.parametrize("name", list(SIZES))
def test_analytic_power_agrees_with_an_independent_monte_carlo(analytic, name):
    rng = np.random.default_rng(1234 + list(SIZES).index(name))
    e = analytic.effects[name]
    for i, d in enumerate(DESIGNS):
        row = e["per_experiment"][i]
        p = row["power"]
        assert 0.3 <= p <= 0.9, (name, d, p)
        th = Experiment(d, N, 0.314).theta()
        h0 = np.column_stack([np.ones(N), -G * np.sin(th)])
        h1 = np.column_stack([h0, _extra_column(name, th)])
        y = _signal(name, th, SIZES[name])[:, None] + rng.normal(0, np.sqrt(NV[0]), (N, R))
        lr = (_rss(h0, y) - _rss(h1, y)) / NV[0]
        crit = stats.chi2.isf(analytic.experiments[i]["alpha_step"], 1)
        p_hat = float(np.mean(lr > crit))
        assert abs(p_hat - p) <= 3.3 * np.sqrt(p * (1 - p) / R), (name, d, p_hat, p)


def test_size_for_80_percent_has_80_percent_power(analytic):
    for name, e in analytic.effects.items():
        for i, row in enumerate(e["per_experiment"]):
            exp = Experiment(DESIGNS[i], N, 0.314)
            one = analyze_design([exp], [name], {name: row["size_80"]}, NV, runs=0)
            assert abs(one.effects[name]["per_experiment"][0]["power"] - 0.80) < 1e-6


def test_lambda_inverse_and_false_alarm_rate():
    crit = stats.chi2.isf(1e-3, 2)
    lam = lambda_for_power(0.5, 2, crit)
    assert abs(float(power_from_lambda(lam, 2, crit)) - 0.5) < 1e-9
    assert abs(float(power_from_lambda(0.0, 2, crit)) - 1e-3) < 1e-12


def test_constant_sweep_cannot_tell_lag_from_misalignment_a_reversal_can():
    """Lag τ on a constant-rate sweep is an angle offset -τω: the gap names the misalignment
    (assumes less), so the power to tell them apart is ~0; on a reversal the sign of ω flips
    and the lag is named. 12 runs each: 0/12 vs ≥ 9/12 is far outside either's binomial
    spread (the reversal's 12/12 here has p̂ std 0)."""
    exps = [Experiment("sweep", 601, 0.314), Experiment("reversal", 601, 0.314)]
    res = analyze_design(exps, ["lowpass_lag", "misalignment"], {"lowpass_lag": 0.05}, NV,
                         runs=12, seed=3)
    pair = res.pairs["lowpass_lag-vs-misalignment"]["per_experiment"]
    assert pair[0]["power"] <= 0.1
    assert pair[1]["power"] >= 0.75


def test_cli_json_has_units_and_plot_writes_png(tmp_path, capsys):
    png = tmp_path / "p.png"
    rc = main(["design", "--designs", "uniform,reversal", "--n", "301", "--runs", "2",
               "--workers", "1", "--effects", "misalignment,tilt_offset,noise_level",
               "--json", "--plot", str(png)])
    out = capsys.readouterr().out
    assert rc == 0
    d = json.loads(out)
    from calib.units import missing_units
    assert missing_units(d) == []
    assert d["units"]["effects.misalignment.size"] == "rad"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["design", "--plot", str(png), "--runs", "0"]) == 2  # exists, no --force


@pytest.mark.parametrize("argv, words", [
    (["--designs", "spiral"], "choose from"), (["--size", "misalignment"], "NAME=VALUE"),
    (["--size", "saturation=-1"], "positive"), (["--alpha", "2"], "(0, 1)"),
    (["--effects", "gravity_mismatch"], "choose from"), (["--rate", "0"], "positive")])
def test_bad_options_are_clear_errors(capsys, argv, words):
    assert main(["design", *argv]) == 2
    assert words in capsys.readouterr().err
