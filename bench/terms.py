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

from dataclasses import dataclass
from typing import ClassVar, Literal, Protocol

import numpy as np
from scipy.signal import fftconvolve

from calib.filters import lowpass, uniform_step
from calib.noise.allan_model import flicker_coefficients

Stage = Literal["response", "output"]


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


def register_term(cls: type) -> type:
    TERM_REGISTRY[cls.name] = cls
    return cls


TERM_ORDER: tuple[str, ...] = ("lowpass_lag", "nonlinearity_k2", "cross_axis", "bias_drift",
                               "bias_instability", "bias_random_walk", "quantization")
"""Order in which sensor terms are applied (stage first, then this order)."""


def require_finite(value: float, what: str) -> float:
    value = float(value)
    if not np.isfinite(value):
        raise ValueError(f"{what} must be finite, got {value}")
    return value


def _positive(value: float, what: str) -> float:
    value = require_finite(value, what)
    if value <= 0:
        raise ValueError(f"{what} must be positive, got {value}")
    return value


def _one_of(a: float | None, b: float | None, names: tuple[str, str], effect: str) -> None:
    if (a is None) == (b is None):
        raise ValueError(f"{effect}: give exactly one of {names[0]} (with timing) or "
                         f"{names[1]} (samples in time order)")


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


# --- the catalog's sensor error terms -----------------------------------------------------


@register_term
@dataclass(frozen=True)
class NonlinearityK2:
    """Second-order response (IEEE Std 1293 K2/K1): ``a ↦ a + k2·a²``.

    Parameters
    ----------
    k2 : 1/(m/s²). Positive raises the reading at both ends of the range (cos 2θ phase on the
        tilt table: ``a_x² = g²(1 - cos 2θ)/2``).
    """

    k2: float
    name: ClassVar[str] = "nonlinearity_k2"
    stage: ClassVar[Stage] = "response"

    def __post_init__(self) -> None:
        require_finite(self.k2, "nonlinearity_k2 k2")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + k2·a²`` (a: (N,) m/s²)."""
        return a + self.k2 * a * a

    def to_dict(self) -> dict:
        return {"k2": float(self.k2)}


@register_term
@dataclass(frozen=True)
class CrossAxis:
    """Cross-coupling (IEEE Std 1293 K_ip/K1): ``a_i ↦ a_i + k_ip·a_i·a_p``.

    Parameters
    ----------
    k_ip : 1/(m/s²). ``a_p`` is the true specific force on the other in-plane axis (x ↔ y); on
        the tilt table ``a_x·a_y = g² sin 2θ / 2`` (sin 2θ phase).
    """

    k_ip: float
    name: ClassVar[str] = "cross_axis"
    stage: ClassVar[Stage] = "response"

    def __post_init__(self) -> None:
        require_finite(self.k_ip, "cross_axis k_ip")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + k_ip·a·a_p``; ``a_p = ctx.a_true[:, other axis]``."""
        a_p = np.asarray(ctx.a_true, dtype=float)[:, 1 - ctx.axis]
        return a + self.k_ip * a * a_p

    def to_dict(self) -> dict:
        return {"k_ip": float(self.k_ip)}


