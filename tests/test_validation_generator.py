"""The validation generator (``validation/``) checked from first principles, without calib.

What is checked, and against what:

* the θ designs have the shapes promised (turns, overshoot, reversals, holds, timing);
* the sensor chain's equations: rotation = angle offset, the low-pass against the closed-form
  ramp response, the random walk's increments, the direction memory of the hysteresis;
* clean runs: a nominal LS fit written here (``[1, -g sin θ]`` with g = 9.80665) leaves
  residuals whose χ² is inside its two-sided band and whose lag-1 autocorrelation is that of
  white noise; the fitted bias/scale match the truth;
* catalog cases: fitting the right extended model (written here from ``docs/effects.md``)
  recovers the true parameter within its standard error, so truth and data agree;
* sizes: every effect lands in its stated range, and sizes recomputed here agree;
* MuJoCo sweep: the hinge-axis sites read ``-g sin θ``, ``-g cos θ`` (< 1e-3 m/s²), the
  off-axis sites add ``-ω²·p`` (centripetal) and ``α·ŷ×p`` (tangential);
* the expected LR of a random walk and the 1/f spectrum match Monte Carlo;
* determinism (same seed, same bytes), the .mat writer, and the scoring rules on stubs.

Statistical checks use a stated false-alarm rate: each χ² band is two-sided at
α = 1e-4 and each parameter check at 4.5 standard errors (p ≈ 7e-6), Bonferroni over at most
a hundred checks: a correct generator fails the file with probability < 1 %. Seeds are fixed,
so the outcome is reproducible.
"""

from __future__ import annotations

import hashlib
import json
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.fft
import scipy.io
from scipy import stats

from validation import cases as vcases
from validation import designs, effects, sizes, sweep
from validation.generate import main as generate_main
from validation.generate import write_set
from validation.score import judge, matches, max_wrong, score

G = 9.80665  # written again: the test does not trust the generator's constant
SEED = 20240610
ALPHA_CHI2 = 1e-4
Z_PARAM = 4.5


@pytest.fixture(scope="module")
def vset():
    return vcases.validation_set(SEED)


def _ref(theta):
    return np.column_stack([-G * np.sin(theta), -G * np.cos(theta)])


def _fit(cols, y, sigma):
    """Known-σ least squares: (coefficients, standard errors, residuals)."""
    a = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    cov = sigma**2 * np.linalg.inv(a.T @ a)
    return coef, np.sqrt(np.diag(cov)), y - a @ coef


def _truth(case, name):
    return next(e for e in case.truth["effects"] if e["name"] == name)


# --- designs ----------------------------------------------------------------------------------

def test_designs_have_the_promised_shapes():
    two_pi = 2 * np.pi
    for name in designs.DESIGNS:
        tita, t = designs.design(name)
        n = tita.size
        assert (300 <= n <= 500) if name == "short" else (1500 <= n <= 6000), name
        assert (t is not None) == (name in designs.TIMED), name
        if t is not None:
            assert t.shape == (n,) and np.allclose(np.diff(t), 1 / designs.RATE, rtol=0, atol=1e-12)
    th = {name: designs.design(name)[0] for name in designs.DESIGNS}
    assert th["full_turn"][0] == 0 and np.isclose(th["full_turn"][-1], two_pi)
    assert np.isclose(th["several_turns"][-1], 6 * np.pi)
    assert np.isclose(th["past_2pi"][-1], two_pi + 0.3)
    assert th["overshoot"][-1] == 6.2841 and 6.2841 > two_pi
    assert np.isclose(th["negative"][-1], -two_pi) and th["negative"].max() <= 1e-12
    assert np.unique(th["held_poses"]).size == 10
    assert th["mujoco_sweep"][-1] > 4 * two_pi
    w = np.gradient(*designs.design("oscillating"))
    assert np.sum(np.diff(np.sign(w[np.abs(w) > 1e-6])) != 0) >= 3  # reversals
    tita, t = designs.design("stop_and_go")
    w = np.gradient(tita, t)
    assert np.mean(w == 0) > 0.4 and w.max() > 0.5  # holds and moves
    tita, t = designs.design("varying_rate")
    w = np.gradient(tita, t)
    assert w.min() >= -1e-9 and w.max() > 1.8 * w.mean()


