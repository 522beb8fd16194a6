"""The extended sensor model's prediction of a measured axis, and the residual to measure.

The bench's true specific force goes through the axis' response terms (:mod:`bench.terms`),
the nominal parameters are fitted linearly (:func:`fit_bias_scale`: the centred least squares
of :func:`calib.calibration.ls.fit_linear`, the estimation side's), and the forward model is
:func:`calib.calibration.correct.apply_errors`.

Noise model of the "after" gap: the extended model's noise variance (``noise_level`` if
named, else the stated one); with ``quantization`` the mean and variance of the rounded
reading are those of ``Q(μ + v)``, v ~ N(0, σ²) (:func:`calib.gap.quantized_moments`); with
``bias_random_walk`` the residuals are whitened by the random-walk Kalman filter of
:func:`calib.filters.walk_filter` (state: the walking bias) and its normalized innovations are
measured.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bench.sensors import SensorContext, SensorErrorModel
from calib.calibration.correct import apply_errors
from calib.calibration.ls import NotIdentifiableError
from calib.conventions import AXES, PARAM_NAMES
from calib.filters import walk_filter
from calib.gap import quantized_moments


def response(a_phys: np.ndarray, t: np.ndarray | None, sensor: SensorErrorModel,
             k: int) -> np.ndarray:
    """Deterministic response-stage signal of axis ``k`` (before scale and bias), m/s².

    Applies the axis' response terms (``lowpass_lag``, ``nonlinearity_k2``, ``cross_axis``) to
    the bench's true specific force; no noise.
    """
    err = sensor.axis(AXES[k])
    ctx = SensorContext(a_phys, t, k)
    a = np.array(a_phys[:, k], dtype=float)
    rng = np.random.default_rng(0)  # response terms are deterministic; never drawn from
    for term in err.terms:
        if term.stage == "response":
            a = term.apply(a, ctx, rng)
    return a


def additive_output(n: int, t: np.ndarray | None, sensor: SensorErrorModel, k: int
                    ) -> np.ndarray:
    """Deterministic additive output terms of axis ``k`` (``bias_drift``), m/s² (N,)."""
    out = np.zeros(n)
    ctx = SensorContext(np.zeros((n, 2)), t, k)
    for term in sensor.axis(AXES[k]).terms:
        if term.name == "bias_drift":
            out = term.apply(out, ctx, np.random.default_rng(0))
    return out


def axis_term(sensor: SensorErrorModel, k: int, name: str) -> Any:
    """The term ``name`` of axis ``k`` (None if absent)."""
    return next((t for t in sensor.axis(AXES[k]).terms if t.name == name), None)


def fit_bias_scale(y: np.ndarray, x: np.ndarray) -> tuple[float, float, np.ndarray]:
    """Least squares ``y ≈ bias + (1 + scale)·x``; returns (bias, scale, residual y - fit).

    The course's per-axis model ``y - x = bias + scale·x`` with the simulated response ``x``
    in place of the reference ``A_r``, on the centred design ``[1, x - x̄]`` as
    :func:`calib.calibration.ls.fit_linear` solves it. Its two columns are orthogonal, so the QR
    factor is diagonal and the solution is two projections, ``scale = ⟨x - x̄, y - x⟩ / ‖x - x̄‖²``
    and ``bias = mean(y - x) - scale·x̄`` (the same numbers as ``fit_linear`` to rounding,
    without its covariance and condition number, which are not used here: this runs once
    per candidate of the ``mujoco.sysid`` fit, ≈ 10× faster).

    Raises
    ------
    NotIdentifiableError : ``x`` is constant (the scale is confounded with the bias).
    """
    x = np.asarray(x, dtype=float)
    yx = np.asarray(y, dtype=float) - x
    mean = float(np.mean(x))
    xc = x - mean
    ss = float(xc @ xc)
    if not ss > (1e-12 * max(1.0, abs(mean))) ** 2 * x.size:
        raise NotIdentifiableError(
            f"the simulated reading is constant ({mean:g} m/s²): cannot identify "
            f"{PARAM_NAMES[0]} / {PARAM_NAMES[1]} (use at least two θ with different readings)")
    scale = float(xc @ yx) / ss
    bias = float(np.mean(yx)) - scale * mean
    return bias, scale, yx - bias - scale * x


def walk_innovations(r: np.ndarray, t: np.ndarray | None, sigma2: float, q: float,
                     per_second: bool) -> np.ndarray:
    """Innovations of ``r_k = b_k + v_k`` (``b`` a random walk of ``q``, v ~ N(0, σ²)), m/s².

    The normalized innovations of :func:`calib.filters.walk_filter` (diffuse start: the first
    one is 0) are i.i.d. N(0, 1) under the model; scaled by σ they read as residuals with the
    stated variance. ``q`` is per √s (increments ``q²Δt``) when ``per_second``, else per
    √sample.
    """
    n = r.shape[0]
    dt = np.diff(t) if (per_second and t is not None) else np.ones(max(n - 1, 0))
    innov, _, _ = walk_filter(np.asarray(r, dtype=float), sigma2, q * q * dt)
    return innov * np.sqrt(sigma2)


@dataclass(frozen=True)
class AxisPrediction:
    """The extended model's prediction of one axis, and the residual to measure.

    bias, scale : refitted nominal parameters.  mean : (N,) predicted mean reading, m/s².
    residual : (N,) data − mean, whitened where the model's noise is not white (random walk:
    Kalman innovations; quantization: scaled by σ/√Var), m/s².  sigma2 : the noise variance
    the residual is to be measured with, (m/s²)².
    """

    bias: float
    scale: float
    mean: np.ndarray
    residual: np.ndarray
    sigma2: float


def predict_axis(y: np.ndarray, a_phys: np.ndarray, t: np.ndarray | None,
                 sensor: SensorErrorModel, k: int, sigma2: float) -> AxisPrediction:
    """Fit bias and scale of axis ``k`` on the extended simulation and build the residual.

    Model: ``y = Q(bias + (1 + scale)·resp(a_phys) + drift + walk + v)`` with the axis'
    terms in ``sensor`` (zero noise); ``sigma2`` is the axis' white-noise variance.
    """
    n = y.shape[0]
    x = response(a_phys, t, sensor, k)
    drift = additive_output(n, t, sensor, k)
    bias, scale, _ = fit_bias_scale(y - drift, x)
    mean = apply_errors(x, bias, scale) + drift
    var = np.full(n, sigma2)
    quant = axis_term(sensor, k, "quantization")
    if quant is not None:
        mean, var = quantized_moments(mean, sigma2, quant.lsb)
    r = y - mean
    walk = axis_term(sensor, k, "bias_random_walk")
    if walk is not None:
        per_second = walk.q is not None
        q = walk.q if per_second else walk.q_per_sample
        r = walk_innovations(r, t, float(np.mean(var)), q, per_second)
        var = np.full(n, float(np.mean(var)))
    scale_to = float(np.mean(var))
    if np.any(var != scale_to):
        r = r * np.sqrt(scale_to / np.maximum(var, 1e-300))
    return AxisPrediction(bias, scale, mean, r, scale_to)
