"""An effect at a given size: its linear coefficients, and synthetic readings for the MC.

Truth of the synthetic sensor: bias 0, scale 0 (gain 1), so an effect's coefficient on its
model column (:mod:`calib.effects.linear`, :mod:`calib.effects.tilt`) follows from the size
in the catalog's unit (``calib.conventions.EFFECTS``):

=================== ============================= =========================================
effect               size (unit)                   coefficient(s) c on the effect's columns
=================== ============================= =========================================
misalignment         δ (rad)                       ``tan δ`` on ``sgn·A_p``
tilt_offset          δ (rad), both axes            ``sin δ`` on the shared column
nonlinearity_k2      k2 (1/(m/s²))                 k2 on ``A_r²``
cross_axis           k_ip (1/(m/s²))               k_ip on ``A_r·A_p``
bias_drift           rate (m/s² per s)             rate (timed), ``rate·T/(N-1)`` per sample
lever_arm            pos_z (m), pos_x = 0          x: (0, pos_z) on (ω², α); y: (pos_z, 0)
=================== ============================= =========================================

(a gain ``1 + s`` multiplies every coefficient: λ scales by ``(1 + s)²``, ±6 % for the
course's |s| ≈ 0.03; ``analyze_design(gain=…)`` includes it, so the sizes it states are those
of the sensor with that gain). The Monte Carlo effects act on the reading of ``axis``:
``lowpass_lag`` ``LPF_τ(A_r)`` (:func:`calib.filters.lowpass`), ``saturation``
``clip(A_r, ±L)``, ``bias_random_walk`` ``+ Σ q·√Δt·w_k`` (Δt the sample period), ``noise_level``
white noise of variance ``size`` instead of the stated σ², ``quantization`` readings rounded
to multiples of ``lsb``.
"""

from __future__ import annotations

import numpy as np

from calib.conventions import AXES, EFFECTS, reference_accel
from calib.design.experiments import Experiment
from calib.filters import lowpass
from calib.stats.diagnostics import angular_rates

LINEAR: tuple[str, ...] = ("misalignment", "tilt_offset", "nonlinearity_k2", "cross_axis",
                           "bias_drift", "lever_arm")
"""Effects linear in their parameter: analytic power (non-central χ²)."""
SIMULATED: tuple[str, ...] = ("lowpass_lag", "saturation", "bias_random_walk", "noise_level",
                              "quantization")
"""Effects tested by Monte Carlo through the gap detection."""


def size_unit(name: str) -> str:
    """Unit of an effect's size (its first catalog key; lever_arm: pos_z)."""
    info = EFFECTS[name]
    return info.units[info.keys.index("pos_z")] if name == "lever_arm" else info.units[0]


def coefficients(name: str, size: float, exp: Experiment, axis: str) -> np.ndarray:
    """Coefficient(s) of a linear effect's model column(s) at ``size`` (module table)."""
    if name == "misalignment":
        return np.array([np.tan(size)])
    if name == "tilt_offset":
        return np.array([np.sin(size)])
    if name in ("nonlinearity_k2", "cross_axis"):
        return np.array([float(size)])
    if name == "bias_drift":
        return np.array([size * (1.0 if exp.timed else exp.period)])
    if name == "lever_arm":
        return np.array([0.0, size]) if axis == "x" else np.array([size, 0.0])
    raise ValueError(f"{name} is not linear in its parameter")


def size_of(name: str, c: float, exp: Experiment) -> float | None:
    """The size whose coefficient magnitude is ``c`` ≥ 0 (inverse of :func:`coefficients`);
    None when no size reaches it (a tilt with sin δ > 1)."""
    if name == "misalignment":
        return float(np.arctan(c))
    if name == "tilt_offset":
        return float(np.arcsin(c)) if c <= 1.0 else None
    if name == "bias_drift":
        return float(c / (1.0 if exp.timed else exp.period))
    return float(c)


def _linear_signal(exp: Experiment, name: str, size: float, axis: str, g: float
                   ) -> np.ndarray:
    """(N, 2) the specific force along the sensitive axes with a linear effect at ``size``
    (the physics, not the model's columns: the Monte Carlo of the whole workflow)."""
    th = exp.theta()
    a_r = reference_accel(th, g)
    k = AXES.index(axis)
    y = a_r.copy()
    if name == "misalignment":
        y[:, k] = reference_accel(th + size, g)[:, k]
    elif name == "tilt_offset":
        y = reference_accel(th + size, g)
    elif name == "nonlinearity_k2":
        y[:, k] = a_r[:, k] + size * a_r[:, k] ** 2
    elif name == "cross_axis":
        y[:, k] = a_r[:, k] + size * a_r[:, k] * a_r[:, 1 - k]
    elif name == "bias_drift":
        tc = exp.times() - exp.times()[0] if exp.timed else np.arange(exp.n) * exp.period
        y[:, k] = a_r[:, k] + size * tc
    elif name == "lever_arm":  # pos_z on the hinge normal: tangential α·z on x, ω²·z on y
        w, al = angular_rates(th, exp.times())
        y[:, k] = a_r[:, k] + size * (al if k == 0 else w * w)
    return y


def readings(exp: Experiment, name: str | None, size: float, axis: str,
             noise_var: np.ndarray, g: float, rng: np.random.Generator,
             gain: float = 1.0) -> np.ndarray:
    """Synthetic readings (N, 2), m/s², with the effect ``name`` on ``axis`` (module
    docstring; a linear one by its physics, :func:`_linear_signal`); ``name`` None: the
    nominal sensor. ``gain`` = 1 + scale of the sensor multiplies the specific force (the
    effects act through it, as in the gap's model)."""
    th = exp.theta()
    a_r = reference_accel(th, g)
    k = AXES.index(axis)
    sig = np.sqrt(np.asarray(noise_var, float))
    std = sig.copy()
    if name == "noise_level":
        std[k] = np.sqrt(size)
    y = a_r.copy()
    if name in LINEAR:
        y = _linear_signal(exp, name, size, axis, g)
    elif name == "lowpass_lag":
        y[:, k] = lowpass(a_r[:, k], exp.times(), size)
    elif name == "saturation":
        y[:, k] = np.clip(a_r[:, k], -size, size)
    y = gain * y
    noise = rng.standard_normal(a_r.shape) * std
    y = y + noise
    if name == "bias_random_walk":
        steps = rng.standard_normal(exp.n - 1) * size * np.sqrt(exp.period)
        y[1:, k] += np.cumsum(steps)
    elif name == "quantization":
        y[:, k] = np.round(y[:, k] / size) * size
    return y