def test_timed_sweeps_start_and_stop_at_rest():
    for name in ("full_turn", "several_turns", "past_2pi", "negative", "varying_rate"):
        tita, t = designs.design(name)
        w = np.gradient(tita, t)
        assert abs(w[0]) < 1e-2 and abs(w[-1]) < 1e-2, name


# --- the chain's equations --------------------------------------------------------------------

def test_rotation_is_an_angle_offset():
    th = np.linspace(-7, 7, 301)
    for d in (-0.3, 0.01, 0.2):
        np.testing.assert_allclose(effects.rotate(_ref(th), d), _ref(th + d), atol=1e-12)


def test_lowpass_matches_the_closed_form_ramp_response():
    # τ y' + y = m t from rest: y = m (t - τ (1 - exp(-t/τ)))
    t = np.arange(0, 5, 0.01)
    m, tau = 0.7, 0.3
    y = effects.lowpass(m * t, t, tau)
    np.testing.assert_allclose(y, m * (t - tau * (1 - np.exp(-t / tau))), atol=1e-12)
    # uneven steps (the loop) agree with the same formula
    tu = np.sort(np.r_[0.0, np.random.default_rng(SEED).uniform(0, 5, 400)])
    np.testing.assert_allclose(effects.lowpass(m * tu, tu, tau),
                               m * (tu - tau * (1 - np.exp(-tu / tau))), atol=1e-12)
    np.testing.assert_array_equal(effects.lowpass(m * t, t, 0.0), m * t)


def test_random_walk_increments_and_direction_memory():
    w = np.random.default_rng(SEED).standard_normal(50)
    dt = np.full(49, 0.01)
    b = effects.walk(w, dt, 0.3)
    assert b[0] == 0
    np.testing.assert_allclose(np.diff(b), 0.3 * 0.1 * w[1:], atol=1e-15)
    omega = np.array([0, 0, 1, 1, 0, 0, -2, 0, 0, 3])
    np.testing.assert_array_equal(effects.direction(omega), [1, 1, 1, 1, 1, 1, -1, -1, -1, 1])


def test_noise_free_reading_is_the_ieee_1293_equation():
    tita, t = designs.design("varying_rate")
    run = effects.Run.build("varying_rate", tita, t)
    ax = effects.AxisSpec(bias=0.1, scale=0.02, k2=0.004, k_ip=-0.003, rate=0.01)
    ay = effects.AxisSpec(bias=-0.05, scale=-0.01, delta=0.02, limit=9.0)
    got = effects.mean_reading(run, effects.Spec(x=ax, y=ay))
    a = _ref(tita)
    tt = t - t[0]
    x = 0.1 + 1.02 * (a[:, 0] + 0.004 * a[:, 0] ** 2 - 0.003 * a[:, 0] * a[:, 1]) + 0.01 * tt
    y = -0.05 + 0.99 * np.clip(-G * np.cos(tita + 0.02), -9.0, 9.0)
    np.testing.assert_allclose(got, np.column_stack([x, y]), atol=1e-12)


# --- clean runs -------------------------------------------------------------------------------

def test_clean_runs_fit_the_nominal_model_with_white_residuals_of_the_stated_variance():
    clean = vcases.clean_cases(2 * len(designs.DESIGNS), SEED)
    assert {c.design for c in clean} == set(designs.DESIGNS)
    for c in clean:
        a = _ref(c.tita)
        for k, axis in enumerate("xy"):
            sigma = np.sqrt(c.noise_var[k])
            coef, se, r = _fit([np.ones(c.n), a[:, k]], c.datos[:, k], sigma)
            dof = c.n - 2
            chi2 = np.sum(r**2) / sigma**2
            lo, hi = stats.chi2.ppf([ALPHA_CHI2 / 2, 1 - ALPHA_CHI2 / 2], dof)
            assert lo <= chi2 <= hi, (c.id, axis, chi2 / dof)
            rho1 = np.sum(r[1:] * r[:-1]) / np.sum(r * r)
            assert abs(rho1) * np.sqrt(c.n) < Z_PARAM, (c.id, axis, rho1)
            nom = c.truth["nominal"][axis]
            assert abs(coef[0] - nom["bias"]) < Z_PARAM * se[0], (c.id, axis)
            assert abs(coef[1] - (1 + nom["scale"])) < Z_PARAM * se[1], (c.id, axis)


