"""The twin of a measured sensor: a :class:`calib.noise.sensor_profile.SensorProfile`
(``sensor.json``) turned into the bench's sensor error model, and static logs of it on the MuJoCo
table.

Per axis, the profile's terms become (docs/noise.md):

=========================  ===============================================================
profile term               bench model at the run's sample rate fs
=========================  ===============================================================
white_noise_density N      ``AxisErrors.noise_var = (N·√fs)²`` (per-sample white noise)
bias_instability B         :class:`bench.terms.BiasInstability` ``b = B`` (Kasdin flicker;
                           ADEV floor 0.664·B, independent of fs)
rate_random_walk K         :class:`bench.terms.BiasRandomWalk` ``q_per_sample = K/√fs``
                           (the same walk as ``q = K`` with Δt = 1/fs)
quantization_step Δ        :class:`bench.terms.Quantization` ``lsb = Δ`` (left out when Δ is
                           the step of the Δv counter of Q below: :func:`counter_lattice`)
quantization_noise Q       :class:`QuantizationNoise` ``amplitude = Q·fs``: the rate of an
                           integrated output quantized by Q, ``Q·fs·(w_k − w_{k−1})``
                           (Allan variance ``3Q²/τ²``, IEEE Std 952 C.1)
gauss_markov σ, T_c        :class:`GaussMarkov` ``sigma = σ``, ``correlation_samples =
                           T_c·fs``: a stationary AR(1), ``x_k = φ x_{k−1} + σ√(1−φ²) w_k``,
                           ``φ = e^{−1/(T_c·fs)}``, x_0 drawn from N(0, σ²)
export_filter f            :class:`ExportFilter` ``taps = f``: every reading so far (white
                           noise and the terms above) convolved with the export's low-pass
                           filter (lags −L … L, Σ f = 1; :mod:`calib.noise.shaping`), before
                           the reading's own quantization step
calibration bias, scale    ``AxisErrors.bias`` / ``scale`` (the profile's estimates)
=========================  ===============================================================

Quantization noise and the Gauss–Markov term are the processes of
:mod:`calib.noise.allan_model` and the export filter its ``h_m ∗ f`` (what the fit assumes), so
the twin of a profile has the Allan curve its fit describes. They are registered with
:func:`bench.terms.register_term` here, where the twin needs them (``truth.json`` round-trips
through ``AxisErrors.from_dict`` once this module is imported).

:func:`simulate_axis` draws one axis of any kind (an accelerometer's x, y, z, a gyro's axis)
from its profile block: ``tiltbench noise --twin`` compares it with the log
(:mod:`calib.noise.closure`).

A term the profile leaves null (not resolved by its log) is left out. The walk and the
flicker are per sample, so a static run without sample times is simulated as consecutive
samples at fs (``generate calibration --sensor``: the profile's own rate; a sweep: ``--rate``).

Every function here takes a profile object and runs the checks of the one loader first
(:func:`calib.noise.sensor_profile.check_profile`, the checks of ``load_profile``): a profile
built in Python with a negative N, one axis or a calibration that does not cover x and y is
refused in one line (:class:`calib.input_rules.DataError`), never an IndexError.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import ClassVar

import numpy as np
from scipy.signal import lfilter

from bench.sensors import AxisErrors, SensorErrorModel
from bench.terms import (
    BiasInstability,
    BiasRandomWalk,
    Quantization,
    SensorContext,
    register_term,
    require_finite,
)
from calib.conventions import AXES
from calib.noise.sensor_profile import NoiseTerm, SensorProfile, check_profile


@register_term("quantization_noise", "output", bound="nonnegative")
@dataclass(frozen=True)
class QuantizationNoise:
    """The rate of an integrated output quantized by Q (module table): adds
    ``amplitude·(w_k − w_{k−1})`` (N + 1 standard normals drawn), ``amplitude = Q·fs`` in the
    reading's unit (m/s²; gyro rad/s). Allan variance ``3Q²/τ²`` at every τ = m/fs."""

    amplitude: float
    name: ClassVar[str]
    stage: ClassVar[str]

    def __post_init__(self) -> None:
        if require_finite(self.amplitude, "quantization_noise amplitude") < 0:
            raise ValueError(f"quantization_noise amplitude must be >= 0, got {self.amplitude}")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        w = rng.standard_normal(a.shape[0] + 1)
        return a + self.amplitude * np.diff(w)

    def to_dict(self) -> dict:
        return {k: float(v) for k, v in asdict(self).items()}


