"""Sensor error terms: the protocol, the registry and the catalog's non-physical terms.

An error term is one small object per effect of the catalog (``docs/effects.md``): it knows its
vocabulary name (:data:`calib.conventions.EFFECTS`), its stage in the signal chain of
:mod:`bench.sensors` and how to apply itself. Terms register by name (:func:`register_term`) so
``truth.json`` round-trips through ``AxisErrors.to_dict`` / ``from_dict``; importing this module
registers all of them, and :mod:`bench.sensors` imports it, so the registry is always full.

Stages (response → ``(1 + scale)·a + bias`` → white noise → output) follow the catalog's model
column exactly:

* ``nonlinearity_k2``, ``cross_axis`` — response stage, so ``A_m = bias + (1 + scale)·(a_i +
  k2·a_i² + k_ip·a_i·a_p) + v`` as in the catalog's reading equation.
* ``lowpass_lag`` — response stage: the first-order low-pass (:func:`calib.filters.lowpass`,
  the one the estimation side fits with) acts on the signal, the white noise ``v`` is the noise
  *of the reading* (the stated σ² is measured at the output). The filter is linear with unit DC
  gain, so ``LPF(bias + (1 + scale)·a) = bias + (1 + scale)·LPF(a)``: the deterministic reading
  is the catalog's "low-pass on the output"; only the noise stays white (filtering it too would
  make the stated σ² wrong by the factor ``(1 - e^{-h/τ}) / (1 + e^{-h/τ})`` and colour the
  residuals).
* ``bias_drift``, ``bias_instability``, ``bias_random_walk`` — output stage, additive at the
  bias level, so the reading is ``bias + rate·(t - t0) + …`` exactly as the catalog writes it
  (a response term would be multiplied by ``1 + scale``).
* ``quantization`` — output stage: the noisy reading is rounded to a multiple of ``lsb``.

Canonical term order inside a stage: :data:`TERM_ORDER`.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import ClassVar, Literal, Protocol

import numpy as np

from calib.filters import lowpass, uniform_step
from calib.noise.allan_model import flicker_coefficients

Stage = Literal["response", "output"]
Bound = Literal["finite", "nonnegative", "positive"]
"""What a term's coefficient must be (besides finite: >= 0, > 0)."""


@dataclass(frozen=True)
class SensorContext:
    """What an error term may look at.

    a_true : (N, 2) true specific force on both sensitive axes, m/s² (MuJoCo).
    t : (N,) sample times, s, or None when the run has no timing.
    axis : index of the axis being modelled (0 = x, 1 = y).
    """

    a_true: np.ndarray
    t: np.ndarray | None
    axis: int


