"""The effect catalog on the bench: terms, MjSpec edits, ``--effect``, truth.json round trip.

Injection tests put ONE effect into a noise-free run and project the reading error
``A_m - (bias + (1 + scale)·A_r)`` on the signature basis of the catalog
(1, sin θ, cos θ, sin 2θ, cos 2θ, t): only the effect's own signature may move, by the amount
its first-order model predicts, and the other axis must not move at all. Noise-free runs make
these exact (tolerances are float round-off, 1e-9 on O(10) m/s² signals), except where the
catalog's model is first order (misalignment: the second order term δ²/2·g is bounded below).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.io

from bench.cli import main
from bench.effects import (
    CATALOG,
    EFFECT_NAMES,
    BiasDrift,
    BiasRandomWalk,
    CrossAxis,
    EffectSpec,
    LowpassLag,
    NonlinearityK2,
    Quantization,
    apply_effects,
    effects_from_truth,
    parse_effect_option,
)
from bench.sensors import AxisErrors, SensorContext, SensorErrorModel
from bench.tilt import CalibrationConfig, SweepProfile, ThetaDesign, generate_calibration
from calib.conventions import reference_accel
from calib.files.course import DataError
from calib.filters import lowpass

G = 9.8
BIAS, SCALE = (0.07, -0.04), (-0.02, 0.015)


def _noise_free() -> SensorErrorModel:
    return SensorErrorModel.from_pairs(BIAS, SCALE, (0.0, 0.0))


def _static(effects, count: int = 721) -> tuple:
    cfg = CalibrationConfig(theta=ThetaDesign(count=count, stop=2 * np.pi * (1 - 1 / count)),
                            sensor=_noise_free())
    return generate_calibration(apply_effects(cfg, effects), 1)


def _sweep(effects, kind: str = "constant", duration: float = 10.0) -> tuple:
    cfg = CalibrationConfig(mode="sweep", sweep=SweepProfile(kind=kind, duration=duration),
                            sensor=_noise_free())
    return generate_calibration(apply_effects(cfg, effects), 1)


def _error(run) -> np.ndarray:
    """Reading minus the nominal model at the encoder angle (N, 2), m/s²."""
    a_r = reference_accel(run.tita, G)
    return run.datos - (np.array(BIAS) + (1 + np.array(SCALE)) * a_r)


def _signature_fit(run, err: np.ndarray) -> dict[str, float]:
    """Least-squares coefficients of ``err`` on the catalog signature basis."""
    th = run.tita
    t = run.t if run.t is not None else np.arange(th.size, dtype=float)
    basis = {"1": np.ones_like(th), "sin": np.sin(th), "cos": np.cos(th),
             "sin2": np.sin(2 * th), "cos2": np.cos(2 * th), "t": t - t.mean()}
    H = np.column_stack(list(basis.values()))
    coef, *_ = np.linalg.lstsq(H, err, rcond=None)
    return dict(zip(basis, coef, strict=True))


def _only(coef: dict[str, float], expected: dict[str, float], atol: float = 1e-9) -> None:
    for name, value in coef.items():
        assert value == pytest.approx(expected.get(name, 0.0), abs=atol), name


# ------------------------------------------------------------------------ injection

@pytest.mark.parametrize("axis", ["x", "y"])
def test_injection_nonlinearity_k2_moves_only_cos2theta(axis):
    k = "xy".index(axis)
    k2 = 1e-3
    run = _static([EffectSpec("nonlinearity_k2", axis, {"k2": k2})])
    err = _error(run)
    # a_x² = g²(1 - cos 2θ)/2, a_y² = g²(1 + cos 2θ)/2, scaled by (1 + scale)
    amp = (1 + SCALE[k]) * k2 * G**2 / 2
    _only(_signature_fit(run, err[:, k]), {"1": amp, "cos2": -amp if axis == "x" else amp})
    np.testing.assert_allclose(err[:, 1 - k], 0.0, atol=1e-9)


@pytest.mark.parametrize("axis", ["x", "y"])
def test_injection_cross_axis_moves_only_sin2theta(axis):
    k = "xy".index(axis)
    kip = -2e-3
    run = _static([EffectSpec("cross_axis", axis, {"k_ip": kip})])
    err = _error(run)
    amp = (1 + SCALE[k]) * kip * G**2 / 2  # a_x·a_y = g² sin θ cos θ = g² sin 2θ / 2
    _only(_signature_fit(run, err[:, k]), {"sin2": amp})
    np.testing.assert_allclose(err[:, 1 - k], 0.0, atol=1e-9)


@pytest.mark.parametrize("axis", ["x", "y"])
def test_injection_misalignment_moves_only_the_other_axis_phase(axis):
    k = "xy".index(axis)
    delta = 0.01
    run = _static([EffectSpec("misalignment", axis, {"delta": delta})])
    err = _error(run)
    # x: -g sin(θ+δ) = A_rx·cos δ - g cos θ·sin δ;  y: -g cos(θ+δ) = A_ry·cos δ + g sin θ·sin δ
    # (catalog first order: x + δ·A_ry, y - δ·A_rx; the cos δ part is a scale change δ²/2)
    gain = (1 + SCALE[k]) * G
    if axis == "x":
        expected = {"cos": -gain * np.sin(delta), "sin": gain * (1 - np.cos(delta))}
    else:
        expected = {"sin": gain * np.sin(delta), "cos": gain * (1 - np.cos(delta))}
    _only(_signature_fit(run, err[:, k]), expected)
    np.testing.assert_allclose(err[:, 1 - k], 0.0, atol=1e-9)


def test_injection_tilt_offset_moves_both_axes_like_a_common_misalignment():
    delta = -0.015
    a = _static([EffectSpec("tilt_offset", "both", {"delta": delta})])
    b = _static([EffectSpec("misalignment", "x", {"delta": delta}),
                 EffectSpec("misalignment", "y", {"delta": delta})])
    np.testing.assert_allclose(a.datos, b.datos, atol=1e-12)
    np.testing.assert_allclose(a.a_true, reference_accel(a.tita + delta), atol=1e-9)


@pytest.mark.parametrize("axis", ["x", "y"])
def test_injection_bias_drift_moves_only_the_time_signature(axis):
    k = "xy".index(axis)
    rate = 4e-3  # m/s² per s, additive at the bias level (catalog: bias + rate·(t - t0))
    run = _sweep([EffectSpec("bias_drift", axis, {"rate": rate})])
    err = _error(run)
    np.testing.assert_allclose(err[:, k], rate * (run.t - run.t[0]), atol=1e-9)
    np.testing.assert_allclose(err[:, 1 - k], 0.0, atol=1e-9)
    per_sample = _static([EffectSpec("bias_drift", axis, {"rate_per_sample": 1e-5})])
    np.testing.assert_allclose(_error(per_sample)[:, k], 1e-5 * np.arange(per_sample.tita.size),
                               atol=1e-9)


def test_injection_bias_random_walk_increments_have_the_stated_variance():
    """Increments of the walk are q·√Δt·w: their variance / (q²Δt) ~ χ²_n / n.

    With n = 20000 increments, |ratio - 1| ≤ 4·√(2/n) holds with probability 1 - 6e-5.
    """
    q = 0.02
    term = BiasRandomWalk(q=q)
    t = np.arange(20001) * 0.01
    ctx = SensorContext(np.zeros((t.size, 2)), t, 0)
    walk = term.walk(t.size, ctx, np.random.default_rng(7))
    assert walk[0] == 0.0
    ratio = np.var(np.diff(walk), mean=0.0) / (q * q * 0.01)
    assert abs(ratio - 1) <= 4 * np.sqrt(2 / 20000)
    run = _sweep([EffectSpec("bias_random_walk", "y", {"q": q})])
    np.testing.assert_allclose(_error(run)[:, 0], 0.0, atol=1e-9)  # x untouched
    assert np.std(np.diff(_error(run)[:, 1])) > 0


def test_injection_quantization_rounds_the_reading_only():
    lsb = 0.05
    run = _static([EffectSpec("quantization", "x", {"lsb": lsb})])
    err = _error(run)
    assert np.all(np.abs(err[:, 0]) <= lsb / 2 + 1e-12)
    np.testing.assert_allclose(run.datos[:, 0] / lsb, np.round(run.datos[:, 0] / lsb),
                               atol=1e-9)
    np.testing.assert_allclose(err[:, 1], 0.0, atol=1e-9)


def test_injection_lowpass_lag_is_the_first_order_response_of_the_sweep():
    """At constant rate ω the low-passed A_ry is -g/√(1+(ωτ)²)·cos(θ - atan ωτ) (steady state).

    Late samples only (t > 2 s ≫ τ and the servo time constant 0.1 s); the first-order-hold
    discretization is exact for inputs linear between samples, its error on a sinusoid is
    ≲ h²ω²g/12 ≈ 3e-5 m/s² at h = 0.01 s, ω = 0.63 rad/s.
    """
    tau, duration = 0.05, 10.0
    run = _sweep([EffectSpec("lowpass_lag", "y", {"tau": tau})], duration=duration)
    plain = _sweep([], duration=duration)
    np.testing.assert_array_equal(run.datos[:, 0], plain.datos[:, 0])
    w = 2 * np.pi / duration
    late = run.t > 2.0
    expect = BIAS[1] + (1 + SCALE[1]) * (-G / np.sqrt(1 + (w * tau) ** 2)
                                         * np.cos(run.tita - np.arctan(w * tau)))
    np.testing.assert_allclose(run.datos[late, 1], expect[late], atol=1e-4)
    assert np.max(np.abs(run.datos[late, 1] - plain.datos[late, 1])) > 100 * 1e-4


def test_injection_saturation_clips_the_true_specific_force():
    limit = 7.0
    run = _static([EffectSpec("saturation", "y", {"limit": limit})])
    assert np.max(np.abs(run.a_true[:, 1])) == pytest.approx(limit)
    clipped = np.abs(reference_accel(run.tita)[:, 1]) > limit
    assert clipped.any()
    np.testing.assert_allclose(_error(run)[~clipped, 1], 0.0, atol=1e-9)
    np.testing.assert_allclose(run.a_true[:, 0], reference_accel(run.tita)[:, 0], atol=1e-9)


def test_injection_gravity_mismatch_is_a_common_scale():
    run = _static([EffectSpec("gravity_mismatch", "both", {"g": 9.81})])
    np.testing.assert_allclose(run.a_true, reference_accel(run.tita) * 9.81 / 9.8, atol=1e-9)


def test_injection_noise_level_sets_the_variance():
    """Sample variance of N normals: |s²/σ² - 1| ≤ 4·√(2/N)."""
    cfg = CalibrationConfig(theta=ThetaDesign(count=20001), sensor=_noise_free())
    run = generate_calibration(apply_effects(cfg, [EffectSpec("noise_level", "x",
                                                              {"sigma2": 0.49})]), 3)
    err = _error(run)
    assert abs(np.var(err[:, 0]) / 0.49 - 1) <= 4 * np.sqrt(2 / 20001)
    np.testing.assert_allclose(err[:, 1], 0.0, atol=1e-9)


def test_lever_arm_is_dynamic_and_rejected_for_static_runs():
    run = _sweep([EffectSpec("lever_arm", "x", {"pos_x": 0.2, "pos_z": 0.0})], kind="accel",
                 duration=4.0)
    plain = _sweep([], kind="accel", duration=4.0)
    assert np.max(np.abs(run.a_true[:, 0] - plain.a_true[:, 0])) > 0.1
    np.testing.assert_array_equal(run.a_true[:, 1], plain.a_true[:, 1])
    with pytest.raises(DataError, match="sweep"):
        _static([EffectSpec("lever_arm", "x", {"pos_x": 0.2})])


# --------------------------------------------------------------------------- terms

def test_lowpass_is_exact_for_ramps_and_steps():
    t = np.linspace(0, 1, 101)
    np.testing.assert_allclose(lowpass(2 * t, t, 0.01)[50:], 2 * t[50:] - 0.02, atol=1e-12)
    step = np.where(t > 0, 1.0, 0.0)
    # first-order hold turns the step into a ramp over the first interval: after it,
    # y = 1 - (τ/h)(1 - e^{-h/τ})·e^{-(t - h)/τ}
    h, tau = t[1], 0.1
    y = lowpass(step, t, tau)
    expect = 1 - tau / h * (1 - np.exp(-h / tau)) * np.exp(-(t[1:] - h) / tau)
    np.testing.assert_allclose(y[1:], expect, atol=1e-12)


@pytest.mark.parametrize("term", [NonlinearityK2(1e-3), CrossAxis(-2e-3), BiasDrift(rate=1e-3),
                                  BiasDrift(rate_per_sample=1e-6), BiasRandomWalk(q=0.01),
                                  BiasRandomWalk(q_per_sample=0.001), Quantization(0.01),
                                  LowpassLag(0.02)])
def test_terms_round_trip_through_json(term):
    ax = AxisErrors(0.1, -0.02, 0.25, (term,))
    back = AxisErrors.from_dict(json.loads(json.dumps(ax.to_dict())))
    assert back == ax


def test_term_validation():
    with pytest.raises(ValueError):
        BiasDrift()
    with pytest.raises(ValueError):
        BiasDrift(rate=1.0, rate_per_sample=1.0)
    with pytest.raises(ValueError):
        Quantization(0.0)
    with pytest.raises(ValueError):
        LowpassLag(-1.0)
    with pytest.raises(ValueError, match="sample times"):
        LowpassLag(0.1).apply(np.zeros(3), SensorContext(np.zeros((3, 2)), None, 0),
                              np.random.default_rng(0))


# ----------------------------------------------------------------- parse and apply

def test_catalog_matches_design_vocabulary():
    assert EFFECT_NAMES == ("noise_level", "misalignment", "tilt_offset", "nonlinearity_k2",
                            "cross_axis", "bias_drift", "bias_random_walk", "quantization",
                            "saturation", "lowpass_lag", "lever_arm", "gravity_mismatch")
    assert {n for n, e in CATALOG.items() if e.timing == "yes"} == {"lowpass_lag", "lever_arm"}


@pytest.mark.parametrize("text, expected", [
    ("misalignment:x:delta=0.02", EffectSpec("misalignment", "x", {"delta": 0.02})),
    (" tilt_offset : both : delta = -1e-2 ", EffectSpec("tilt_offset", "both", {"delta": -0.01})),
    ("lever_arm:y:pos_x=0.2,pos_z=0.05",
     EffectSpec("lever_arm", "y", {"pos_x": 0.2, "pos_z": 0.05})),
    ("bias_drift:x:rate_per_sample=1e-5", EffectSpec("bias_drift", "x",
                                                      {"rate_per_sample": 1e-5})),
    ("gravity_mismatch:both:g=9.81", EffectSpec("gravity_mismatch", "both", {"g": 9.81})),
])
def test_parse_effect_option(text, expected):
    e = parse_effect_option(text)
    assert e == expected
    assert parse_effect_option(e.option()) == e


@pytest.mark.parametrize("text, words", [
    ("misalignment:x", "NAME:AXIS"),
    ("wobble:x:a=1", "unknown effect"),
    ("misalignment:z:delta=0.1", "axis"),
    ("tilt_offset:x:delta=0.1", "axis"),
    ("misalignment:x:angle=0.1", "unknown parameter"),
    ("misalignment:x:delta=abc", "not a number"),
    ("misalignment:x:delta", "KEY=VALUE"),
    ("quantization:x:lsb=0", "positive"),
    ("bias_drift:x:rate=1,rate_per_sample=1", "exactly one"),
    ("misalignment:x:delta=nan", "finite"),
])
def test_parse_effect_option_errors_name_the_problem(text, words):
    with pytest.raises(DataError, match=words) as info:
        parse_effect_option(text)
    assert "--effect" in str(info.value)


def test_apply_effects_sets_fields_and_checks_timing():
    cfg = CalibrationConfig(sensor=_noise_free())
    out = apply_effects(cfg, [parse_effect_option(s) for s in (
        "misalignment:y:delta=0.01", "tilt_offset:both:delta=0.002", "saturation:x:limit=8",
        "gravity_mismatch:both:g=9.79", "noise_level:y:sigma2=0.3", "quantization:x:lsb=0.1",
        "nonlinearity_k2:x:k2=1e-3")])
    assert out.table.misalignment == (0.0, 0.01) and out.table.tilt_offset == 0.002
    assert out.table.cutoff == (8.0, 0.0) and out.g == 9.79
    assert out.sensor.y.noise_var == 0.3
    assert [t.name for t in out.sensor.x.terms] == ["nonlinearity_k2", "quantization"]
    for text in ("lowpass_lag:x:tau=0.1", "lever_arm:x:pos_x=0.1", "bias_drift:x:rate=1e-3",
                 "bias_random_walk:y:q=0.1"):
        with pytest.raises(DataError, match="sweep"):
            apply_effects(cfg, [parse_effect_option(text)])


def _key(e: EffectSpec) -> tuple[str, str]:
    return e.name, e.axis


def test_effects_round_trip_through_truth():
    effects = [parse_effect_option(s) for s in (
        "tilt_offset:both:delta=0.002", "misalignment:y:delta=0.01", "saturation:x:limit=8",
        "lever_arm:x:pos_x=0.1,pos_z=-0.05", "nonlinearity_k2:x:k2=0.001",
        "lowpass_lag:y:tau=0.02", "bias_random_walk:y:q=0.01")]
    cfg = apply_effects(CalibrationConfig(mode="sweep", sensor=_noise_free()), effects)
    truth = json.loads(json.dumps(cfg.to_dict()))
    back = effects_from_truth(truth)
    assert sorted(back, key=_key) == sorted(effects, key=_key)


# ------------------------------------------------------------------------- CLI

def test_generate_with_effects_same_seed_same_bytes(tmp_path):
    args = ["generate", "calibration", "--mode", "sweep", "--duration", "4", "--sweep-profile",
            "sine", "--cycles", "2", "--effect", "lever_arm:x:pos_x=0.2", "--effect",
            "bias_random_walk:y:q=0.05", "--effect", "quantization:y:lsb=0.05", "--seed", "3"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 0
    assert main([*args, "--out", str(tmp_path / "b")]) == 0
    for name in ("ensayo.mat", "truth.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    args[-1] = "4"
    assert main([*args, "--out", str(tmp_path / "c")]) == 0
    assert (tmp_path / "a/ensayo.mat").read_bytes() != (tmp_path / "c/ensayo.mat").read_bytes()
    truth = json.loads((tmp_path / "a" / "truth.json").read_text())
    assert truth["table"]["lever_arm"][0] == [0.2, 0.0]
    assert [t["name"] for t in truth["sensor"]["y"]["terms"]] == ["bias_random_walk",
                                                                  "quantization"]
    found = {(e.name, e.axis) for e in effects_from_truth(truth)}
    assert found == {("lever_arm", "x"), ("bias_random_walk", "y"), ("quantization", "y")}


def test_generate_bad_effect_is_a_clear_error(tmp_path, capsys):
    assert main(["generate", "calibration", "--effect", "misalignment:q:delta=1", "--out",
                 str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "--effect" in err and "axis" in err
    assert main(["generate", "calibration", "--effect", "lowpass_lag:x:tau=0.1", "--out",
                 str(tmp_path)]) == 2
    assert "--mode sweep" in capsys.readouterr().err


@pytest.mark.parametrize("design", [
    ["--count", "1000"],                                          # full turn, uniform
    ["--positions", "12", "--per-position", "80"],                # discrete held positions
    ["--theta-range", "0.3,2.0", "--count", "1000"],              # partial
    ["--theta-list", "0.1,0.5,0.6,2.5,2.6,4.0,6.0"],              # non-uniform
    ["--mode", "sweep", "--sweep-profile", "accel", "--duration", "10"],  # non-uniform in time
    ["--mode", "sweep", "--sweep-profile", "updown", "--duration", "10", "--cycles", "1"],
    ["--mode", "sweep", "--sweep-profile", "sine", "--duration", "10", "--cycles", "3"],
])
def test_generate_all_theta_designs_with_an_effect(tmp_path, design):
    assert main(["generate", "calibration", *design, "--effect", "cross_axis:x:k_ip=0.001",
                 "--out", str(tmp_path)]) == 0
    mat = scipy.io.loadmat(tmp_path / "ensayo.mat")
    tita = mat["tita"].ravel()
    assert tita.size == mat["datos"].shape[0] >= 7
    if "updown" in design:
        turn = int(np.argmax(tita))
        assert 0 < turn < tita.size - 1 and tita[-1] < tita[turn] - 1.0
    if "sine" in design:
        assert np.sum(np.diff(np.sign(np.diff(tita))) != 0) >= 5  # oscillates
    if "--positions" in design:
        assert np.unique(tita).size == 12


def test_bounded_caches_survive_eviction_during_one_request(monkeypatch):
    """A request for more columns than a cache holds evicts entries of the same request
    (a walk profile in the DCT basis on a lever-arm run once raised KeyError): the answer
    must not depend on the cache sizes."""
    from calib.effects import engine
    from calib.files.course import Ensayo
    from calib.gap import analyze_gap

    rng = np.random.default_rng(4)
    n = 1500
    t = np.arange(n) / 100.0
    th = 2.0 * np.sin(2 * np.pi * t / 7.5) + 0.5 * t
    y = np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)]) + rng.normal(0, 0.5, (n, 2))
    y[:, 0] += np.cumsum(rng.normal(0.0, 0.02, n))
    ens = Ensayo(th, y, t)
    full = analyze_gap(ens, [0.25, 0.25])
    original = engine._LRU.__init__
    monkeypatch.setattr(engine._LRU, "__init__",
                        lambda self, size: original(self, min(size, 2)))
    tiny = analyze_gap(ens, [0.25, 0.25])
    assert tiny.named == full.named and tiny.verdict == full.verdict
    np.testing.assert_allclose(tiny.final.params, full.final.params, rtol=1e-6, atol=1e-12)