@register_term("gauss_markov", "output", bound="nonnegative")
@dataclass(frozen=True)
class GaussMarkov:
    """A first-order Gauss–Markov bias (module table): stationary AR(1) of std ``sigma`` (the
    reading's unit) and correlation time ``correlation_samples`` (samples), x_0 ~ N(0, σ²),
    then N − 1 innovations (N standard normals drawn)."""

    sigma: float
    correlation_samples: float
    name: ClassVar[str]
    stage: ClassVar[str]

    def __post_init__(self) -> None:
        if require_finite(self.sigma, "gauss_markov sigma") < 0:
            raise ValueError(f"gauss_markov sigma must be >= 0, got {self.sigma}")
        if not require_finite(self.correlation_samples, "gauss_markov correlation_samples") > 0:
            raise ValueError("gauss_markov correlation_samples must be positive, got "
                             f"{self.correlation_samples}")

    def path(self, n: int, rng: np.random.Generator) -> np.ndarray:
        phi = float(np.exp(-1.0 / self.correlation_samples))
        w = rng.standard_normal(n)
        w[1:] *= np.sqrt(1.0 - phi * phi)
        return self.sigma * lfilter([1.0], [1.0, -phi], w)

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        return a + self.path(a.shape[0], rng)

    def to_dict(self) -> dict:
        return {k: float(v) for k, v in asdict(self).items()}


@register_term("export_filter", "output")
@dataclass(frozen=True)
class ExportFilter:
    """The export's low-pass filter (module table): the signal so far convolved with ``taps``
    (lags −L … L, Σ = 1, centred), the ends held at their first and last readings.
    :func:`simulate_axis` draws ``pad`` = L extra readings on each side and keeps the middle,
    so every reading it returns has its whole filter; on a bench run (``generate --sensor``)
    the first and last L readings see their end's reading repeated."""

    taps: tuple[float, ...]
    name: ClassVar[str]
    stage: ClassVar[str]

    def __post_init__(self) -> None:
        taps = tuple(require_finite(v, "export_filter tap") for v in self.taps)
        if len(taps) % 2 == 0 or abs(sum(taps) - 1.0) > 1e-6:
            raise ValueError("export_filter taps must be an odd count (lags −L … L) summing "
                             f"to 1, got {len(taps)} taps summing to {sum(taps):.9g}")
        object.__setattr__(self, "taps", taps)

    @property
    def pad(self) -> int:
        return (len(self.taps) - 1) // 2

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        # the ends held at their first and last readings: a constant stays that constant
        # (zeros beyond the ends would halve the reading level there)
        padded = np.pad(a, self.pad, mode="edge")
        return np.convolve(padded, np.asarray(self.taps), mode="valid")

    def to_dict(self) -> dict:
        return {"taps": [float(v) for v in self.taps]}


def _value(terms: tuple[NoiseTerm | None, ...] | None, k: int) -> float | None:
    if terms is None or terms[k] is None:
        return None
    return float(terms[k].value)


def calibration_pairs(profile: SensorProfile) -> tuple[tuple[float, float], tuple[float, float]
                                                       ] | None:
    """(bias (x, y) m/s², scale (x, y)) from the profile's calibration, or None if it has none.

    The calibration is ``{"param_names", "params", ...}`` of a calibration file
    (``scale_x, bias_x, scale_y, bias_y`` in any order) or ``{"bias", "scale"}``, each an
    object keyed by axis name (the file's form) or a list in the order of ``profile.axes``.
    The profile is checked first (:func:`calib.noise.sensor_profile.check_profile`).
    """
    profile = check_profile(profile)
    cal = profile.calibration
    if not cal:
        return None
    if "bias" in cal and "scale" in cal:
        bias, scale = cal["bias"], cal["scale"]
        return (tuple(float(bias[a]) for a in AXES), tuple(float(scale[a]) for a in AXES))
    named = dict(zip(cal["param_names"], cal["params"], strict=True))
    return (tuple(float(named[f"bias_{a}"]) for a in AXES),
            tuple(float(named[f"scale_{a}"]) for a in AXES))