class ErrorTerm(Protocol):
    """One additional error term of the accelerometer model."""

    name: ClassVar[str]  # effect vocabulary name (docs/effects.md), e.g. "nonlinearity_k2"
    stage: ClassVar[Stage]

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return the signal after this term; ``a`` is the (N,) signal at this stage."""
        ...

    def to_dict(self) -> dict: ...


TERM_REGISTRY: dict[str, type] = {}
"""Effect name → term class; filled by :func:`register_term`, used to rebuild from JSON."""


def register_term(name: str, stage: Stage, bound: Bound = "finite"):
    """Class decorator: give a term class its vocabulary ``name``, its ``stage`` and the
    ``bound`` its coefficient keeps, and register it under ``name`` (dm_control registers a
    task the same way)."""

    def register(cls: type) -> type:
        cls.name, cls.stage, cls.bound = name, stage, bound
        TERM_REGISTRY[name] = cls
        return cls

    return register


TERM_ORDER: tuple[str, ...] = ("lowpass_lag", "nonlinearity_k2", "cross_axis", "bias_drift",
                               "bias_instability", "bias_random_walk", "quantization")
"""Order in which sensor terms are applied (stage first, then this order)."""


def require_finite(value: float, what: str) -> float:
    value = float(value)
    if not np.isfinite(value):
        raise ValueError(f"{what} must be finite, got {value}")
    return value


def _per_sample_or_time(ctx: SensorContext, n: int, per_second: bool, effect: str,
                        key: str) -> np.ndarray:
    """Elapsed time t - t0 (s) or the sample index k (samples) for a drift-type term."""
    if per_second:
        if ctx.t is None:
            raise ValueError(f"{effect}: '{key}' is per second and needs sample times (a "
                             f"sweep); use '{key}_per_sample' for a run without timing")
        t = np.asarray(ctx.t, dtype=float)
        return t - t[0]
    return np.arange(n, dtype=float)


class CoefficientTerm:
    """What every term of the catalog shares: its coefficient is checked when it is made and
    written to ``truth.json`` as a float.

    A term has one coefficient, or two alternatives of which exactly one is given (per second,
    with sample times, or per sample: ``rate`` / ``rate_per_sample``); the first field names
    the coefficient in messages. The coefficient is finite and keeps the term's ``bound``
    (:func:`register_term`).
    """

    name: ClassVar[str]
    stage: ClassVar[Stage]
    bound: ClassVar[Bound]

    def __post_init__(self) -> None:
        names = tuple(f.name for f in fields(self))
        values = [getattr(self, n) for n in names]
        if len(names) == 2:
            a, b = values
            if (a is None) == (b is None):
                raise ValueError(f"{self.name}: give exactly one of {names[0]} (with timing) "
                                 f"or {names[1]} (samples in time order)")
        value = values[0] if values[0] is not None else values[-1]
        what = f"{self.name} {names[0]}"
        checked = require_finite(value, what)
        if self.bound == "nonnegative" and checked < 0:
            raise ValueError(f"{what} must be >= 0, got {value}")
        if self.bound == "positive" and checked <= 0:
            raise ValueError(f"{what} must be positive, got {checked}")

    def to_dict(self) -> dict:
        """The given coefficient(s) as floats (an alternative left unset is left out)."""
        return {f.name: float(v) for f in fields(self) if (v := getattr(self, f.name)) is not None}


# --- the catalog's sensor error terms -----------------------------------------------------


@register_term("nonlinearity_k2", "response")
@dataclass(frozen=True)
class NonlinearityK2(CoefficientTerm):
    """Second-order response (IEEE Std 1293 K2/K1): ``a ↦ a + k2·a²``.

    Parameters
    ----------
    k2 : 1/(m/s²). Positive raises the reading at both ends of the range (cos 2θ phase on the
        tilt table: ``a_x² = g²(1 - cos 2θ)/2``).
    """

    k2: float

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + k2·a²`` (a: (N,) m/s²)."""
        return a + self.k2 * a * a


@register_term("cross_axis", "response")
@dataclass(frozen=True)
class CrossAxis(CoefficientTerm):
    """Cross-coupling (IEEE Std 1293 K_ip/K1): ``a_i ↦ a_i + k_ip·a_i·a_p``.

    Parameters
    ----------
    k_ip : 1/(m/s²). ``a_p`` is the true specific force on the other in-plane axis (x ↔ y); on
        the tilt table ``a_x·a_y = g² sin 2θ / 2`` (sin 2θ phase).
    """

    k_ip: float

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + k_ip·a·a_p``; ``a_p = ctx.a_true[:, other axis]``."""
        a_p = np.asarray(ctx.a_true, dtype=float)[:, 1 - ctx.axis]
        return a + self.k_ip * a * a_p


@register_term("bias_drift", "output")
@dataclass(frozen=True)
class BiasDrift(CoefficientTerm):
    """Linear bias drift, additive at the bias level: ``A_m ↦ A_m + rate·(t - t0)``.

    Exactly one of ``rate`` (m/s² per s, needs sample times) or ``rate_per_sample`` (m/s² per
    sample, ``t - t0`` replaced by the sample index k = 0…N-1) is given. The drift is zero at
    the first sample, so ``bias`` is the bias at the start of the run.
    """

    rate: float | None = None
    rate_per_sample: float | None = None

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + rate·(t - t0)`` (or ``a + rate_per_sample·k``)."""
        per_second = self.rate is not None
        x = _per_sample_or_time(ctx, a.shape[0], per_second, self.name, "rate")
        return a + (self.rate if per_second else self.rate_per_sample) * x