def test_clean_runs_are_cheap_and_deterministic():
    a = vcases.clean_cases(11, SEED)
    b = vcases.clean_cases(11, SEED)
    assert all(c.n <= 2000 for c in a)
    assert [c.datos.tobytes() for c in a] == [c.datos.tobytes() for c in b]
    assert all(c.expected == () and c.size_sigma == {} for c in a)


# --- the set ----------------------------------------------------------------------------------

CATALOG = ("misalignment", "tilt_offset", "nonlinearity_k2", "cross_axis", "bias_drift",
           "bias_random_walk", "quantization", "saturation", "noise_level", "lowpass_lag",
           "lever_arm")


def test_the_set_covers_the_catalog_the_designs_and_outside_effects(vset):
    ids = [c.id for c in vset]
    assert len(ids) == len(set(ids))
    cat = [c for c in vset if c.kind == "catalog"]
    ooc = [c for c in vset if c.kind == "out_of_catalog"]
    assert 60 <= len(cat) + len(ooc) <= 100
    single = {c.expected[0] for c in cat if len(c.expected) == 1}
    for name in CATALOG:
        axes = ("both",) if name == "tilt_offset" else ("x", "y")
        assert all((name, a) in single for a in axes), name
    assert any(len(c.expected) == 2 for c in cat)
    for c in cat:
        for name, _ in c.expected:
            if name in ("bias_drift", "bias_random_walk", "lowpass_lag", "lever_arm"):
                assert c.t is not None, c.id
            if name == "lever_arm":
                assert c.design == "mujoco_sweep"
    labels = {e["name"] for c in ooc for e in c.truth["effects"]}
    assert {"cubic", "periodic_bias", "spikes", "bias_step", "hysteresis",
            "clock_drift", "transient", "two_tone", "box", "zero_g", "ringing",
            "drive_vibration", "frozen"} <= labels
    assert all(c.expected == () for c in ooc)
    assert {c.design for c in vset if c.kind == "clean"} == set(designs.DESIGNS)
    assert len({c.design for c in cat}) >= 8


def test_effect_sizes_land_in_their_stated_range(vset):
    for c in vset:
        for e in c.truth["effects"]:
            if e["name"] == "spikes":  # drawn per spike: 8-15 σ each, ≈ 0.3 % of samples
                amp = np.abs(e["params"]["amplitude_sigma"])
                assert amp.min() >= 8 and amp.max() <= 15
                assert e["params"]["count"] == max(3, round(0.003 * c.n))
                continue
            if e["name"] == "frozen":  # size = sqrt(frozen samples), a whole number of them
                assert e["params"]["length"] == round(e["target_sigma"] ** 2), c.id
                assert np.isclose(e["size_sigma"] ** 2, e["params"]["length"]), c.id
                continue
            lo, hi = vcases.EFFECTS[e["name"]].target_range
            assert lo - 1e-6 <= e["size_sigma"] <= hi + 1e-6, (c.id, e)
            assert abs(e["size_sigma"] - e["target_sigma"]) <= 1e-6 * e["target_sigma"], c.id


def test_deterministic_sizes_recomputed_here(vset):
    """size = ||(I - P) s|| / σ with P on [1, A_r]: recomputed from the truth parameters."""
    checked = 0
    for c in vset:
        if c.kind != "catalog" or len(c.expected) != 1 or c.design == "mujoco_sweep":
            continue
        (name, axis), e = c.expected[0], c.truth["effects"][0]
        k = 0 if axis in ("x", "both") else 1
        a = _ref(c.tita)
        scale = 1 + c.truth["nominal"]["xy"[k]]["scale"]
        p = e["params"]
        if name == "misalignment":
            s = scale * (_ref(c.tita + p["delta"])[:, k] - a[:, k])
        elif name == "nonlinearity_k2":
            s = scale * p["k2"] * a[:, k] ** 2
        elif name == "cross_axis":
            s = scale * p["k_ip"] * a[:, k] * a[:, 1 - k]
        elif name == "bias_drift":
            s = p["rate"] * (c.t - c.t[0])
        elif name == "saturation":
            s = scale * (np.clip(a[:, k], -p["limit"], p["limit"]) - a[:, k])
        elif name == "tilt_offset":
            s2 = [scale_k * (_ref(c.tita + p["delta"])[:, j] - a[:, j]) for j, scale_k in
                  enumerate(1 + c.truth["nominal"][ax]["scale"] for ax in "xy")]
            size = np.hypot(*[sizes.residual_size(s2[j], np.column_stack(
                [np.ones(c.n), a[:, j]]), np.sqrt(c.noise_var[j])) for j in range(2)])
            assert np.isclose(size, e["size_sigma"], rtol=1e-6), c.id
            checked += 1
            continue
        else:
            continue
        basis = np.column_stack([np.ones(c.n), a[:, k]])
        resid = s - basis @ np.linalg.lstsq(basis, s, rcond=None)[0]
        size = np.linalg.norm(resid) / np.sqrt(c.noise_var[k])
        assert np.isclose(size, e["size_sigma"], rtol=1e-6), (c.id, size, e["size_sigma"])
        checked += 1
    assert checked >= 20


