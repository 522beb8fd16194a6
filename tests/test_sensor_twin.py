"""The twin of a measured sensor (:mod:`bench.sensor_twin`, :class:`bench.terms.BiasInstability`)
and the closed loop: ``tiltbench noise``'s library call on static logs simulated with the
bench's own sensor terms recovers each term inside its interval at the stated rate.

Monte Carlo bands (R runs, fixed seeds): coverage p within ``p ± 4·sqrt(p(1−p)/R)``; a false
"resolved" rate at most ``α + 4·sqrt(α(1−α)/R)``; a mean of R draws with predicted standard
deviation sd within ``4·sd/sqrt(R)`` of its expectation.
"""

from __future__ import annotations

import allantools
import numpy as np
import pytest

from bench.sensor_twin import (
    calibration_pairs,
    make_static_run,
    twin_axis,
    twin_sensor,
    twin_truth,
)
from bench.sensors import AxisErrors, SensorErrorModel
from bench.terms import BiasInstability, BiasRandomWalk, Quantization
from bench.tilt import static_readings
from calib.conventions import G
from calib.noise.allan import characterize_noise
from calib.noise.allan_model import FLICKER_FLOOR, TERM_NAMES, allan_moments, avar_covariance
from calib.noise.sensor_profile import NoiseTerm, SensorProfile


def alpha_fp_limit(r: int, alpha: float = 0.05) -> float:
    """Highest rate of "resolved" that chance allows at α over r runs: α + 4·sqrt(α(1−α)/r)."""
    return alpha + 4 * np.sqrt(alpha * (1 - alpha) / r)


SEED = 20261127
RATE = 100.0


def term(v: float) -> NoiseTerm:
    return NoiseTerm(value=v, interval=(0.9 * v, 1.1 * v), tau_range=(0.01, 10.0))


def profile(**kw) -> SensorProfile:
    base = dict(sample_rate=RATE, white_noise_density=(term(2e-3), term(3e-3)),
                bias_instability=(term(1.5e-3), None), rate_random_walk=(term(5e-4), None),
                quantization_step=(None, 0.01))
    base.update(kw)
    return SensorProfile(**base)


def test_profile_maps_onto_bench_terms():
    """N → white variance (N·√fs)² at the run's rate; B → BiasInstability(b = B); K → walk
    with q_per_sample = K/√fs; Δ → Quantization; null terms left out."""
    sensor = twin_sensor(profile(), rate=50.0)
    x, y = sensor.x, sensor.y
    assert x.noise_var == pytest.approx((2e-3 * np.sqrt(50.0)) ** 2)
    assert y.noise_var == pytest.approx((3e-3 * np.sqrt(50.0)) ** 2)
    assert x.terms == (BiasInstability(b=1.5e-3), BiasRandomWalk(q_per_sample=5e-4 / np.sqrt(50)))
    assert y.terms == (Quantization(lsb=0.01),)
    assert (x.bias, x.scale, y.bias, y.scale) == (0.0, 0.0, 0.0, 0.0)
    assert twin_sensor(profile()).x.noise_var == pytest.approx((2e-3 * 10) ** 2)
    assert SensorErrorModel.from_dict(sensor.to_dict()) == sensor  # truth.json round trip


def test_calibration_comes_from_the_profile():
    cal = {"param_names": ["bias_x", "scale_x", "bias_y", "scale_y"],
           "params": [0.07, -0.03, -0.02, 0.01], "cov": np.eye(4).tolist()}
    prof = profile(calibration=cal)
    assert calibration_pairs(prof) == ((0.07, -0.02), (-0.03, 0.01))
    s = twin_sensor(prof, bias=(9, 9), scale=(9, 9))
    assert (s.x.bias, s.x.scale, s.y.bias, s.y.scale) == (0.07, -0.03, -0.02, 0.01)
    assert calibration_pairs(profile(calibration={"bias": [1, 2], "scale": [3, 4]})) == (
        (1.0, 2.0), (3.0, 4.0))
    s = twin_sensor(profile(), bias=(0.1, 0.2), scale=(0.0, 0.05))  # no calibration: options
    assert (s.x.bias, s.y.scale) == (0.1, 0.05)
    rec = twin_truth(prof, 50.0, "sensor.json")
    assert rec["bias_instability"] == [1.5e-3, None]
    assert rec["calibration"] == {"bias": [0.07, -0.02], "scale": [-0.03, 0.01]}


