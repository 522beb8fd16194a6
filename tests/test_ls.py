"""Least-squares calibration: course reference, Monte Carlo honesty, identifiability, numerics."""

from __future__ import annotations

import contextlib
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from calib.calibration.correct import apply_errors, correct
from calib.calibration.ls import (
    NotIdentifiableError,
    PoorlyIdentifiedWarning,
    fit_axis,
    fit_joint,
)
from calib.calibration.tilt_plane import calibrate
from calib.conventions import reference_accel
from calib.files.course import Ensayo, read_ensayo
from tests.reference import course_2009 as ref

G = 9.8


# --- course reference ---------------------------------------------------------------------

@pytest.mark.parametrize("method", ["ols", "wls"])
def test_course_estimates_and_variances(course_dir, method):
    cal = calibrate(read_ensayo(course_dir / "ensayo.mat"), ref.NOISE_VAR, method)
    d = cal.to_dict()["axes"]
    for key, (value, decimals) in ref.ESTIMATES.items():
        name, axis = key.split("_")
        assert abs(d[axis][name] - value) <= 0.5 * 10.0**-decimals, key
    for key, (value, digits) in ref.VARIANCES.items():
        name, axis = key.split("_")
        var = d[axis][f"{name}_std"] ** 2
        exponent = math.floor(math.log10(abs(value)))
        assert abs(var - value) <= 0.5 * 10.0 ** (exponent - digits + 1), (key, var)


def test_course_gap_is_noise(course_dir):
    """With the stated σ², the course residuals have χ²/dof within the χ² spread of 1."""
    cal = calibrate(read_ensayo(course_dir / "ensayo.mat"), ref.NOISE_VAR)
    for f in cal.fits.values():
        lo, hi = stats.chi2.ppf([5e-4, 1 - 5e-4], f.dof) / f.dof
        assert lo < f.chi2_dof < hi


# --- Monte Carlo: the covariance and the intervals are honest ------------------------------

def _mc_estimates(n_runs: int, n: int, sigma2_given: bool, seed: int):
    rng = np.random.default_rng(seed)
    tita = np.sort(rng.uniform(0, 2 * np.pi, n))
    truth = np.array([0.3, -0.02])  # bias, scale of axis y
    a_r = reference_accel(tita)[:, 1]
    sigma = 0.8
    est, cov, hits = [], [], 0
    for _ in range(n_runs):
        a_m = apply_errors(a_r, truth[0], truth[1]) + sigma * rng.standard_normal(n)
        f = fit_axis(tita, a_m, "y", sigma**2 if sigma2_given else None)
        est.append(f.params)
        cov.append(f.cov)
        ci = f.conf_int(0.95)
        hits += np.sum((ci[:, 0] <= truth) & (truth <= ci[:, 1]))
    return np.array(est), np.array(cov), hits, truth


def test_mc_covariance_and_coverage_sigma_given():
    """R = 3000 runs, N = 30: empirical covariance matches the reported one; 95 % covers 95 %.

    * variance of each estimate: (R-1) s²/σ² ~ χ²(R-1); accept within the 1e-4 two-sided tails.
    * NEES (p̂-p)ᵀΣ⁻¹(p̂-p) ~ χ²(2): its mean is within 2 ± 4·sqrt(2·2/R).
    * coverage of each interval: hits ~ Binomial(2R, 0.95) (2 parameters per run; the two
      indicators are dependent, so use R, not 2R, for a conservative spread):
      |hits/2R - 0.95| <= 4 sqrt(0.95·0.05/R).
    """
    R = 3000
    est, cov, hits, truth = _mc_estimates(R, 30, True, seed=20261121)
    sigma_rep = cov[0]  # σ² given: the reported covariance is the same every run
    emp = np.cov(est.T)
    lo, hi = stats.chi2.ppf([5e-5, 1 - 5e-5], R - 1) / (R - 1)
    for k in range(2):
        assert lo < emp[k, k] / sigma_rep[k, k] < hi
    d = est - truth
    nees = np.einsum("ij,jk,ik->i", d, np.linalg.inv(sigma_rep), d)
    assert abs(nees.mean() - 2) <= 4 * math.sqrt(2 * 2 / R)
    assert abs(hits / (2 * R) - 0.95) <= 4 * math.sqrt(0.95 * 0.05 / R)