@register_term("bias_random_walk", "output", bound="nonnegative")
@dataclass(frozen=True)
class BiasRandomWalk(CoefficientTerm):
    """Bias random walk, additive at the bias level: ``b_k = b_{k-1} + q·√Δt_k·w_k``, b_0 = 0.

    Exactly one of ``q`` (m/s²/√s, Δt from the sample times) or ``q_per_sample`` (m/s² per
    √sample, Δt = 1) is given, ≥ 0. Draws N - 1 standard normals w_k from the run's generator.
    """

    q: float | None = None
    q_per_sample: float | None = None

    def walk(self, n: int, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """The (N,) bias path b_k, m/s² (b_0 = 0)."""
        per_second = self.q is not None
        x = _per_sample_or_time(ctx, n, per_second, self.name, "q")
        q = self.q if per_second else self.q_per_sample
        w = rng.standard_normal(max(n - 1, 0))
        return np.concatenate([[0.0], np.cumsum(q * np.sqrt(np.diff(x)) * w)])[:n]

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + b`` with ``b`` a fresh random-walk path (see :meth:`walk`)."""
        return a + self.walk(a.shape[0], ctx, rng)


@register_term("bias_instability", "output", bound="nonnegative")
@dataclass(frozen=True)
class BiasInstability(CoefficientTerm):
    """Bias instability (flicker noise of the bias), additive at the bias level:
    ``b_k = B · Σ_{j=0}^{N-1} f_j w_{k-j}``, ``f`` Kasdin's fractional-integration filter for
    α = 1 (:func:`calib.noise.allan_model.flicker_coefficients`), ``w`` standard normal.

    Why this model: its one-sided spectrum is ``S(f) ≈ B²/(π f)`` for f ≪ fs (IEEE Std 952's
    ``h_{-1} = B²/π``), so its Allan deviation has the flat floor ``√(2 ln2/π)·B = 0.664·B``
    at every τ from a few samples to the record length — exactly the term ``tiltbench noise``
    fits (:mod:`calib.noise.allan_model`), not an approximation of it by a few Gauss–Markov
    corners. The filter's memory is N samples (a stationary process over the run: 2N − 1
    normals drawn, the first N − 1 as the run's past). Per sample: B does not depend on the
    sample rate, so the term needs no sample times.

    Parameters
    ----------
    b : m/s², B (IEEE Std 952 bias instability coefficient), ≥ 0.
    """

    b: float

    def path(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """The (N,) flicker bias path, m/s² (draws 2N − 1 standard normals)."""
        if n <= 0:
            return np.zeros(0)
        # scipy.signal costs ≈ 0.7 s to import; only flicker terms need it (gap, startup)
        from scipy.signal import fftconvolve

        w = rng.standard_normal(2 * n - 1)
        return self.b * fftconvolve(w, flicker_coefficients(n), mode="valid")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + b`` with ``b`` a fresh flicker path (see :meth:`path`)."""
        return a + self.path(a.shape[0], rng)


@register_term("quantization", "output", bound="positive")
@dataclass(frozen=True)
class Quantization(CoefficientTerm):
    """Output quantization: the reading is rounded to the nearest multiple of ``lsb`` (m/s²).

    Ties round up (``lsb·floor(a/lsb + 1/2)``), so the result does not depend on numpy's
    round-half-to-even.
    """

    lsb: float

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``lsb·floor(a/lsb + 1/2)``."""
        return self.lsb * np.floor(a / self.lsb + 0.5)


@register_term("lowpass_lag", "response", bound="positive")
@dataclass(frozen=True)
class LowpassLag(CoefficientTerm):
    """First-order low-pass ``τ·dy/dt + y = u`` with time constant ``tau`` (s).

    Needs sample times. Response stage (see the module docstring): the deterministic reading is
    the catalog's low-passed output, the reading's white noise stays white. For a constant rate
    ω the reading lags like an angle offset −τ·ω.
    """

    tau: float

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return the low-passed signal (:func:`calib.filters.lowpass`)."""
        if ctx.t is None:
            raise ValueError("lowpass_lag needs sample times (a sweep); a static run has none")
        return lowpass(a, ctx.t, self.tau, uniform_step(ctx.t))


TERM_CLASSES: dict[str, type] = {c.name: c for c in (
    NonlinearityK2, CrossAxis, BiasDrift, BiasRandomWalk, Quantization, LowpassLag)}
"""Catalog name → sensor term class (the non-physical effects except ``noise_level``)."""