def test_bias_instability_has_the_flat_floor():
    """R = 200 flicker paths of n = 4096 samples: the mean Allan variance at every octave is
    the exact moment B²·X_flicker (band 4·sd/√R), and on 16 ≤ m ≤ n/32 that is the IEEE floor
    (0.664·B)² within 1 % — a flat ADEV floor at 0.664·B."""
    n, r, b = 4096, 200, 2e-3
    rng = np.random.default_rng(SEED)
    term_b = BiasInstability(b=b)
    ms = tuple(2 ** k for k in range(11))
    s = np.array([allantools.oadev(term_b.path(n, rng), rate=1.0, data_type="freq",
                                   taus=np.array(ms, float))[1] ** 2 for _ in range(r)])
    design, tensor = allan_moments(n, ms)
    theta = np.array([0.0, b * b, 0.0])
    sd = np.sqrt(np.diag(avar_covariance(tensor, theta)))
    assert np.all(np.abs(s.mean(0) - design[:, 1] * b * b) <= 4 * sd / np.sqrt(r))
    m = np.array(ms)
    mid = (m >= 16) & (m <= n / 32)
    np.testing.assert_allclose(design[mid, 1] * b * b, (FLICKER_FLOOR * b) ** 2, rtol=0.01)
    assert term_b.to_dict() == {"b": b}
    with pytest.raises(ValueError, match="b must be >= 0"):
        BiasInstability(b=-1.0)


def test_static_run_is_seeded_and_reads_gravity():
    prof = profile(calibration={"bias": [0.05, -0.02], "scale": [0.0, 0.0]})
    sensor = twin_sensor(prof)
    a = make_static_run(sensor, 20.0, RATE, 0.3, seed=5, twin=twin_truth(prof, RATE))
    b = make_static_run(sensor, 20.0, RATE, 0.3, seed=5)
    c = make_static_run(sensor, 20.0, RATE, 0.3, seed=6)
    assert a.datos.tobytes() == b.datos.tobytes()
    assert a.datos.tobytes() != c.datos.tobytes()
    assert a.t.size == 2000 and a.t[1] == pytest.approx(0.01)
    np.testing.assert_allclose(a.a_true[0], [-G * np.sin(0.3), -G * np.cos(0.3)], atol=1e-9)
    # mean reading: true force + bias, within the noise of a 20 s mean (white + walk + flicker)
    assert np.abs(a.datos.mean(0) - (a.a_true[0] + [0.05, -0.02])).max() < 0.02
    assert a.truth()["sensor_profile"]["white_noise_density"] == [2e-3, 3e-3]
    assert "sensor_profile" not in b.truth()


def _closed_loop(r: int, n: int, level: float, alpha: float):
    prof = profile()
    sensor = twin_sensor(prof)
    a_pose, _ = static_readings(np.array([0.0]))  # MuJoCo once: the held pose
    a_true = np.repeat(a_pose, n, axis=0)
    t = np.arange(n) / RATE
    seeds = np.random.SeedSequence(SEED + 1).spawn(r)
    out = []
    for ss in seeds:
        acc = sensor.apply(a_true, np.random.default_rng(ss), t)
        out.append(characterize_noise(acc, RATE, level=level, alpha=alpha))
    return out