def test_catalog_parameters_are_recovered_by_the_right_extended_fit(vset):
    """Fitting the true model (written here) finds the truth within 4.5 standard errors."""
    checked = 0
    for c in vset:
        if c.kind != "catalog" or len(c.expected) != 1:
            continue
        name, axis = c.expected[0]
        if name not in ("misalignment", "nonlinearity_k2", "cross_axis", "bias_drift"):
            continue
        k = "xy".index(axis)
        a = _ref(c.tita)
        scale = 1 + c.truth["nominal"][axis]["scale"]
        p = _truth(c, name)["params"]
        one, ai, ap = np.ones(c.n), a[:, k], a[:, 1 - k]
        if name == "misalignment":  # x: cos δ A_x + sin δ A_y;  y: cos δ A_y - sin δ A_x
            col, true = ap, scale * np.sin(p["delta"]) * (1 if k == 0 else -1)
        elif name == "nonlinearity_k2":
            col, true = ai**2, scale * p["k2"]
        elif name == "cross_axis":
            col, true = ai * ap, scale * p["k_ip"]
        else:
            col, true = c.t - c.t[0], p["rate"]
        coef, se, _ = _fit([one, ai, col], c.datos[:, k], np.sqrt(c.noise_var[k]))
        assert abs(coef[2] - true) < Z_PARAM * se[2], (c.id, coef[2], true, se[2])
        checked += 1
    assert checked >= 14


def test_noise_level_quantization_and_saturation_show_in_the_data(vset):
    for c in vset:
        for e in c.truth["effects"]:
            k = 0 if e["axis"] in ("x", "both") else 1
            y = c.datos[:, k]
            if e["name"] == "quantization":
                q = y / e["params"]["lsb"]
                np.testing.assert_allclose(q, np.round(q), atol=1e-9)
            elif e["name"] == "noise_level" and len(c.expected) == 1:
                a = _ref(c.tita)
                _, _, r = _fit([np.ones(c.n), a[:, k]], y, 1.0)
                dof = c.n - 2
                lo, hi = stats.chi2.ppf([ALPHA_CHI2 / 2, 1 - ALPHA_CHI2 / 2], dof)
                assert lo <= np.sum(r**2) / e["params"]["sigma2"] <= hi, c.id
            elif e["name"] == "saturation":
                nom = c.truth["nominal"]["xy"[k]]
                lim = nom["bias"] + (1 + nom["scale"]) * np.array([-1, 1]) * e["params"]["limit"]
                sd = np.sqrt(c.noise_var[k])
                assert y.max() <= lim[1] + 6 * sd and y.min() >= lim[0] - 6 * sd, c.id


# --- MuJoCo sweep -----------------------------------------------------------------------------

def test_mujoco_hinge_sites_read_the_course_convention():
    run = sweep.simulate(3000)
    assert np.std(run.omega) > 0.3 and np.std(run.alpha) > 0.3  # a varying-rate sweep
    err = np.abs(run.force - _ref(run.tita))
    assert err.max() < 1e-3
    # the rates are those of the encoder angle (central differences, O(h²))
    np.testing.assert_allclose(np.gradient(run.tita, run.t)[1:-1], run.omega[1:-1], atol=2e-3)


def test_mujoco_lever_arm_site_adds_centripetal_and_tangential_terms():
    arm = ((0.08, -0.05), (-0.03, 0.06))
    run = sweep.simulate(1500, arm)
    w2, al = run.omega**2, run.alpha
    (px, pz), (qx, qz) = arm
    dx = run.arm_force[:, 0] - run.force[:, 0]
    dy = run.arm_force[:, 1] - run.force[:, 1]
    np.testing.assert_allclose(dx, -w2 * px + al * pz, atol=1e-9)  # -ω²·p + α ŷ×p on x
    np.testing.assert_allclose(dy, w2 * qz + al * qx, atol=1e-9)   # the same on -z
    assert np.max(np.abs(w2 * px)) > 0.1  # the centripetal term is there and large
    only_centripetal = sweep.simulate(1500, ((0.1, 0.0), (0.0, 0.0)))
    np.testing.assert_allclose(only_centripetal.arm_force[:, 0] - only_centripetal.force[:, 0],
                               -only_centripetal.omega**2 * 0.1, atol=1e-9)