@register_term
@dataclass(frozen=True)
class BiasDrift:
    """Linear bias drift, additive at the bias level: ``A_m ↦ A_m + rate·(t - t0)``.

    Exactly one of ``rate`` (m/s² per s, needs sample times) or ``rate_per_sample`` (m/s² per
    sample, ``t - t0`` replaced by the sample index k = 0…N-1) is given. The drift is zero at
    the first sample, so ``bias`` is the bias at the start of the run.
    """

    rate: float | None = None
    rate_per_sample: float | None = None
    name: ClassVar[str] = "bias_drift"
    stage: ClassVar[Stage] = "output"

    def __post_init__(self) -> None:
        _one_of(self.rate, self.rate_per_sample, ("rate", "rate_per_sample"), self.name)
        require_finite(self.rate if self.rate is not None else self.rate_per_sample,
                       "bias_drift rate")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + rate·(t - t0)`` (or ``a + rate_per_sample·k``)."""
        per_second = self.rate is not None
        x = _per_sample_or_time(ctx, a.shape[0], per_second, self.name, "rate")
        return a + (self.rate if per_second else self.rate_per_sample) * x

    def to_dict(self) -> dict:
        if self.rate is not None:
            return {"rate": float(self.rate)}
        return {"rate_per_sample": float(self.rate_per_sample)}


@register_term
@dataclass(frozen=True)
class BiasRandomWalk:
    """Bias random walk, additive at the bias level: ``b_k = b_{k-1} + q·√Δt_k·w_k``, b_0 = 0.

    Exactly one of ``q`` (m/s²/√s, Δt from the sample times) or ``q_per_sample`` (m/s² per
    √sample, Δt = 1) is given. Draws N - 1 standard normals w_k from the run's generator.
    """

    q: float | None = None
    q_per_sample: float | None = None
    name: ClassVar[str] = "bias_random_walk"
    stage: ClassVar[Stage] = "output"

    def __post_init__(self) -> None:
        _one_of(self.q, self.q_per_sample, ("q", "q_per_sample"), self.name)
        q = self.q if self.q is not None else self.q_per_sample
        if require_finite(q, "bias_random_walk q") < 0:
            raise ValueError(f"bias_random_walk q must be >= 0, got {q}")

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

    def to_dict(self) -> dict:
        if self.q is not None:
            return {"q": float(self.q)}
        return {"q_per_sample": float(self.q_per_sample)}


@register_term
@dataclass(frozen=True)
class BiasInstability:
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
    name: ClassVar[str] = "bias_instability"
    stage: ClassVar[Stage] = "output"

    def __post_init__(self) -> None:
        if require_finite(self.b, "bias_instability b") < 0:
            raise ValueError(f"bias_instability b must be >= 0, got {self.b}")

    def path(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """The (N,) flicker bias path, m/s² (draws 2N − 1 standard normals)."""
        if n <= 0:
            return np.zeros(0)
        w = rng.standard_normal(2 * n - 1)
        return self.b * fftconvolve(w, flicker_coefficients(n), mode="valid")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``a + b`` with ``b`` a fresh flicker path (see :meth:`path`)."""
        return a + self.path(a.shape[0], rng)

    def to_dict(self) -> dict:
        return {"b": float(self.b)}


@register_term
@dataclass(frozen=True)
class Quantization:
    """Output quantization: the reading is rounded to the nearest multiple of ``lsb`` (m/s²).

    Ties round up (``lsb·floor(a/lsb + 1/2)``), so the result does not depend on numpy's
    round-half-to-even.
    """

    lsb: float
    name: ClassVar[str] = "quantization"
    stage: ClassVar[Stage] = "output"

    def __post_init__(self) -> None:
        _positive(self.lsb, "quantization lsb")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return ``lsb·floor(a/lsb + 1/2)``."""
        return self.lsb * np.floor(a / self.lsb + 0.5)

    def to_dict(self) -> dict:
        return {"lsb": float(self.lsb)}


@register_term
@dataclass(frozen=True)
class LowpassLag:
    """First-order low-pass ``τ·dy/dt + y = u`` with time constant ``tau`` (s).

    Needs sample times. Response stage (see the module docstring): the deterministic reading is
    the catalog's low-passed output, the reading's white noise stays white. For a constant rate
    ω the reading lags like an angle offset −τ·ω.
    """

    tau: float
    name: ClassVar[str] = "lowpass_lag"
    stage: ClassVar[Stage] = "response"

    def __post_init__(self) -> None:
        _positive(self.tau, "lowpass_lag tau")

    def apply(self, a: np.ndarray, ctx: SensorContext, rng: np.random.Generator) -> np.ndarray:
        """Return the low-passed signal (:func:`calib.filters.lowpass`)."""
        if ctx.t is None:
            raise ValueError("lowpass_lag needs sample times (a sweep); a static run has none")
        return lowpass(a, ctx.t, self.tau, uniform_step(ctx.t))

    def to_dict(self) -> dict:
        return {"tau": float(self.tau)}


TERM_CLASSES: dict[str, type] = {c.name: c for c in (
    NonlinearityK2, CrossAxis, BiasDrift, BiasRandomWalk, Quantization, LowpassLag)}
"""Catalog name → sensor term class (the non-physical effects except ``noise_level``)."""