def test_mc_coverage_sigma_estimated_uses_t():
    """σ² estimated, N = 8 (dof 6): Student-t intervals cover 95 %; normal ones would not.

    With dof = 6 the normal quantile 1.96 gives ≈ 90 % coverage; the binomial tolerance
    4 sqrt(0.95·0.05/R) at R = 3000 is 0.016, so the test separates the two.
    """
    R = 3000
    est, cov, hits, truth = _mc_estimates(R, 8, False, seed=7)
    assert abs(hits / (2 * R) - 0.95) <= 4 * math.sqrt(0.95 * 0.05 / R)


# --- identifiability and numerics --------------------------------------------------------

def test_all_theta_equal_names_the_parameter():
    tita = np.full(50, 0.7)
    datos = reference_accel(tita) + 0.1
    with pytest.raises(NotIdentifiableError, match="scale_x"):
        fit_axis(tita, datos[:, 0], "x", 0.25)
    with pytest.raises(NotIdentifiableError, match="scale_y"):
        calibrate(Ensayo(tita, datos), (0.25, 0.64), "wls")


def test_axis_blind_design_names_that_axis_only():
    """θ ∈ {0, π}: A_rx = -g sin θ is 0 at both, so only the x scale is unidentifiable."""
    tita = np.repeat([0.0, np.pi], 20)
    datos = reference_accel(tita)
    datos[:, 0] = 0.05 + 1e-3 * np.arange(40) % 3
    fit_axis(tita, datos[:, 1], "y", 0.64)  # y is fine
    with pytest.raises(NotIdentifiableError, match="scale_x"):
        fit_axis(tita, datos[:, 0], "x", 0.25)


def test_small_theta_range_warns_with_cond_and_std():
    rng = np.random.default_rng(1)
    tita = np.linspace(0.3, 0.3 + 5e-4, 200)
    a_m = reference_accel(tita)[:, 0] + 0.5 * rng.standard_normal(200)
    with pytest.warns(PoorlyIdentifiedWarning, match=r"condition number .* std\(scale_x\)"):
        f = fit_axis(tita, a_m, "x", 0.25)
    assert f.std[1] > 1.0  # the warning is right: the scale is unknowable here


def test_full_turn_does_not_warn(recwarn):
    tita = np.linspace(0, 2 * np.pi, 100)
    fit_axis(tita, reference_accel(tita)[:, 0], "x", 0.25)
    assert not [w for w in recwarn if issubclass(w.category, PoorlyIdentifiedWarning)]


def test_ill_conditioned_design_exact_where_normal_equations_fail():
    """θ ∈ [0, 0.01] rad, noise-free: lstsq on the centred design recovers the parameters to
    1e-9 relative; the MATLAB-style inv(GᵀG)Gᵀy loses far more (y axis: A_ry ≈ -g)."""
    tita = np.linspace(0.0, 0.01, 2001)
    bias, scale = 0.0767, -0.0301
    a_m = apply_errors(reference_accel(tita), bias, scale)
    for k, axis in enumerate("xy"):
        with pytest.warns(PoorlyIdentifiedWarning) if axis == "y" else contextlib.nullcontext():
            f = fit_axis(tita, a_m[:, k], axis, 0.25)
        np.testing.assert_allclose(f.params, [bias, scale], rtol=1e-9)
    a_r = reference_accel(tita)[:, 1]
    Gm = np.column_stack([np.ones_like(a_r), a_r])
    naive = np.linalg.inv(Gm.T @ Gm) @ Gm.T @ (a_m[:, 1] - a_r)
    assert np.max(np.abs(naive - [bias, scale]) / np.abs([bias, scale])) > 1e-9