def test_lever_arm_cases_come_from_the_simulated_sensors(vset):
    for c in (c for c in vset if ("lever_arm", "x") in c.expected
              or ("lever_arm", "y") in c.expected):
        e = _truth(c, "lever_arm")
        k = "xy".index(e["axis"])
        arm = [(0.0, 0.0), (0.0, 0.0)]
        arm[k] = (e["params"]["pos_x"], e["params"]["pos_z"])
        run = sweep.simulate(c.n, tuple(arm))
        np.testing.assert_array_equal(c.tita, run.tita)
        w2, al = run.omega**2, run.alpha
        px, pz = arm[k]
        lever = (-w2 * px + al * pz) if k == 0 else (w2 * pz + al * px)
        nom = c.truth["nominal"]["xy"[k]]
        expect = nom["bias"] + (1 + nom["scale"]) * (_ref(c.tita)[:, k] + lever)
        if not any(n == "bias_drift" and a == e["axis"] for n, a in c.expected):
            r = c.datos[:, k] - expect
            sigma = np.sqrt(c.noise_var[k])
            lo, hi = stats.chi2.ppf([ALPHA_CHI2 / 2, 1 - ALPHA_CHI2 / 2], c.n)
            assert lo <= np.sum(r**2) / sigma**2 <= hi, c.id


# --- random effects: formulas against Monte Carlo ---------------------------------------------

def test_expected_lr_of_a_random_walk_matches_monte_carlo():
    """Mean over R = 300 runs of the exact LR (true q vs q = 0) of the differenced series,
    computed in the sine basis that diagonalises ``DDᵀ``, against :func:`sizes.walk_lr`,
    within 4.5 standard errors of the mean."""
    n, dt, s2, q, reps = 1000, 0.01, 0.25, 0.3, 300
    rng = np.random.default_rng(SEED)
    f0 = s2 * (2 - 2 * np.cos(sizes.walk_frequencies(n)))
    f1 = f0 + q * q * dt
    lrs = []
    for _ in range(reps):
        y = effects.walk(rng.standard_normal(n), np.full(n - 1, dt), q)
        y = y + np.sqrt(s2) * rng.standard_normal(n)
        z2 = scipy.fft.dst(np.diff(y), type=1, norm="ortho") ** 2
        lrs.append(np.sum(np.log(f0 / f1) + z2 / f0 - z2 / f1))
    lrs = np.array(lrs)
    expected = sizes.walk_lr(q, dt, s2, n)
    assert abs(lrs.mean() - expected) < Z_PARAM * lrs.std() / np.sqrt(reps), (
        lrs.mean(), expected)