def twin_axis(profile: SensorProfile, k: int | str, rate: float, bias: float = 0.0,
              scale: float = 0.0) -> AxisErrors:
    """The bench's :class:`AxisErrors` of axis ``k`` (0 = x, 1 = y, or any axis name of the
    profile: ``z``, ``gyro_x``, …) of ``profile`` at ``rate`` Hz (table in the module
    docstring); bias and scale in the axis's unit (m/s², 1)."""
    profile = check_profile(profile)
    k = profile.axis_index(AXES[k] if isinstance(k, int) else k)
    n_d = _value(profile.white_noise_density, k)
    b = _value(profile.bias_instability, k)
    q = _value(profile.rate_random_walk, k)
    lsb = None if profile.quantization_step is None else profile.quantization_step[k]
    quant = _value(profile.quantization_noise, k)
    gm = None if profile.gauss_markov is None else profile.gauss_markov[k]
    terms = []
    if b is not None and b > 0:
        terms.append(BiasInstability(b=b))
    if q is not None and q > 0:
        terms.append(BiasRandomWalk(q_per_sample=q / np.sqrt(rate)))
    if gm is not None and gm.value > 0:
        terms.append(GaussMarkov(sigma=float(gm.value),
                                 correlation_samples=float(gm.correlation_time) * rate))
    if quant is not None and quant > 0:
        terms.append(QuantizationNoise(amplitude=quant * rate))
    taps = None if profile.export_filter is None else profile.export_filter[k]
    if taps is not None:
        terms.append(ExportFilter(taps=tuple(taps)))
    if lsb is not None and not counter_lattice(lsb, quant, profile.sample_rate):
        terms.append(Quantization(lsb=float(lsb)))
    return AxisErrors(bias=float(bias), scale=float(scale),
                      noise_var=0.0 if n_d is None else (n_d * np.sqrt(rate)) ** 2,
                      terms=tuple(terms))


COUNTER_LATTICE_TOLERANCE = 0.25
"""A reading lattice is the Δv counter's own when its step is within 25 % of ``Δ·fs`` with
Δ = √12·Q (the counter's step from the profile's quantization noise Q, at the profile's rate):
the rate of a counted integral sits on that lattice by construction. The twin then does not
round its readings again (rounding the Q process's output would add Δ²fs²/12 of white noise a
second time)."""


def counter_lattice(lsb: float | None, quant: float | None, rate: float) -> bool:
    """Whether the reading lattice ``lsb`` is the Δv (Δθ) counter's of quantization noise
    ``quant`` at ``rate`` Hz (:data:`COUNTER_LATTICE_TOLERANCE`)."""
    if lsb is None or quant is None or quant <= 0:
        return False
    step = np.sqrt(12.0) * quant * rate
    return abs(lsb / step - 1.0) <= COUNTER_LATTICE_TOLERANCE


def simulate_axis(errors: AxisErrors, n: int, rate: float, rng: np.random.Generator,
                  level: float = 0.0) -> np.ndarray:
    """(n,) readings of one held axis with ``errors`` (:func:`twin_axis`) at ``rate`` Hz around
    the true reading ``level``: the same steps as :meth:`bench.sensors.SensorErrorModel.apply`
    for one axis (bias and scale, white noise, then the output terms in order), without the
    MuJoCo pose (a held axis reads a constant). With an :class:`ExportFilter` the axis is
    drawn ``pad`` readings longer on each side and its middle ``n`` kept."""
    pad = max((int(getattr(t, "pad", 0)) for t in errors.terms), default=0)
    keep = n
    n = n + 2 * pad
    a_true = np.full(n, float(level))
    ctx = SensorContext(np.column_stack([a_true, a_true]), np.arange(n) / float(rate), 0)
    a = errors.bias + (1.0 + errors.scale) * a_true
    if errors.noise_var > 0:
        a = a + np.sqrt(errors.noise_var) * rng.standard_normal(n)
    for term in errors.terms:
        if term.stage == "output":
            a = term.apply(a, ctx, rng)
    return a[pad:pad + keep]


def twin_sensor(profile: SensorProfile, rate: float | None = None,
                bias: tuple[float, float] = (0.0, 0.0),
                scale: tuple[float, float] = (0.0, 0.0)) -> SensorErrorModel:
    """The :class:`SensorErrorModel` of ``profile`` at ``rate`` Hz (default: the profile's).
    Bias (m/s²) and scale come from the profile's calibration when it has one, else from the
    arguments (x, y). Raises :class:`calib.input_rules.DataError` on a profile the loader
    would refuse."""
    profile = check_profile(profile)
    rate = float(profile.sample_rate if rate is None else rate)
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"sample rate must be a positive number of Hz, got {rate}")
    cal = calibration_pairs(profile)
    if cal is not None:
        bias, scale = cal
    return SensorErrorModel(*(twin_axis(profile, k, rate, bias[k], scale[k])
                              for k in range(len(AXES))))


