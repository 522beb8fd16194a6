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
course's |s| ≈ 0.03). The Monte Carlo effects act on the reading of ``axis``:
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


def readings(exp: Experiment, name: str | None, size: float, axis: str,
             noise_var: np.ndarray, g: float, rng: np.random.Generator) -> np.ndarray:
    """Synthetic readings (N, 2), m/s², with the Monte Carlo effect ``name`` on ``axis``
    (module docstring); ``name`` None: the nominal sensor."""
    th = exp.theta()
    a_r = reference_accel(th, g)
    k = AXES.index(axis)
    sig = np.sqrt(np.asarray(noise_var, float))
    std = sig.copy()
    if name == "noise_level":
        std[k] = np.sqrt(size)
    y = a_r.copy()
    if name == "lowpass_lag":
        y[:, k] = lowpass(a_r[:, k], exp.times(), size)
    elif name == "saturation":
        y[:, k] = np.clip(a_r[:, k], -size, size)
    noise = rng.standard_normal(a_r.shape) * std
    y = y + noise
    if name == "bias_random_walk":
        steps = rng.standard_normal(exp.n - 1) * size * np.sqrt(exp.period)
        y[1:, k] += np.cumsum(steps)
    elif name == "quantization":
        y[:, k] = np.round(y[:, k] / size) * size
    return y
