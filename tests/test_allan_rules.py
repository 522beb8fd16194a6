"""The rules of the Allan fit (:mod:`calib.noise.allan_fit`): K resolved only with a rise over
enough clusters (its false-call rate on white + flicker logs by Monte Carlo), B under the Allan
minimum's upper χ² bound, a model that describes the curve or says where it does not (the
widening and narrowing steps, and the failed fit), every θ ≥ 0.

Logs come from the independent generator (:mod:`validation.noise_independent.generator`) or
are built directly as octave Allan variances (the engine's own input). Monte Carlo band: a
one-sided false-call rate at α over R logs at most ``α + 4·sqrt(α(1−α)/R)``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from calib.noise.allan import characterize_noise, octave_factors
from calib.noise.allan_fit import (
    B_BOUND_ALPHA,
    CORE,
    FLICKER,
    K_RISE_CLUSTERS,
    K_RISE_STEPS,
    Engine,
    Model,
)
from calib.noise.allan_model import moments, theta_from_terms
from validation.noise_independent.generator import NoiseSpec, static_log

SEED = 20261203


def band(p: float, r: int) -> float:
    return 4.0 * np.sqrt(p * (1.0 - p) / r)


@pytest.mark.slow
def test_k_false_call_rate_on_white_plus_flicker():
    """R = 200 logs of white noise + flicker (AR(1) bank, no walk), 4096 samples at 100 Hz:
    K is called resolved at most α + 4·sqrt(α(1−α)/R) = 0.112 of the time (measured: 0.000;
    the score test alone would call it in 0.10 of them — its own α of 0.05 and more, the
    bank's flicker not being the fit's at the longest τ — the rise rule removes them); the
    model stays the three core terms in ≥ 95 % (an extra term is added by its χ² drop at
    ADD_ALPHA = 0.01, Šidák over the correlation times: measured 2.5 %)."""
    rng = np.random.default_rng(SEED)
    r, alpha = 200, 0.05
    calls = score_calls = extra = 0
    for _ in range(r):
        y, _ = static_log(NoiseSpec(rate=100.0, white=2e-3, flicker=1.5e-3), 4096, rng)
        fit = characterize_noise(y[:, None], 100.0, axes=("x",), alpha=alpha).axes[0]
        k = fit.term("rate_random_walk")
        calls += k.resolved
        score_calls += k.z > 1.6449
        extra += fit.rule != "three terms"
    assert calls / r <= alpha + band(alpha, r), calls / r
    assert extra / r <= 0.05, extra / r
    assert score_calls > calls  # the rule does something on these logs


def test_k_needs_two_octave_steps_of_rise_with_enough_clusters():
    """A walk seen only at the last octaves (n/m < 8 clusters: 2–5 degrees of freedom) is
    not resolved however large its score z; seen over two octave steps with ≥ 8 clusters each,
    it is."""
    rate, n = 100.0, 10_700  # the 107-s log of the issue
    rng = np.random.default_rng(SEED + 1)
    # K√(τ/3) = N/√τ at τ = √3·N/K (N = 2e-3, K = 8.5e-3 and 2e-2 m/s²/√s): 8 s for the
    # first (the rise only beyond n/8 = 13 s), 1.7 s for the second
    late = 0.02 * rng.standard_normal(n) + 8.5e-4 * np.cumsum(rng.standard_normal(n)) / 10
    early = 0.02 * rng.standard_normal(n) + 2e-3 * np.cumsum(rng.standard_normal(n)) / 10
    res = characterize_noise(np.column_stack([late, early]), rate)
    ks = [a.term("rate_random_walk") for a in res.axes]
    assert res.axes[0].k_rise_steps < K_RISE_STEPS and not ks[0].resolved
    assert res.axes[1].k_rise_steps >= K_RISE_STEPS and ks[1].resolved
    assert n // res.axes[1].ms[-1] < K_RISE_CLUSTERS  # the last octave never counts
    if ks[0].z > 1.6449:  # zero rejected by the score test, yet not a resolved walk
        assert "rise" in res.axes[0].summary()


def _engine(n: int, rate: float, terms, scale=None) -> Engine:
    """An engine on the *expected* octave Allan variances of ``terms`` (N, B, K), times
    ``scale`` per octave (to bend the curve)."""
    ms = octave_factors(n, rate)
    mom = moments(n, ms)
    s = mom.design[:, :3] @ theta_from_terms(*terms, rate)
    if scale is not None:
        s = s * scale
    return Engine(s, mom, 1e-12 * s[0] / mom.design[0, 0])


def test_b_stays_under_the_allan_minimum_bound():
    """On the model's own curve the fit is exact and B is inside its bound; with the floor's
    octaves pulled down (the real log of the issue: a fitted floor 1.84× above the measured
    minimum) the three-term fit's B would exceed the upper χ² bound of the lowest point, so
    it is not accepted: the chosen model satisfies the bound or the fit is reported failed."""
    n, rate = 2 ** 14, 100.0
    eng = _engine(n, rate, (2e-3, 1.5e-3, 5e-5))
    fit = eng.fit(Model(CORE, None, 0, eng.k))
    assert fit.bound_ok and fit.chi2 < 1e-6 and fit.p > 0.99
    assert fit.theta[FLICKER] <= fit.b_bound
    dip = np.ones(eng.k)
    dip[7:10] = 0.3  # the minimum 0.55× the model's deviation over three octaves
    bent = _engine(n, rate, (2e-3, 1.5e-3, 5e-5), dip)
    core = bent.fit(Model(CORE, None, 0, bent.k))
    # the bound at the lowest point: s·ν/χ²_ν(α) (the upper χ² bound at α = B_BOUND_ALPHA)
    i = core.b_bound_index
    assert core.b_bound == pytest.approx(
        bent.s[i] * core.edf[i] / stats.chi2.ppf(B_BOUND_ALPHA, core.edf[i])
        / bent.mom.design[i, FLICKER])
    chosen, ok, tried = bent.select()
    assert not ok or (chosen.bound_ok and chosen.p >= 0.01)
    assert any(not f.bound_ok or f.p < 0.01 for f in tried)


def test_a_drift_at_the_end_narrows_the_range_and_the_twin_parts_there():
    """A strong warm-up drift (its ramp dominates the last octaves): no model of the ladder
    describes the whole curve; the rule keeps the widest adequate τ range and says which
    octaves it leaves out; the terms read inside it still cover their truth."""
    from bench.sensor_twin import simulate_axis, twin_axis
    from calib.noise.closure import closure_test, twin_adev

    spec = NoiseSpec(rate=10.0, white=1e-3, flicker=3e-4, drift=5e-2, drift_tc=3000.0)
    rng = np.random.default_rng(SEED + 2)
    n = 2 ** 14
    y = np.column_stack([static_log(spec, n, rng)[0] for _ in range(2)])
    res = characterize_noise(y, spec.rate, level=0.99)  # one log: a 99 % interval to check
    fit = res.axes[0]
    assert fit.fit_ok and fit.octaves[1] < fit.taus.size  # the longest octaves left out
    assert "not described by the model" in fit.summary()
    for name, true in (("white_noise_density", spec.white), ("bias_instability", spec.flicker)):
        lo, hi = fit.term(name).interval
        assert lo <= true <= hi, name
    twin = simulate_axis(twin_axis(res.to_profile(), "x", spec.rate), n, spec.rate, rng)
    closure = closure_test(fit, twin_adev(fit, twin, spec.rate))
    assert closure.reject and max(closure.parted) >= fit.octaves[1] - 1
    assert "REJECTED" in closure.summary() and "τ =" in closure.summary()


def test_a_curve_no_model_describes_is_reported_failed():
    """A sine of period 16 samples on white noise: its Allan variance peaks at m = 8 and
    vanishes at m = 16, 32, … — a cliff no sum of the model's smooth terms follows on any
    range of ≥ 5 octaves. The fit says so (fit_ok false, every model tried listed), and no
    θ is negative (before θ ≥ 0, a huge term cancelled by a negative one inflated V(θ) and
    "passed" χ² at p = 0.63)."""
    rng = np.random.default_rng(SEED + 3)
    n, rate = 512, 100.0
    t = np.arange(n) / rate
    y = 0.01 * rng.standard_normal(n) + 0.1 * np.sin(2 * np.pi * t / 0.16)
    res = characterize_noise(np.column_stack([y, 0.01 * rng.standard_normal(n)]), rate)
    fit = res.axes[0]
    assert not fit.fit_ok and not res.fit_ok and res.axes[1].fit_ok
    assert len(fit.tried) >= 3 and all(tr["p"] < 0.01 or not tr["b_bound_ok"]
                                       for tr in fit.tried)
    assert np.all(np.asarray(fit.theta) >= 0)
    assert "NO model of the rule describes this curve" in fit.summary()
