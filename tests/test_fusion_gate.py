"""The filter that doubts its inputs, on clean runs (issue 23): the innovation gate rejects
right fixes at its stated rate α_g, and the windowed NIS verdict fires at its stated
false-alarm rate α (calib.fusion.innovation_check). Monte Carlo from the equations of the course
vehicle (the generator of tests/test_fusion.py: 60 s at 50 Hz, 59 fixes at 1 Hz, σ = 3 m),
R = 500 runs, fixed seed.

Bands: a count of independent Bernoulli(p) trials over n trials, |hits/n − p| ≤
4·sqrt(p(1 − p)/n) (binomial, ±4σ: a false failure about once in 16 000 runs of the test).
Fix rejections: n = R·M = 29 500 trials (the innovations of a right filter are independent,
so are its gate decisions). Verdicts: n = R = 500 runs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from calib.fusion.innovation_check import (
    CONSISTENCY_ALPHA,
    GATE_ALPHA,
    Consistency,
    capped_sum_quantiles,
    window_slices,
    windowed_nis,
)
from calib.fusion.kalman import gate_threshold
from calib.fusion.linear import fuse
from tests.test_fusion import (
    BIAS_HAT,
    CAL_COV,
    P0_COV,
    P0_HAT,
    SCALE_HAT,
    SIGMA_A2,
    SIGMA_POS,
    V0_COV,
    V0_HAT,
    generate,
)

SEED = 20261126
R = 500


def within(hits: int, n: int, p: float) -> bool:
    """|hits/n − p| ≤ 4·sqrt(p(1 − p)/n) (module docstring)."""
    return abs(hits / n - p) <= 4.0 * math.sqrt(p * (1.0 - p) / n)


def run(data, gate_alpha, **kw):
    return fuse(data["t"], data["acc_m"], data["t_gps"], data["fixes"], bias=BIAS_HAT,
                scale=SCALE_HAT, cal_cov=CAL_COV, noise_var=SIGMA_A2, sigma_pos=SIGMA_POS,
                p0=P0_HAT, v0=V0_HAT, p0_cov=P0_COV, v0_cov=V0_COV, keep="fixes",
                gate_alpha=gate_alpha, **kw)


@pytest.fixture(scope="module")
def clean():
    return generate(np.random.default_rng(SEED), R=R)


def test_gate_threshold_is_the_chi2_quantile():
    # χ²(2) has the survival function exp(-x/2): the gate is -2 ln α in closed form
    for a in (0.001, 0.01, 0.2):
        assert gate_threshold(a, 2) == pytest.approx(-2.0 * math.log(a), rel=1e-12)
    assert gate_threshold(0.0, 2) == math.inf and gate_threshold(1.0, 4) == 0.0
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        gate_threshold(1.5, 2)


def test_capped_sum_band_matches_draws():
    """The FFT law of Σ min(X, c) against 400 000 seeded draws: the share of draws below the
    lower and above the upper quantile is the tail, within its binomial ±4σ band."""
    rng = np.random.default_rng(SEED + 1)
    n = 400_000
    for d, k, tail in ((2, 10, 0.01), (4, 6, 0.05), (2, 3, 0.002)):
        cap = gate_threshold(GATE_ALPHA, d)
        lo, hi = capped_sum_quantiles(d, cap, k, tail)
        x = np.minimum(rng.chisquare(d, (n, k)), cap).sum(axis=1)
        assert within(int(np.sum(x < lo)), n, tail), (d, k, "low")
        assert within(int(np.sum(x > hi)), n, tail), (d, k, "high")
    # no gate: the χ²(dk) quantiles themselves
    assert capped_sum_quantiles(2, math.inf, 5, 0.01) == pytest.approx(
        (stats.chi2.ppf(0.01, 10), stats.chi2.isf(0.01, 10)), rel=1e-12)


def test_windows_cover_every_fix_once():
    for m, k in ((59, 10), (60, 10), (3, 10), (25, 7)):
        sl = window_slices(m, k)
        idx = np.concatenate([np.arange(m)[s] for s in sl])
        assert idx.tolist() == list(range(m))
        assert all(k - 1 <= s.stop - s.start <= k for s in sl) or len(sl) == 1
    with pytest.raises(ValueError, match="window"):
        window_slices(10, 0)


@pytest.mark.parametrize("gate_alpha", [GATE_ALPHA, 0.05])
def test_gate_rejects_right_fixes_at_its_rate(clean, gate_alpha):
    res = run(clean, gate_alpha)
    rejected = int(np.sum(~res.fix_used))
    trials = res.fix_used.size
    assert trials == R * clean["t_gps"].size
    assert within(rejected, trials, gate_alpha), (rejected, trials)
    # a rejected fix is not used: its NIS reached the gate, every used one is below it
    nis = res.nis()
    cap = gate_threshold(gate_alpha, 2)
    assert np.all(nis[~res.fix_used] >= cap) and np.all(nis[res.fix_used] < cap)


@pytest.mark.parametrize("alpha", [CONSISTENCY_ALPHA, 0.2])
def test_consistency_flag_fires_at_its_false_alarm_rate(clean, alpha):
    """On right runs (default gate) the share of runs called inconsistent is α."""
    res = run(clean, GATE_ALPHA)
    w = windowed_nis(res.nis(), d=2, gate_alpha=GATE_ALPHA, alpha=alpha)
    fired = int(np.sum(~w["consistent"]))
    assert within(fired, R, alpha), (fired, alpha)
    # Šidák: W independent windows at α_w give α for the run
    W = len(w["slices"])
    assert 1.0 - (1.0 - w["per_window_alpha"]) ** W == pytest.approx(alpha, rel=1e-12)


def test_a_misstated_fix_sigma_is_inconsistent(clean):
    """Fixes twice as noisy as stated (R ×4): most runs are called inconsistent."""
    noisy = dict(clean, fixes=clean["fixes"] + np.random.default_rng(SEED + 2).normal(
        0.0, SIGMA_POS * math.sqrt(3.0), clean["fixes"].shape))
    res = run(noisy, GATE_ALPHA)
    w = windowed_nis(res.nis(), d=2, gate_alpha=GATE_ALPHA)
    assert np.mean(~w["consistent"]) > 0.9


def test_one_outlier_is_gated_and_the_run_stays_consistent():
    data = generate(np.random.default_rng(SEED + 3), R=1)
    data["fixes"][0, 30] += [200.0, 0.0]
    clean_run = run(generate(np.random.default_rng(SEED + 3), R=1), GATE_ALPHA)
    res = run(data, GATE_ALPHA)
    assert not res.fix_used[0, 30] and int(np.sum(~res.fix_used)) == 1
    # the result without that fix: near the clean run's, within its stated σ
    d = res.final_position[0] - clean_run.final_position[0]
    assert np.all(np.abs(d) < 3 * np.sqrt(np.diag(res.final_position_cov[0])))
    single = fuse(data["t"], data["acc_m"][0], data["t_gps"], data["fixes"][0], bias=BIAS_HAT,
                  scale=SCALE_HAT, cal_cov=CAL_COV, noise_var=SIGMA_A2, sigma_pos=SIGMA_POS,
                  p0=P0_HAT, v0=V0_HAT, p0_cov=P0_COV, v0_cov=V0_COV, gate_alpha=GATE_ALPHA)
    cons = Consistency.of(single)
    assert cons.consistent and cons.rejected.tolist() == [30]
    assert Consistency.from_dict(cons.to_dict()).to_dict() == cons.to_dict()