def test_flicker_has_a_one_over_f_spectrum():
    n, h, reps = 2048, 0.2, 400
    rng = np.random.default_rng(SEED)
    per = np.zeros(n // 2 + 1)
    for _ in range(reps):
        x = effects.flicker(rng.standard_normal((n // 2 + 1, 2)), h, n)
        per += np.abs(np.fft.rfft(x)) ** 2 / n
    per /= reps
    j = np.arange(1, n // 2)
    ratio = per[j] / (h / (2 * np.pi * j / n))
    # each bin is a mean of R exponentials: std 1/sqrt(R); bands of 64 bins average them
    bands = ratio[: (ratio.size // 64) * 64].reshape(-1, 64).mean(axis=1)
    assert np.all(np.abs(bands - 1) < Z_PARAM / np.sqrt(reps * 64)), bands


# --- determinism and files --------------------------------------------------------------------

def _digest(cs):
    h = hashlib.sha256()
    for c in cs:
        h.update(c.id.encode())
        h.update(c.datos.tobytes())
        h.update(c.tita.tobytes())
    return h.hexdigest()


def test_same_seed_same_bytes_other_seed_other_bytes(vset):
    again = vcases.catalog_cases(SEED) + vcases.out_of_catalog_cases(SEED)
    assert _digest(again) == _digest([c for c in vset if c.kind != "clean"])
    clean = [c for c in vset if c.kind == "clean"]
    assert _digest(vcases.clean_cases(len(clean), SEED)) == _digest(clean)
    assert _digest(vcases.clean_cases(len(clean), SEED + 1)) != _digest(clean)
    # the MuJoCo sweep itself, outside its cache
    a, b = sweep.simulate.__wrapped__(500), sweep.simulate.__wrapped__(500)
    assert a.force.tobytes() == b.force.tobytes() and a.tita.tobytes() == b.tita.tobytes()


def test_generate_writes_course_files_and_refuses_to_overwrite(tmp_path, vset, capsys):
    some = [c for c in vset if c.design in ("held_poses", "mujoco_sweep")][:4]
    out = tmp_path / "set"
    write_set(some, out, SEED)
    for c in some:
        mat = scipy.io.loadmat(out / f"{c.id}.mat")
        assert mat["tita"].shape == (c.n, 1) and mat["datos"].shape == (c.n, 2)
        assert ("t" in mat) == (c.t is not None)
        np.testing.assert_array_equal(mat["datos"], c.datos)
    truth = json.loads((out / "truth.json").read_text())
    assert set(truth["cases"]) == {c.id for c in some}
    assert truth["cases"][some[0].id]["noise_var"] == [0.25, 0.64]
    first = {p.name: p.read_bytes() for p in out.iterdir()}
    with pytest.raises(FileExistsError):
        write_set(some, out, SEED)
    assert generate_main([str(out), "--clean", "0"]) == 1
    assert "--force" in capsys.readouterr().err
    write_set(some, out, SEED, force=True)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == first  # same seed, same bytes


# --- the scoring rules (stub analyses; the acceptance test of analyze_gap lives elsewhere) ----

def _analysis(named=(), ties=(), verdict="explained"):
    return SimpleNamespace(effects=[SimpleNamespace(name=n, axis=a) for n, a in named],
                           not_identifiable=[{"names": list(t), "reason": ""} for t in ties],
                           verdict=verdict, gap_after_fit={})


def test_matching_counts_ties_and_rejects_extras():
    tie = [{"names": ["misalignment", "tilt_offset"]}]
    assert matches([("tilt_offset", "both")], [("tilt_offset", "both")])
    assert matches([("tilt_offset", "both")], [("misalignment", "x"), ("misalignment", "y")], tie)
    assert not matches([("tilt_offset", "both")], [("misalignment", "x")], [])
    lag = [{"names": ["lowpass_lag", "misalignment"]}]
    assert matches([("lowpass_lag", "x"), ("bias_drift", "x")],
                   [("misalignment", "x"), ("bias_drift", "x")], lag)
    assert not matches([("lowpass_lag", "x")], [("misalignment", "y")], lag)  # wrong axis
    assert not matches([("misalignment", "x")], [("misalignment", "x"), ("noise_level", "x")])
    assert not matches([("misalignment", "x")], [])
    assert matches([], [])


def test_score_applies_the_rules_per_kind(vset):
    by_kind = {k: next(c for c in vset if c.kind == k) for k in vcases.KINDS}
    cat = by_kind["catalog"]
    assert judge(cat, _analysis(cat.expected))["right"]
    assert not judge(cat, _analysis(cat.expected, verdict="unexplained"))["right"]
    assert judge(by_kind["clean"], _analysis(verdict="nothing_detected"))["right"]
    assert not judge(by_kind["clean"], _analysis([("noise_level", "x")], verdict="explained")
                     )["right"]
    assert judge(by_kind["out_of_catalog"], _analysis(verdict="unexplained"))["right"]
    assert not judge(by_kind["out_of_catalog"], _analysis(verdict=None))["right"]
    # score() takes any analyze callable: a stub that knows the answers scores 100 %
    answers = {c.id: _analysis(c.expected, verdict={"catalog": "explained",
                                                    "clean": "nothing_detected",
                                                    "out_of_catalog": "unexplained"}[c.kind])
               for c in vset}
    result = score(vset, lambda c: answers[c.id])
    assert all(r["right"] for r in result.rows)
    assert {s["kind"] for s in result.summary("kind")} == set(vcases.KINDS)
    assert "| id | kind |" in result.to_markdown()
    assert max_wrong(200, 0.005) >= 1 and max_wrong(200, 0.0) == 0