@pytest.mark.slow
def test_closed_loop_recovers_the_twin():
    """The acceptance loop (issue 19, item 6): R = 200 static logs of 2^14 samples at 100 Hz
    simulated by the bench's sensor terms for the profile above, each characterized by
    :func:`calib.noise.allan.characterize_noise` (``tiltbench noise``'s library call).

    Axis x (N = 2e-3, B = 1.5e-3, K = 5e-4): each term's 95 % interval covers the truth at
    0.95 ± 4·sqrt(0.95·0.05/200) = ± 0.062, and B is resolved more often than chance allows
    (α + 4·sqrt(α(1−α)/200) = 0.112), so the intervals are not vacuous (K, whose rise spans
    one octave step with ≥ 8 clusters here, is reported as an upper bound by the rise rule).
    Axis y (white N = 3e-3 with a 0.01 m/s² quantization step, no B, no K): the step is found in
    every run; N covers √(N² + Δ²/(12·fs)) (sample quantization is white, Δ²/12 per sample);
    bias instability and rate random walk are called resolved at most
    α + 4·sqrt(α(1−α)/200) = 0.05 + 0.062 of the time (they are absent: chance only)."""
    r, n, level, alpha = 200, 2 ** 14, 0.95, 0.05
    runs = _closed_loop(r, n, level, alpha)
    truth_x = np.array([2e-3, 1.5e-3, 5e-4])
    n_y = np.sqrt(3e-3 ** 2 + 0.01 ** 2 / 12 / RATE)
    hits = np.zeros(3)
    resolved = np.zeros(3)
    false_pos = np.zeros(3)
    hits_y = 0
    extra = 0
    for res in runs:
        x, y = res.axes
        for a, name in enumerate(TERM_NAMES):
            t = x.term(name)
            hits[a] += t.interval[0] <= truth_x[a] <= t.interval[1]
            resolved[a] += t.resolved
        lo, hi = y.term("white_noise_density").interval
        hits_y += lo <= n_y <= hi
        false_pos += [y.term(name).resolved for name in TERM_NAMES]
        extra += x.rule != "three terms" or y.rule != "three terms"
        assert y.quantization_step == pytest.approx(0.01, rel=1e-6)
        assert x.quantization_step is None
    band = 4 * np.sqrt(level * (1 - level) / r)
    assert np.all(np.abs(hits / r - level) <= band), hits / r
    assert abs(hits_y / r - level) <= band, hits_y / r
    assert np.all(false_pos[1:] / r <= alpha_fp_limit(r, alpha)), false_pos / r
    chance = alpha_fp_limit(r)
    assert resolved[0] == r and resolved[1] / r > chance, resolved / r
    # K's +½ rise shows over one octave step with ≥ 8 clusters only (10 → 20 s of 164 s):
    # the rise rule (calib.noise.allan_fit) reports it "not resolved, < upper" — its interval
    # still covers (above); measured resolved 0.01
    # the model rule adds a term by its χ² drop at 0.01 (Šidák over T_c): rarely, here
    assert extra / r <= 0.05, extra / r


def test_the_twin_draws_the_model_s_quantization_and_gauss_markov_processes():
    """``simulate_axis`` of a profile with Q (Δv quantization) and a Gauss–Markov term: the
    mean octave Allan variance of R = 300 twins equals the exact expectation — white
    ``N²/τ``, ``3Q²/τ²`` and the AR(1)'s closed form of the independent generator
    (:func:`validation.noise_independent.generator.ar1_avar`) — within 4·sd/√R; the reading
    lattice of the Δv counter is not applied a second time
    (:func:`bench.sensor_twin.counter_lattice`); truth.json round-trips the new terms."""
    from bench.sensor_twin import GaussMarkov, QuantizationNoise, counter_lattice, simulate_axis
    from calib.noise.allan import octave_factors, overlapping_adev
    from validation.noise_independent.generator import ar1_avar

    n, r = 2048, 300
    q, sigma, tc = 2e-4, 3e-3, 0.5
    lsb = np.sqrt(12.0) * q * RATE  # the counter's lattice: left out of the twin
    gm = NoiseTerm(value=sigma, interval=(0.9 * sigma, 1.1 * sigma), tau_range=(0.1, 10.0),
                   correlation_time=tc)
    prof = profile(quantization_noise=(term(q), None), gauss_markov=(gm, None),
                   bias_instability=None, rate_random_walk=None,
                   quantization_step=(lsb, 0.01))
    errors = twin_axis(prof, "x", RATE)
    assert counter_lattice(lsb, q, RATE) and not counter_lattice(0.01, q, RATE)
    assert errors.terms == (GaussMarkov(sigma=sigma, correlation_samples=tc * RATE),
                            QuantizationNoise(amplitude=q * RATE))
    assert AxisErrors.from_dict(errors.to_dict()) == errors
    ms = octave_factors(n, RATE)
    rng = np.random.default_rng(SEED + 20)
    s = np.array([overlapping_adev(simulate_axis(errors, n, RATE, rng), RATE, ms)[1] ** 2
                  for _ in range(r)])
    m = np.array(ms, float)
    mean = ((2e-3 * np.sqrt(RATE)) ** 2 / m + 3.0 * q ** 2 / (m / RATE) ** 2
            + ar1_avar(m, sigma ** 2, np.exp(-1.0 / (tc * RATE))))
    sd = s.std(axis=0, ddof=1)
    assert np.all(np.abs(s.mean(axis=0) - mean) <= 4 * sd / np.sqrt(r))