def test_per_axis_equals_joint_with_block_diagonal_weights(course_dir):
    e = read_ensayo(course_dir / "ensayo.mat")
    ols = calibrate(e, ref.NOISE_VAR, "ols")
    wls = calibrate(e, ref.NOISE_VAR, "wls")
    np.testing.assert_allclose(wls.params, ols.params, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(wls.cov, ols.cov, rtol=1e-10, atol=1e-18)


def test_correlated_noise_couples_axes():
    """With correlated noise the joint WLS differs from per-axis OLS and is more precise."""
    rng = np.random.default_rng(3)
    tita = rng.uniform(0, 2 * np.pi, 400)
    C = np.array([[0.25, 0.3], [0.3, 0.64]])
    noise = rng.multivariate_normal([0, 0], C, 400)
    datos = apply_errors(reference_accel(tita), [0.1, -0.1], [0.01, 0.02]) + noise
    joint = fit_joint(tita, datos, C)
    ols = calibrate(Ensayo(tita, datos), np.diag(C), "ols")
    assert np.all(np.diag(joint.cov) < np.diag(ols.cov))


def test_estimated_sigma_matches_residual_variance():
    rng = np.random.default_rng(5)
    tita = rng.uniform(0, 2 * np.pi, 1000)
    a_m = reference_accel(tita)[:, 0] + 0.5 * rng.standard_normal(1000)
    f = fit_axis(tita, a_m, "x")
    assert f.sigma2_source == "estimated"
    assert f.sigma2 == pytest.approx(f.residuals @ f.residuals / f.dof)
    assert f.chi2_dof == pytest.approx(1.0)


def test_result_is_frozen_and_readonly():
    tita = np.linspace(0, 6, 20)
    f = fit_axis(tita, reference_accel(tita)[:, 0], "x", 0.25)
    with pytest.raises(AttributeError):
        f.params = np.zeros(2)  # type: ignore[misc]
    with pytest.raises(ValueError):
        f.params[0] = 1.0
    assert "bias" in f.summary() and "scale" in f.summary()


# --- properties --------------------------------------------------------------------------

finite = st.floats(-0.5, 0.5, allow_nan=False)


@settings(derandomize=True, max_examples=60, deadline=None)
@given(bias=finite, scale=st.floats(-0.2, 0.2), a=st.floats(-30, 30))
def test_correct_inverts_apply(bias, scale, a):
    assert correct(apply_errors(np.array([a]), bias, scale), bias, scale)[0] == pytest.approx(
        a, abs=1e-12)


@settings(derandomize=True, max_examples=40, deadline=None)
@given(
    tita=st.lists(st.floats(0, 2 * np.pi), min_size=3, max_size=30, unique=True),
    bias=finite, scale=st.floats(-0.2, 0.2), axis=st.sampled_from("xy"),
)
def test_noiseless_data_give_exact_parameters(tita, bias, scale, axis):
    tita = np.array(tita)
    k = "xy".index(axis)
    a_r = reference_accel(tita)[:, k]
    if np.ptp(a_r) < 0.5:  # nearly-blind designs are covered by the warning tests
        return
    f = fit_axis(tita, apply_errors(a_r, bias, scale), axis, 0.25)
    np.testing.assert_allclose(f.params, [bias, scale], atol=1e-12)


@settings(derandomize=True, max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_sample_order_is_irrelevant(seed):
    rng = np.random.default_rng(seed)
    tita = rng.uniform(0, 2 * np.pi, 50)
    a_m = reference_accel(tita)[:, 0] + rng.standard_normal(50)
    perm = rng.permutation(50)
    a, b = fit_axis(tita, a_m, "x", 0.25), fit_axis(tita[perm], a_m[perm], "x", 0.25)
    np.testing.assert_allclose(a.params, b.params, rtol=1e-10, atol=1e-13)
