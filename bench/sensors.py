"""Sensor error model: the true errors applied to MuJoCo's accelerometer readings.

MuJoCo gives the true specific force along each sensitive axis, ``a`` (m/s²). The model turns
it into the reading (course model; IEEE Std 1293 accelerometer model equation, K0 = bias,
K1 = 1 + scale)::

    A_m = (1 + scale) · a + bias + Σ terms(a, context) + v,     v ~ N(0, σ²) white

The base terms (bias, scale, white noise) are fields of :class:`AxisErrors`. Further error
terms (IEEE K2, cross-axis, drift, quantization, ...) are :class:`bench.terms.ErrorTerm` objects
added one by one to ``AxisErrors.terms``; each knows its vocabulary name, its stage in the
signal chain and how to apply itself, so new effects need no change here. The forward model
``(1 + scale)·a + bias`` is :func:`calib.calibration.correct.apply_errors` (one home for both
sides). Signal chain per axis:

    stage "response" (deterministic, on the true input) → scale & bias → white noise
    → stage "output" (on the noisy reading: low-pass, quantization, ...)

All randomness comes from the ``numpy.random.Generator`` passed in: the same seed gives the
same bytes. Draws happen in a fixed order: axis x, then y; within an axis, terms in order, with
the white noise drawn between the response and output stages.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from bench.terms import (  # noqa: F401  (ErrorTerm, Stage, register_term: public here too)
    TERM_REGISTRY,
    ErrorTerm,
    SensorContext,
    Stage,
    register_term,
)
from calib.calibration.correct import apply_errors
from calib.conventions import AXES


@dataclass(frozen=True)
class AxisErrors:
    """True errors of one accelerometer.

    bias : m/s² (K0); positive shifts the reading up.
    scale : dimensionless (K1 - 1); positive makes the sensor read too much.
    noise_var : variance of the white noise, (m/s²)².
    terms : further error terms, applied by stage, in order.
    """

    bias: float = 0.0
    scale: float = 0.0
    noise_var: float = 0.0
    terms: tuple = field(default_factory=tuple)

    def __post_init__(self) -> None:
        for name in ("bias", "scale", "noise_var"):
            v = getattr(self, name)
            if not np.isfinite(v):
                raise ValueError(f"sensor {name} must be finite, got {v}")
        if self.noise_var < 0:
            raise ValueError(f"noise variance must be >= 0, got {self.noise_var}")
        if self.scale <= -1:
            raise ValueError(f"scale must be > -1 (1 + scale is the gain), got {self.scale}")

    def to_dict(self) -> dict:
        d = {k: v for k, v in asdict(self).items() if k != "terms"}
        d["terms"] = [{"name": t.name, **t.to_dict()} for t in self.terms]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> AxisErrors:
        terms = tuple(TERM_REGISTRY[t["name"]](**{k: v for k, v in t.items() if k != "name"})
                      for t in d.get("terms", ()))
        return cls(float(d["bias"]), float(d["scale"]), float(d["noise_var"]), terms)


@dataclass(frozen=True)
class SensorErrorModel:
    """Errors of the two accelerometers (x, y)."""

    x: AxisErrors = field(default_factory=AxisErrors)
    y: AxisErrors = field(default_factory=AxisErrors)

    @classmethod
    def from_pairs(cls, bias=(0.0, 0.0), scale=(0.0, 0.0), noise_var=(0.0, 0.0)
                   ) -> SensorErrorModel:
        return cls(*(AxisErrors(float(bias[k]), float(scale[k]), float(noise_var[k]))
                     for k in range(2)))

    def axis(self, name: str) -> AxisErrors:
        return getattr(self, name)

    def with_axis(self, name: str, errors: AxisErrors) -> SensorErrorModel:
        return SensorErrorModel(**{a: (errors if a == name else self.axis(a)) for a in AXES})

    def apply(self, a_true: np.ndarray, rng: np.random.Generator,
              t: np.ndarray | None = None) -> np.ndarray:
        """Readings (N, 2) from the true specific force ``a_true`` (N, 2), m/s²."""
        a_true = np.asarray(a_true, dtype=float)
        if a_true.ndim != 2 or a_true.shape[1] != 2:
            raise ValueError(f"a_true must be (N, 2), got {a_true.shape}")
        out = np.empty_like(a_true)
        for k, name in enumerate(AXES):
            err = self.axis(name)
            ctx = SensorContext(a_true, t, k)
            a = a_true[:, k].copy()
            for term in err.terms:
                if term.stage == "response":
                    a = term.apply(a, ctx, rng)
            a = apply_errors(a, err.bias, err.scale)
            if err.noise_var > 0:
                a = a + np.sqrt(err.noise_var) * rng.standard_normal(a.shape[0])
            for term in err.terms:
                if term.stage == "output":
                    a = term.apply(a, ctx, rng)
            out[:, k] = a
        return out

    def to_dict(self) -> dict:
        return {a: self.axis(a).to_dict() for a in AXES}

    @classmethod
    def from_dict(cls, d: dict) -> SensorErrorModel:
        return cls(*(AxisErrors.from_dict(d[a]) for a in AXES))
