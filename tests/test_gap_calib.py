"""Discrepancy workflow, estimation side (``calib.gap``): detection, selection, estimates.

Synthetic runs come from :mod:`tests.gap_synthetic`: numpy straight from the equations of
``docs/effects.md`` (never through ``calib`` or the bench), so an error in the estimator's
model cannot cancel in the test. The bench-generated end-to-end tests live with the bench
(``bench.gap``).

Tolerances (derived, not tuned)
-------------------------------
* Estimates: ``|estimate - truth| ≤ 4 std`` (P ≈ 6e-5 per parameter for a Gaussian estimate;
  the random-walk q is a variance component with a skewed estimate: its std, derived from the
  profile-likelihood interval, gives sd(z) ≈ 1.0-1.05 and P(|z| > 4) ≲ 1e-3, measured in
  ``benchmarks/gap_uncertainty_mc.py`` and asserted in
  :func:`test_random_walk_interval_and_std_are_honest`).
* Gap after the fit: per axis, χ²/dof inside the two-sided 99.9 % χ²(dof)/dof band and
  ``max_signature_z`` below its Bonferroni threshold at α = 0.001 (each fails with P ≤ 0.001
  under a correct model).
* Naming: exactly the true effects. A correct selector adds a spurious one with P ≤
  ``family_alpha`` = :data:`calib.gap.selection.FAMILY_ALPHA` (0.001) per run (Bonferroni).
* False-alarm rate: R clean runs, K runs that name anything, K ~ Binomial(R, p) with
  p ≤ FAMILY_ALPHA; assert ``K ≤ binom.ppf(0.999, R, FAMILY_ALPHA)`` (a selector at its stated
  level fails with P ≤ 0.001).
All randomness is seeded; seeds are fixed per case (``SEED``, case index), never searched.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from scipy import stats

from calib.calibration.tilt_plane import calibrate
from calib.conventions import AXES
from calib.effects import Extensions, ModelState, RunData, lowpass
from calib.files.course import Ensayo, read_ensayo
from calib.gap import analyze_gap, predict, q_uncertainty
from calib.gap.selection import FAMILY_ALPHA
from calib.stats.diagnostics import detect_lattice, gap_measure, hinge_levels
from tests.gap_synthetic import RATE, STATED, TWO_PI, G, design, lowpass_loop, synth
from tests.pools import process_pool

SEED = 20240605
ALPHA_TEST = 0.001


# ------------------------------------------------------------------------ cases

# (design, [(name, axis, params)]): each effect at a clearly detectable size (≥ 7 std). Tables:
# their rows are alike in shape, not in logic.
ONE_EFFECT = [
    ("uniform", [("misalignment", "x", {"delta": 0.02})]),
    ("held", [("misalignment", "y", {"delta": -0.025})]),
    ("uniform", [("tilt_offset", "both", {"delta": 0.015})]),
    ("held", [("nonlinearity_k2", "x", {"k2": 0.004})]),
    ("uniform", [("nonlinearity_k2", "y", {"k2": -0.004})]),
    ("uniform", [("cross_axis", "x", {"k_ip": 0.004})]),
    ("held", [("cross_axis", "y", {"k_ip": -0.004})]),
    ("uniform", [("bias_drift", "x", {"rate_per_sample": 1e-4})]),
    ("updown", [("bias_drift", "y", {"rate": 0.015})]),
    ("held", [("bias_random_walk", "y", {"q_per_sample": 0.02})]),
    ("updown", [("bias_random_walk", "x", {"q": 0.2})]),
    ("uniform", [("quantization", "x", {"lsb": 0.5})]),
    ("held", [("quantization", "y", {"lsb": 0.4})]),
    ("uniform", [("saturation", "x", {"limit": 9.0})]),
    ("held", [("saturation", "y", {"limit": 8.5})]),
    ("uniform", [("noise_level", "x", {"sigma2": 0.33})]),
    ("updown", [("noise_level", "y", {"sigma2": 0.45})]),
    ("uniform", [("noise_level", "x", {"sigma2": 0.18})]),
    ("updown", [("lowpass_lag", "x", {"tau": 0.05})]),
    ("sine", [("lowpass_lag", "y", {"tau": 0.05})]),
    ("sine", [("lever_arm", "x", {"pos_x": 0.3, "pos_z": 0.2})]),
    ("sine", [("lever_arm", "y", {"pos_x": -0.2, "pos_z": 0.25})]),
]

TWO_EFFECTS = [
    ("uniform", [("nonlinearity_k2", "x", {"k2": 0.004}), ("misalignment", "y", {"delta": 0.02})]),
    ("sine", [("nonlinearity_k2", "y", {"k2": 0.004}), ("lowpass_lag", "x", {"tau": 0.05})]),
    ("held", [("bias_drift", "x", {"rate_per_sample": 1e-4}), ("quantization", "y", {"lsb": 0.5})]),
    ("uniform", [("saturation", "y", {"limit": 9.0}), ("cross_axis", "x", {"k_ip": 0.004})]),
    ("sine", [("lever_arm", "x", {"pos_x": 0.3, "pos_z": 0.2}),
              ("noise_level", "y", {"sigma2": 0.9})]),
]


def _ids(cases):
    return ["-".join([c[0]] + [f"{n}:{a}" for n, a, _ in c[1]]) for c in cases]


def _check_named_and_estimates(res, effects):
    truth = {(n, a) for n, a, _ in effects}
    assert set(res.named) == truth, res.summary()
    for name, axis, params in effects:
        est = res.effect(name, axis)
        for key, value in params.items():
            err = est.params[key] - value
            # quantization lsb comes from an exact lattice: float64 rounding is its only error
            slack = 8 * np.finfo(float).eps * abs(value) if name == "quantization" else 0.0
            assert abs(err) <= 4 * est.std[key] + slack, (name, axis, key, est)
        assert est.p_value < res.criterion["alpha_step"], est


def _check_after_is_noise(res):
    """The gap after is measured against the stated noise: its χ² band holds unless a noise
    level is named on the axis (its excess then reads as χ²/dof ≠ 1). The verdict is scored
    over many runs against its stated error rate (tests/test_validation_score.py), not per run."""
    for a in AXES:
        m = res.gap_after_fit[a]
        lo, hi = m.chi2_band(ALPHA_TEST)
        if ("noise_level", a) in res.named:
            assert m.chi2_dof > hi or m.chi2_dof < lo, (a, m.details())
            continue
        assert lo <= m.chi2_dof <= hi, (a, m.details())
        assert m.max_signature_z <= m.threshold_z(ALPHA_TEST), (a, m.details())


@pytest.mark.parametrize("case", range(len(ONE_EFFECT)), ids=_ids(ONE_EFFECT))
def test_each_effect_named_estimated_and_gap_closed(case):
    """Each catalog effect alone: right name and axis, estimate within 4 std, the gap before
    shows it (the axis' gap is not noise at α = 0.001) and the fitted extension closes it."""
    kind, effects = ONE_EFFECT[case]
    th, y, t = synth(kind, 3000, np.random.default_rng([SEED, 1, case]), effects)
    res = analyze_gap(Ensayo(th, y, t), STATED)
    _check_named_and_estimates(res, effects)
    _check_after_is_noise(res)
    for name, axis, _ in effects:
        if name != "quantization":  # a lattice is seen in the readings, not the residuals
            for a in (AXES if axis == "both" else (axis,)):
                assert not res.gap_before[a].consistent(ALPHA_TEST), (a, res.summary())


@pytest.mark.parametrize("case", range(len(TWO_EFFECTS)), ids=_ids(TWO_EFFECTS))
def test_two_effects_at_once(case):
    kind, effects = TWO_EFFECTS[case]
    th, y, t = synth(kind, 3000, np.random.default_rng([SEED, 2, case]), effects)
    res = analyze_gap(Ensayo(th, y, t), STATED)
    _check_named_and_estimates(res, effects)
    _check_after_is_noise(res)


def test_tilt_offset_reported_with_its_confusion():
    effects = [("tilt_offset", "both", {"delta": 0.015})]
    th, y, _ = synth("uniform", 3000, np.random.default_rng([SEED, 3]), effects)
    res = analyze_gap(Ensayo(th, y), STATED)
    assert res.named == [("tilt_offset", "both")]
    names = [set(d["names"]) for d in res.not_identifiable]
    assert {"tilt_offset", "misalignment"} in names


def test_lowpass_at_constant_rate_is_reported_as_confused_with_an_offset():
    """At a constant sweep rate the lag looks like an angle offset -τω (docs/effects.md)."""
    effects = [("lowpass_lag", "x", {"tau": 0.05})]
    th, y, t = synth("constant", 3000, np.random.default_rng([SEED, 4]), effects)
    res = analyze_gap(Ensayo(th, y, t), STATED)
    named = {n for n, _ in res.named}
    confused = [set(d["names"]) for d in res.not_identifiable if "lowpass_lag" in d["names"]]
    assert named & {"lowpass_lag", "misalignment", "tilt_offset"}
    assert confused and confused[0] & {"misalignment", "tilt_offset"}, res.not_identifiable


def test_a_slight_clip_of_the_top_pose_is_found_as_saturation():
    """Held poses, one of them clipped by a little: the limit lies between the top pose's
    |A_r| and the grid's top level (half-way to the next pose), where Brent reaches it only
    with |A_r|max as its upper bracket. Before, the profile stopped at the top level, which
    clips more than the data do: LR 0, and a walk and K2 took the clip (drive set, seed 2)."""
    rng = np.random.default_rng([SEED, 12])
    poses = np.array([-3.1, -2.9, -1.94, -1.408, -1.12, -0.5, 0.38, 2.1, 2.99])
    tita = np.repeat(poses, 300)
    a = np.column_stack([-G * np.sin(tita), -G * np.cos(tita)])
    limit = 9.57  # the top pose reads |A_x| = 9.67: clipped by 0.1 m/s² (1 σ) only there
    y = np.column_stack([0.03 + np.clip(a[:, 0], -limit, limit), -0.02 + a[:, 1]])
    stated = (0.01, 0.01)
    y = y + rng.normal(0.0, 1.0, y.shape) * np.sqrt(stated)
    res = analyze_gap(Ensayo(tita, y), stated)
    assert res.named == [("saturation", "x")], res.summary()
    est = next(e for e in res.effects if e.name == "saturation")
    assert abs(est.params["limit"] - limit) < 4.0 * est.std["limit"] + 1e-3, est


def test_partial_sweep_names_the_truth_or_says_it_cannot_tell():
    """On part of a turn the misalignment (A_p) and cross-axis (A_r·A_p) columns are nearly
    collinear: either the truth is named, or the named one is reported as confused with it."""
    effects = [("misalignment", "x", {"delta": 0.03})]
    th, y, _ = synth("partial", 3000, np.random.default_rng([SEED, 5]), effects)
    res = analyze_gap(Ensayo(th, y), STATED)
    assert len(res.named) == 1
    if res.named != [("misalignment", "x")]:
        pair = {res.named[0][0], "misalignment"}
        assert any(set(d["names"]) == pair for d in res.not_identifiable), res.summary()


def test_gravity_mismatch_is_never_named_but_always_listed():
    th, y, _ = synth("uniform", 3000, np.random.default_rng([SEED, 6]),
                     [("gravity_mismatch", "both", {"g": 9.83})])
    res = analyze_gap(Ensayo(th, y), STATED)
    assert res.named == []
    entry = [d for d in res.not_identifiable if d["names"] == ["gravity_mismatch"]]
    assert entry and entry[0]["reason"].startswith("absorbed by the scale factors")


def test_timing_effects_skipped_without_timing_and_rate_equals_t():
    """Without t or a rate, lowpass_lag and lever_arm are listed as needing timing; giving
    the sample rate instead of t (uniform sampling) gives the same analysis."""
    effects = [("lowpass_lag", "y", {"tau": 0.05})]
    th, y, t = synth("updown", 2000, np.random.default_rng([SEED, 7]), effects)
    no_t = analyze_gap(Ensayo(th, y), STATED)
    assert set(no_t.needs_timing) == {"lowpass_lag", "lever_arm"}
    assert "lowpass_lag" not in {n for n, _ in no_t.named}
    with_t = analyze_gap(Ensayo(th, y, t), STATED)
    with_rate = analyze_gap(Ensayo(th, y), STATED, rate=RATE)
    assert with_t.needs_timing == () == with_rate.needs_timing
    assert with_t.named == with_rate.named == [("lowpass_lag", "y")]
    tau_t = with_t.effect("lowpass_lag").params["tau"]
    tau_r = with_rate.effect("lowpass_lag").params["tau"]
    assert abs(tau_t - tau_r) <= 1e-9 * tau_t


def test_course_file_names_nothing_and_its_gap_is_noise(course_dir):
    res = analyze_gap(read_ensayo(course_dir / "ensayo.mat"), STATED)
    assert res.named == [], res.summary()
    for a in AXES:
        m = res.gap_before[a]
        lo, hi = m.chi2_band(ALPHA_TEST)
        assert lo <= m.chi2_dof <= hi
        assert m.max_signature_z <= m.threshold_z(ALPHA_TEST), m.details()
    assert set(res.needs_timing) == {"lowpass_lag", "lever_arm"}


# ----------------------------------------------------------- false-alarm rate (clean runs)

CLEAN_DESIGNS = ("uniform", "held", "partial", "constant", "updown", "sine")
CLEAN_PER_DESIGN = 84


LEVEL_CHECKS = ("gain_drift", "hysteresis", "cross_correlation", "variance_force")
"""Battery checks added in stop 26 whose level the clean runs also check."""


def _clean_run(job: tuple[str, int]) -> tuple[str, int, list, list]:
    kind, i = job
    rng = np.random.default_rng(np.random.SeedSequence([SEED, 8, CLEAN_DESIGNS.index(kind), i]))
    th, y, t = synth(kind, 2000, rng)
    res = analyze_gap(Ensayo(th, y, t), STATED)
    return kind, i, res.named, [(c["name"], c["p_value"]) for c in res.adequacy["checks"]
                                if c["name"] in LEVEL_CHECKS]


@pytest.mark.slow
def test_false_alarm_rate_on_clean_runs():
    """R = 504 clean runs (six θ designs, N = 2000) name anything in at most
    ``binom.ppf(0.999, R, FAMILY_ALPHA)`` = 4 runs (module docstring; the selection's level,
    0.001 since stop 44). On the same runs each of
    :data:`LEVEL_CHECKS` keeps its level: the count of p < 0.05 lies in the 0.9999 band of
    Binomial(n, 0.05) (a check whose null law were wrong — autocorrelated series, a column
    the model spans — would fall outside; hysteresis runs where θ moves both ways)."""
    jobs = [(k, i) for k in CLEAN_DESIGNS for i in range(CLEAN_PER_DESIGN)]
    r = len(jobs)
    with process_pool(2) as ex:
        results = list(ex.map(_clean_run, jobs, chunksize=8))
    alarms = [(k, i, named) for k, i, named, _ in results if named]
    k_max = int(stats.binom.ppf(0.999, r, FAMILY_ALPHA))
    assert len(alarms) <= k_max, alarms
    for name in LEVEL_CHECKS:
        p = np.array([v for *_, ps in results for n, v in ps if n == name])
        assert p.size >= 100, (name, p.size)
        lo, hi = stats.binom.ppf([5e-5, 1 - 5e-5], p.size, 0.05)
        assert lo <= np.sum(p < 0.05) <= hi, (name, int(np.sum(p < 0.05)), p.size, lo, hi)


# ------------------------------------------------ honesty of the random-walk uncertainty

WALK_R = 400
WALK_N = 2000
WALK_Q = 2.0 * float(np.sqrt(STATED[0] / WALK_N))  # q√N = 2σ_x per sample


def _walk_run(i: int):
    rng = np.random.default_rng(np.random.SeedSequence([SEED, 15, i]))
    return synth("uniform", WALK_N, rng, [("bias_random_walk", "x", {"q_per_sample": WALK_Q})])


def _walk_replicate(i: int) -> tuple[float, float, float, float]:
    """q̂, std, interval of run i through analyze_gap's own path when the walk is named:
    the nominal gains, the REML test of the walk on x, ``refine``, ``q_uncertainty``
    (selection skipped for speed; the test checks on run 0 that this is what it reports)."""
    th, y, _ = _walk_run(i)
    ext = Extensions(RunData.build(th, y, G),
                     1.0 + calibrate(Ensayo(th, y), STATED, "ols", G).scale)
    state = ModelState.nominal(STATED)
    state = ext.refine(ext.test(state, "bias_random_walk", "x").state)
    std, (lo, hi) = q_uncertainty(ext, state, 0)
    return state.axes[0].q, std, lo, hi


@pytest.mark.slow
def test_random_walk_interval_and_std_are_honest():
    """Random walk on x, static full-turn design, N = 2000, q√N = 2σ_x; R = 400 runs.

    * The reported 95 % profile-likelihood interval covers the true q: with H hits,
      ``|H/R - 0.95| ≤ 4·sqrt(0.95·0.05/R)`` = 0.044 (4 binomial standard errors).
    * The std stays valid for ``estimate ± std`` statements: ``q̂ ± 1.96 std`` covers within the
      same binomial band; the mean of z² = ((q̂ - q)/std)² (NEES, p = 1) is within
      ``1 ± 4·sqrt(2/R)`` = ±0.28 (var z² = 2 for a Gaussian z; q̂ is mildly skewed); and the
      4-std check used by the other tests fails in at most ``binom.ppf(0.999, R, 1e-3)`` runs
      (the P(|z| > 4) ≲ 1e-3 of the module docstring).
    Run 0 is also analysed by :func:`analyze_gap`: it names the walk and reports the same
    numbers, so the fast path here is the reported one.
    """
    th, y, _ = _walk_run(0)
    res = analyze_gap(Ensayo(th, y), STATED)
    assert res.named == [("bias_random_walk", "x")], res.summary()
    with process_pool(2) as ex:
        out = np.array(list(ex.map(_walk_replicate, range(WALK_R), chunksize=20)))
    q_hat, std, lo, hi = out.T
    est = res.effect("bias_random_walk", "x")
    np.testing.assert_allclose([est.params["q_per_sample"], est.std["q_per_sample"],
                                *est.interval["q_per_sample"]], out[0], rtol=1e-5)
    # (the same optimum to the profile search's tolerance, 1e-4 of its bracket in log q)
    assert np.all((lo < q_hat) & (q_hat < hi)) and np.all(lo > 0)
    r = WALK_R
    band = 4.0 * np.sqrt(0.95 * 0.05 / r)
    z = (q_hat - WALK_Q) / std
    cover_interval = np.mean((lo <= WALK_Q) & (WALK_Q <= hi))
    cover_std = np.mean(np.abs(z) <= stats.norm.ppf(0.975))
    assert abs(cover_interval - 0.95) <= band, cover_interval
    assert abs(cover_std - 0.95) <= band, cover_std
    assert abs(np.mean(z * z) - 1.0) <= 4.0 * np.sqrt(2.0 / r), np.mean(z * z)
    assert np.sum(np.abs(z) > 4) <= stats.binom.ppf(0.999, r, 1e-3)


# --------------------------------------------------------------- the yardstick itself

def test_gap_measure_is_calibrated_under_noise():
    """Under white noise the Bonferroni p of max_signature_z is a valid p-value:
    #(p < 0.05) ≤ binom.ppf(0.999, R, 0.05) over R = 400 series (timed, with readings)."""
    rng = np.random.default_rng([SEED, 9])
    r_runs, n = 400, 600
    hits = 0
    for _ in range(r_runs):
        th, t = design("sine", n, rng)
        a = np.column_stack([-G * np.sin(th), -G * np.cos(th)])
        y = a[:, 0] + 0.5 * rng.standard_normal(n)
        h = np.column_stack([np.ones(n), a[:, 0]])
        resid = y - h @ np.linalg.lstsq(h, y, rcond=None)[0]
        m = gap_measure(resid, th, 0.25, t, a[:, 1], own_ref=a[:, 0], readings=y, n_params=2)
        hits += m.max_signature_p < 0.05
    assert hits <= stats.binom.ppf(0.999, r_runs, 0.05)


SIGNATURE_CASES = [("cos1", "h1_cos"), ("sin1", "h1_sin"), ("cos2", "h2_cos"),
                   ("sin2", "h2_sin"), ("trend", "trend"), ("ar1", "whiteness"),
                   ("scale", "chi2")]


@pytest.mark.parametrize("case", range(len(SIGNATURE_CASES)),
                         ids=[c[0] for c in SIGNATURE_CASES])
def test_gap_measure_points_to_the_signature(case):
    """A residual with one structure: the worst signature names it, above its threshold
    (misalignment → 1st harmonic, K2 → cos 2θ, cross-axis → sin 2θ, drift → trend, lag or
    random walk → whiteness, noise level → χ²)."""
    shape, expected = SIGNATURE_CASES[case]
    rng = np.random.default_rng([SEED, 10, case])
    n = 3000
    th = np.sort(rng.uniform(0, TWO_PI, n))
    v = 0.5 * rng.standard_normal(n)
    add = {"cos1": 0.15 * np.cos(th), "sin1": 0.15 * np.sin(th), "cos2": 0.15 * np.cos(2 * th),
           "sin2": 0.15 * np.sin(2 * th), "trend": np.linspace(0, 0.3, n),
           "scale": 0.3 * v}
    if shape == "ar1":
        r = np.empty(n)
        r[0] = v[0]
        for k in range(1, n):  # AR(1), ρ = 0.3, same variance
            r[k] = 0.3 * r[k - 1] + np.sqrt(1 - 0.09) * v[k]
    else:
        r = v + add[shape]
    m = gap_measure(r, th, 0.25)
    assert m.worst == expected, m.details()
    assert m.max_signature_z > m.threshold_z(ALPHA_TEST)


def test_lattice_detection():
    rng = np.random.default_rng([SEED, 11])
    x = 9.8 * np.sin(rng.uniform(0, TWO_PI, 4000)) + 0.5 * rng.standard_normal(4000)
    assert not detect_lattice(x).found
    held = np.repeat(np.linspace(-9.8, 9.8, 8), 500) + 0.5 * rng.standard_normal(4000)
    assert not detect_lattice(held).found
    for lsb in (0.5, 0.01, 1e-4, 2.0**-10):
        lat = detect_lattice(lsb * np.floor(x / lsb + 0.5))
        assert lat.found and abs(lat.lsb - lsb) <= 1e-9 * lsb, (lsb, lat)
    shifted = 0.3 + 0.05 * np.round(x / 0.05)  # a lattice with an offset
    assert abs(detect_lattice(shifted).lsb - 0.05) <= 1e-9
    m = gap_measure(x - np.mean(x), np.zeros(4000) + np.arange(4000) * 1e-3, 1.0,
                    readings=0.05 * np.round(x / 0.05), model_lsb=0.05)
    assert m.signature("lattice") == 0.0


def test_hinge_levels_on_held_positions():
    th = np.repeat(np.linspace(0, TWO_PI, 24, endpoint=False), 100)
    levels = hinge_levels(-G * np.cos(th))
    distinct = np.unique(np.round(np.abs(G * np.cos(th)), 9))
    assert levels.size >= 3
    assert not np.any(np.isin(np.round(levels, 9), distinct))  # strictly between levels


# --------------------------------------------------------------------- API and contracts

def test_to_dict_layout_and_json():
    effects = [("misalignment", "x", {"delta": 0.02})]
    th, y, _ = synth("uniform", 2000, np.random.default_rng([SEED, 12]), effects)
    res = analyze_gap(Ensayo(th, y), STATED)
    d = json.loads(json.dumps(res.to_dict()))
    assert {"effects", "not_identifiable", "gap_before", "gap_after", "verdict",
            "unexplained", "adequacy"} <= set(d)
    assert d["verdict"] in ("explained", "unexplained", "nothing_detected")
    assert all(c["name"] and c["axis"] in (*AXES, "both") for c in d["adequacy"]["checks"])
    assert [c["axis"] for c in d["adequacy"]["checks"] if c["name"] == "cross_correlation"] == [
        "both"]
    (e,) = d["effects"]
    assert set(e) == {"name", "axis", "params", "std", "statistic", "p_value", "tentative"}
    assert e["tentative"] == (d["verdict"] == "unexplained")
    assert e["name"] == "misalignment" and e["axis"] == "x" and set(e["params"]) == {"delta"}
    for key in ("gap_before", "gap_after"):
        assert set(d[key]) == {"x", "y"}
        for a in AXES:
            assert set(d[key][a]) == {"chi2_dof", "max_signature_z"}
    for entry in d["not_identifiable"]:
        assert set(entry) == {"names", "reason"} and isinstance(entry["names"], list)
    assert res.residuals_before.shape == res.residuals_after.shape == (2000, 2)
    assert "misalignment (x)" in res.summary()


def test_predict_reproduces_the_fit_and_needs_timing_for_a_lag():
    effects = [("lowpass_lag", "x", {"tau": 0.05}), ("bias_drift", "y", {"rate": 0.01})]
    th, y, t = synth("updown", 2000, np.random.default_rng([SEED, 13]), effects)
    res = analyze_gap(Ensayo(th, y, t), STATED)
    assert set(res.named) == {("lowpass_lag", "x"), ("bias_drift", "y")}
    np.testing.assert_allclose(predict(res, th, t), res.fitted, rtol=0, atol=1e-10)
    with pytest.raises(ValueError, match="sample times"):
        predict(res, th)


def test_lowpass_matches_the_catalog_equation():
    rng = np.random.default_rng([SEED, 14])
    t_uniform = np.arange(500) / RATE
    t_jitter = np.cumsum(rng.uniform(0.5, 1.5, 500)) / RATE
    u = np.sin(3 * t_uniform) + 0.1 * rng.standard_normal(500)
    for t, h in ((t_uniform, 1 / RATE), (t_jitter, None)):
        np.testing.assert_allclose(lowpass(u, t, 0.07, h), lowpass_loop(u, t, 0.07),
                                   rtol=0, atol=1e-12)
    ramp = 2.0 * t_uniform
    lagged = lowpass(ramp, t_uniform, 0.05, 1 / RATE)
    assert abs(lagged[-1] - (ramp[-1] - 2.0 * 0.05)) < 1e-12  # a ramp lags by τ


def test_calib_never_imports_bench_or_mujoco():
    code = ("import sys, calib.gap, calib.effects, calib.stats.diagnostics; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('bench', 'mujoco')]; "
            "assert not bad, bad")
    subprocess.run([sys.executable, "-c", code], check=True)