def twin_truth(profile: SensorProfile, rate: float, source: str | None = None) -> dict:
    """What ``truth.json`` records of the twin: the profile's values (per axis x, y; units
    as :data:`calib.noise.sensor_profile.TERM_UNITS`), the run's rate (Hz) and the profile's
    file name."""
    profile = check_profile(profile)
    cal = calibration_pairs(profile)
    idx = [profile.axis_index(a) for a in AXES]
    q = profile.quantization_step
    out = {
        "source": source, "sample_rate": float(profile.sample_rate), "run_rate": float(rate),
        "white_noise_density": [_value(profile.white_noise_density, k) for k in idx],
        "bias_instability": [_value(profile.bias_instability, k) for k in idx],
        "rate_random_walk": [_value(profile.rate_random_walk, k) for k in idx],
        "quantization_step": None if q is None else [q[k] for k in idx],
        "calibration": None if cal is None else {"bias": list(cal[0]), "scale": list(cal[1])},
    }
    # the model's extra terms, only when the profile has them (the bytes of every other
    # truth.json stay as they were)
    if profile.quantization_noise is not None:
        out["quantization_noise"] = [_value(profile.quantization_noise, k) for k in idx]
    if profile.gauss_markov is not None:
        out["gauss_markov"] = [
            None if profile.gauss_markov[k] is None else
            {"sigma": profile.gauss_markov[k].value,
             "correlation_time": profile.gauss_markov[k].correlation_time} for k in idx]
    return out


@dataclass(frozen=True)
class StaticRun:
    """A static log on the MuJoCo table: t (N,) s, tita (N,) rad (constant), datos (N, 2)
    m/s², a_true (N, 2) m/s², and what made it."""

    t: np.ndarray
    tita: np.ndarray
    datos: np.ndarray
    a_true: np.ndarray
    sensor: SensorErrorModel
    rate: float
    seed: int
    g: float
    twin: dict | None = None

    def truth(self) -> dict:
        d = {"kind": "static", "n": int(self.t.size), "duration": float(self.t.size / self.rate),
             "rate": float(self.rate), "theta": float(self.tita[0]), "g": float(self.g),
             "sensor": self.sensor.to_dict(), "model": "models/tilt_table.xml"}
        if self.twin is not None:
            d["sensor_profile"] = self.twin
        return d


def static_samples(duration: float, rate: float) -> int:
    """Number of samples of a static log: ⌊duration·rate⌋ (at least 1)."""
    return max(1, int(np.floor(duration * rate + 1e-9)))


def make_static_run(sensor: SensorErrorModel, duration: float, rate: float, theta: float,
                    seed: int, g: float | None = None, twin: dict | None = None) -> StaticRun:
    """Hold the table at ``theta`` (rad) for ``duration`` s sampled at ``rate`` Hz: MuJoCo
    evaluates the pose once (:func:`bench.tilt.static_readings`), the sensor model adds its
    errors over the run's sample times (same seed → same bytes)."""
    from bench.model import TableEdits
    from bench.tilt import static_readings

    table = TableEdits() if g is None else TableEdits(g=g)
    n = static_samples(duration, rate)
    a_pose, enc = static_readings(np.array([float(theta)]), table)
    a_true = np.repeat(a_pose, n, axis=0)
    t = np.arange(n) / float(rate)
    rng = np.random.default_rng(np.random.SeedSequence(int(seed)))
    datos = sensor.apply(a_true, rng, t)
    return StaticRun(t=t, tita=np.full(n, float(enc[0])), datos=datos, a_true=a_true,
                     sensor=sensor, rate=float(rate), seed=int(seed), g=table.g, twin=twin)


def write_static(run: StaticRun, out, force: bool = False) -> dict[str, str]:
    """Write ``static.mat`` (the course ``acel.mat`` layout: t N×1 s, Aerr N×2 m/s², which every
    log reader reads; one pose is no calibration run, so not the ensayo layout) and
    ``truth.json`` (θ, the sensor, the profile) into ``out``."""
    from bench.dataset import prepare_out_dir, save_mat, write_truth

    out = prepare_out_dir(out, ["static.mat", "truth.json"], force)
    paths = {"static": save_mat(out / "static.mat",
                                {"t": run.t, "Aerr": run.datos}, force=True),
             "truth": write_truth(out / "truth.json", run.truth(), run.seed, force=True)}
    return {k: str(v) for k, v in paths.items()}


__all__ = ["COUNTER_LATTICE_TOLERANCE", "GaussMarkov", "QuantizationNoise", "StaticRun",
           "calibration_pairs", "counter_lattice",
           "make_static_run", "simulate_axis", "static_samples", "twin_axis", "twin_sensor",
           "twin_truth", "write_static"]
