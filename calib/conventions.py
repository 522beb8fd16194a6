"""Physical constants, axis names, the course sign convention and the effect vocabulary."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

G: float = 9.8
"""Magnitude of gravity in m/s² used by the course (the user may give another)."""

STANDARD_GRAVITY: float = 9.80665
"""The unit g, m/s² (CGPM 1901): a log in g is converted with this value, whatever the local
gravity the sensor feels (:data:`G`, ``--g`` or :func:`normal_gravity`)."""

# WGS84 defining and derived constants (NIMA TR8350.2, 3rd ed., tables 3.1 and 3.3).
WGS84_A: float = 6378137.0  # semi-major axis, m
WGS84_F: float = 1.0 / 298.257223563  # flattening
WGS84_GM: float = 3.986004418e14  # m³/s²
WGS84_OMEGA: float = 7.292115e-5  # rad/s
WGS84_GAMMA_E: float = 9.7803253359  # normal gravity at the equator, m/s²
WGS84_GAMMA_P: float = 9.8321849378  # normal gravity at the poles, m/s²
WGS84_E2: float = 0.00669437999013  # first eccentricity squared


def normal_gravity(latitude_deg: float, height_m: float = 0.0) -> float:
    """WGS84 normal gravity γ(φ, h) in m/s²: the local g a still sensor feels, to ~1e-4 m/s²
    (anomalies of the real field are not modelled).

    Parameters
    ----------
    latitude_deg : geodetic latitude φ in **degrees** (−90 … 90; north positive) — the unit
        people read off a map, as ``--latitude`` takes it.
    height_m : height h above the ellipsoid in m (−1e4 … 1e5); 0 by default.

    Notes
    -----
    Somigliana's closed formula on the ellipsoid and the second-order height expression of
    NIMA TR8350.2 (eq. 4-1 and 4-3)::

        γ(φ)    = γe (1 + k sin²φ) / √(1 − e² sin²φ),     k = (b γp)/(a γe) − 1
        γ(φ, h) = γ(φ) [1 − (2/a)(1 + f + m − 2 f sin²φ) h + (3/a²) h²],   m = ω² a² b / GM

    with b = a (1 − f). Check values: γ(0°) = γe, γ(90°) = γp; MATLAB's
    ``gravitywgs84(5000, 55, 'TaylorSeries')`` prints 9.7997.

    >>> round(normal_gravity(0.0), 10), round(normal_gravity(90.0), 10)
    (9.7803253359, 9.8321849378)
    >>> round(normal_gravity(55.0, 5000.0), 4)
    9.7997
    """
    lat = float(latitude_deg)
    h = float(height_m)
    if not np.isfinite(lat) or abs(lat) > 90.0:
        raise ValueError(f"latitude {latitude_deg!r}: expected degrees in [-90, 90]")
    if not np.isfinite(h) or not -1e4 <= h <= 1e5:
        raise ValueError(f"height {height_m!r}: expected metres in [-10000, 100000] above the "
                         "WGS84 ellipsoid")
    a, f = WGS84_A, WGS84_F
    b = a * (1.0 - f)
    k = (b * WGS84_GAMMA_P) / (a * WGS84_GAMMA_E) - 1.0
    m = WGS84_OMEGA**2 * a**2 * b / WGS84_GM
    s2 = np.sin(np.radians(lat)) ** 2
    gamma0 = WGS84_GAMMA_E * (1.0 + k * s2) / np.sqrt(1.0 - WGS84_E2 * s2)
    return float(gamma0 * (1.0 - 2.0 / a * (1.0 + f + m - 2.0 * f * s2) * h
                           + 3.0 / a**2 * h**2))

AXES: tuple[str, str] = ("x", "y")
"""Column order of every (N, 2) array: x first, then y."""

PARAM_NAMES: tuple[str, str] = ("bias", "scale")
"""Order of the per-axis parameter vector: bias (m/s²), scale (dimensionless)."""

JOINT_PARAM_NAMES: tuple[str, ...] = ("bias_x", "scale_x", "bias_y", "scale_y")


def reference_accel(tita: np.ndarray, g: float = G) -> np.ndarray:
    """Reference specific force on the tilt table, course convention.

    Parameters
    ----------
    tita : (N,) array, rad
        Table angle.
    g : float, m/s²
        Magnitude of gravity.

    Returns
    -------
    (N, 2) array, m/s²
        ``[A_rx, A_ry] = [-g sin θ, -g cos θ]`` (course report, eq. 12–13). At θ = 0 the y axis
        points down the gravity vector, so it reads -g; tilting by +θ makes x read -g sin θ.
    """
    tita = np.asarray(tita, dtype=float)
    return np.column_stack([-g * np.sin(tita), -g * np.cos(tita)])


def axis_index(axis: str) -> int:
    """Column of ``axis`` ('x' or 'y') in every (N, 2) array."""
    try:
        return AXES.index(axis)
    except ValueError:
        raise ValueError(f"axis must be 'x' or 'y', got {axis!r}") from None


# ------------------------------------------------------------------ effect vocabulary
Timing = Literal["no", "yes", "units"]


@dataclass(frozen=True)
class EffectInfo:
    """One row of the effect catalog (``docs/effects.md``).

    name : JSON name.  axes : allowed axis values ("x", "y" or "both").
    keys : parameter keys (JSON), with their units in ``units``.
    timing : "no", "yes" (cannot be simulated or estimated without sample times) or "units"
        (with timing the parameter is per second, without it per sample).
    physical : True when the effect acts on the physics (the specific force at the site; the
        bench makes it by an ``MjSpec`` edit of the model), False when it is in the sensor.
    """

    name: str
    axes: tuple[str, ...]
    keys: tuple[str, ...]
    units: tuple[str, ...]
    timing: Timing
    physical: bool
    summary: str


PER_AXIS = ("x", "y")
EFFECTS: dict[str, EffectInfo] = {e.name: e for e in (
    EffectInfo("noise_level", PER_AXIS, ("sigma2",), ("(m/s²)²",), "no", False,
               "true white-noise variance differs from the stated σ²"),
    EffectInfo("misalignment", PER_AXIS, ("delta",), ("rad",), "no", True,
               "sensitive axis rotated by +δ about the hinge (+y)"),
    EffectInfo("tilt_offset", ("both",), ("delta",), ("rad",), "no", True,
               "table angle = encoder + δ (both sensors)"),
    EffectInfo("nonlinearity_k2", PER_AXIS, ("k2",), ("1/(m/s²)",), "no", False,
               "second-order response k2·a_i² (IEEE K2/K1)"),
    EffectInfo("cross_axis", PER_AXIS, ("k_ip",), ("1/(m/s²)",), "no", False,
               "cross-coupling k_ip·a_i·a_p (IEEE K_ip/K1)"),
    EffectInfo("bias_drift", PER_AXIS, ("rate", "rate_per_sample"),
               ("m/s² per s", "m/s² per sample"), "units", False,
               "linear bias drift rate·(t - t0)"),
    EffectInfo("bias_random_walk", PER_AXIS, ("q", "q_per_sample"),
               ("m/s²/√s", "m/s²/√sample"), "units", False,
               "bias random walk b_k = b_{k-1} + q·√Δt·w_k"),
    EffectInfo("quantization", PER_AXIS, ("lsb",), ("m/s²",), "no", False,
               "output rounded to multiples of lsb"),
    EffectInfo("saturation", PER_AXIS, ("limit",), ("m/s²",), "no", True,
               "true specific force clipped to ±limit (MuJoCo sensor cutoff)"),
    EffectInfo("lowpass_lag", PER_AXIS, ("tau",), ("s",), "yes", False,
               "first-order low-pass τ·dy/dt + y = u"),
    EffectInfo("lever_arm", PER_AXIS, ("pos_x", "pos_z"), ("m", "m"), "yes", True,
               "site off the hinge axis: centripetal −ω²·p and tangential α·(ŷ×p)"),
    EffectInfo("gravity_mismatch", ("both",), ("g",), ("m/s²",), "no", True,
               "true local gravity differs (absorbed by the scale factors)"),
)}
"""Effect name → catalog row, in the order of ``docs/effects.md``."""

EFFECT_NAMES: tuple[str, ...] = tuple(EFFECTS)
"""The effect vocabulary (JSON names), in the order of ``docs/effects.md``."""

NEEDS_TIMING: tuple[str, ...] = tuple(n for n, e in EFFECTS.items() if e.timing == "yes")
"""Effects that cannot be simulated or estimated without sample times (``t`` or a rate)."""

PER_SAMPLE_UNITS: tuple[str, ...] = tuple(n for n, e in EFFECTS.items() if e.timing == "units")
"""Effects whose parameter is per second with timing and per sample without it."""
