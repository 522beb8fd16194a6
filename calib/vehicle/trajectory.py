"""Vehicle trajectory from the two accelerometers: correct, integrate twice.

Frames, units and signs
-----------------------
The vehicle moves in the horizontal x-y plane without rotating (course assumption), so the
x accelerometer measures ``d²x/dt²`` and the y accelerometer ``d²y/dt²`` (m/s², world axes).
Positions in m, velocities in m/s, time in s. Columns x, then y.

Model (course)::

    A_m = (1 + scale) · A_r + bias + v          (measured, per axis)
    Â_r = (A_m - bias) / (1 + scale)            (corrected,
    :func:`calib.calibration.correct.correct`) V(t) = V0 + ∫₀ᵗ Â_r dτ,     P(t) = P0 + ∫₀ᵗ V dτ

Both integrals are cumulative quadratures of the samples (trapezoid by default, as the course's
``cumtrapz``; composite Simpson as an option). Each is linear in the samples, so the final
position is a weighted sum of the accelerations::

    P(t_end) = P0 + V0 · (t_end - t_0) + Σ_k w_k · Â_r[k]

with weights ``w`` given by :func:`double_integral_weights`; the uncertainty of the arrival
point (:mod:`calib.vehicle.region`) is built on them.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Literal

import numpy as np
from scipy.integrate import cumulative_simpson, cumulative_trapezoid

from calib.calibration.correct import correct
from calib.files.course import Acel
from calib.results import ResultMixin, readonly

if TYPE_CHECKING:  # only for annotations: calib.calibration.tilt_plane is a sibling module
    from calib.calibration.tilt_plane import Calibration

Integrator = Literal["trapezoid", "simpson"]
INTEGRATORS: tuple[str, ...] = ("trapezoid", "simpson")

COURSE_P0: tuple[float, float] = (0.0, 0.0)
"""Initial position of the course vehicle, m (course ``datos.txt``)."""
COURSE_V0: tuple[float, float] = (1.0, 3.0)
"""Initial velocity of the course vehicle, m/s (course ``datos.txt``)."""


def check_integrator(integrator: str) -> None:
    """Refuse an integrator name outside ``INTEGRATORS`` (ValueError naming the choices)."""
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")


def cumulative_integral(y: np.ndarray, t: np.ndarray, integrator: Integrator = "trapezoid"
                        ) -> np.ndarray:
    """Cumulative integral ``∫_{t_0}^{t_k} y dτ`` along axis 0, starting at 0.

    Parameters
    ----------
    y : (M,) or (M, c) samples.  t : (M,) strictly increasing times, s.
    integrator : "trapezoid" (``scipy.integrate.cumulative_trapezoid``, the course's
        ``cumtrapz``) or "simpson" (``scipy.integrate.cumulative_simpson``, composite
        Simpson 1/3 on every sub-interval).

    Returns
    -------
    Same shape as ``y``; row 0 is 0.
    """
    check_integrator(integrator)
    y = np.asarray(y, dtype=float)
    t = np.asarray(t, dtype=float)
    d = np.diff(t)
    uniform = d.size > 0 and np.max(np.abs(d - d[0])) <= 1e-9 * d[0]
    if integrator == "trapezoid":
        if uniform:
            return cumulative_trapezoid(y, dx=d[0], axis=0, initial=0)
        return cumulative_trapezoid(y, x=t, axis=0, initial=0)
    if uniform:
        return cumulative_simpson(y, dx=d[0], axis=0, initial=0)
    return cumulative_simpson(y, x=t, axis=0, initial=0)


def integrate_twice(
    t: np.ndarray, acc: np.ndarray, p0, v0, integrator: Integrator = "trapezoid"
) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity from acceleration samples.

    ``V = V0 + ∫ A``, ``P = P0 + ∫ V`` (cumulative, at the sample times).

    Parameters
    ----------
    t : (M,) s.  acc : (M, 2) m/s².  p0 : (2,) m.  v0 : (2,) m/s.

    Returns
    -------
    pos : (M, 2) m.  vel : (M, 2) m/s.
    """
    vel = np.asarray(v0, dtype=float) + cumulative_integral(acc, t, integrator)
    pos = np.asarray(p0, dtype=float) + cumulative_integral(vel, t, integrator)
    return pos, vel


def trapezoid_weights_uniform(m: int, h: float) -> np.ndarray:
    """Closed-form weights of the double cumulative trapezoid on a uniform grid.

    With ``n = m - 1`` intervals of width ``h``::

        V_i = V0 + h (A_0/2 + A_1 + … + A_{i-1} + A_i/2)
        P_n = P0 + h (V_0/2 + V_1 + … + V_{n-1} + V_n/2)

    Collecting the coefficient of each ``A_k`` gives ``P_n = P0 + V0·n·h + Σ w_k A_k`` with::

        w_0 = h² (2n - 1)/4,    w_k = h² (n - k)  (0 < k < n),    w_n = h²/4

    (Σ w_k = h² n²/2 = T²/2: exact for a constant acceleration.)
    """
    if m < 2:
        raise ValueError(f"need at least 2 samples, got {m}")
    n = m - 1
    w = h * h * (n - np.arange(m, dtype=float))
    w[0] = h * h * (2 * n - 1) / 4.0
    w[n] = h * h / 4.0
    return w


def trapezoid_sum_w2_uniform(m: int, h: float) -> float:
    """``Σ w_k²`` of :func:`trapezoid_weights_uniform` in closed form.

    ``Σ w² = h⁴ [ (2n-1)²/16 + 1/16 + (n-1) n (2n-1)/6 ]``, ``n = m - 1``
    (``Σ_{j=1}^{n-1} j² = (n-1)n(2n-1)/6``). For large ``n``: ``≈ h⁴ n³/3 = h T³/3``, the
    variance growth of a twice-integrated white noise of spectral density ``σ² h``.
    """
    n = m - 1
    return h**4 * ((2 * n - 1) ** 2 / 16.0 + 1.0 / 16.0 + (n - 1) * n * (2 * n - 1) / 6.0)


def _interval_bands(t: np.ndarray, integrator: Integrator, period: int = 5
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sparse (rows, cols, values) of the interval-integral matrix ``S``.

    ``S`` is (M-1, M): ``(S y)_i = ∫_{t_i}^{t_{i+1}} y`` as the quadrature computes it (the
    increments of :func:`cumulative_integral`). Both rules are local (each interval uses at
    most the 4 samples ``i-1 … i+2``), so probing with ``period`` ≥ 4 comb vectors recovers
    every entry exactly: a row never touches two columns of the same comb.
    """
    m = t.shape[0]
    idx = np.arange(m)
    probes = (idx[:, None] % period == np.arange(period)[None, :]).astype(float)
    incr = np.diff(cumulative_integral(probes, t, integrator), axis=0)  # (M-1, period)
    rows, cols, vals = [], [], []
    for off in range(-2, 4):
        j = np.arange(m - 1) + off
        ok = (j >= 0) & (j < m)
        r = np.flatnonzero(ok)
        v = incr[r, j[ok] % period]
        keep = v != 0.0
        rows.append(r[keep])
        cols.append(j[ok][keep])
        vals.append(v[keep])
    return np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)


def _weights_from_bands(t: np.ndarray, integrator: Integrator) -> np.ndarray:
    """Weights ``w`` of ``P_end - P0 - V0 T`` by the adjoint of the two linear quadratures.

    ``V_k = V0 + Σ_{i<k} (S A)_i`` and ``P_end = P0 + Σ_i (S V)_i = P0 + uᵀV`` with
    ``u = 1ᵀS``. Substituting, ``P_end = P0 + V0·uᵀ1 + Σ_i z_i (S A)_i`` with
    ``z_i = Σ_{k>i} u_k``, hence ``w = Sᵀ z`` — O(M), no M×M matrix.
    """
    m = t.shape[0]
    rows, cols, vals = _interval_bands(t, integrator)
    u = np.bincount(cols, weights=vals, minlength=m)
    z = np.concatenate([np.cumsum(u[::-1])[::-1][1:], [0.0]])[: m - 1]  # z_i = Σ_{k>i} u_k
    return np.bincount(cols, weights=vals * z[rows], minlength=m)


@lru_cache(maxsize=16)
def _weights_cached(t_bytes: bytes, m: int, integrator: str) -> np.ndarray:
    t = np.frombuffer(t_bytes, dtype=float, count=m)
    w = _weights_from_bands(t, integrator)  # type: ignore[arg-type]
    w.setflags(write=False)
    return w


def double_integral_weights(t: np.ndarray, integrator: Integrator = "trapezoid") -> np.ndarray:
    """Weights ``w`` (M,) with ``P(t_end) = P0 + V0·(t_end - t_0) + Σ_k w_k A_k``, s².

    Exact for the quadrature used by :func:`integrate_twice` (the map is linear; ``w`` is
    computed from the rule itself, see :func:`_weights_from_bands`). For the trapezoid on a
    uniform grid it equals the closed form :func:`trapezoid_weights_uniform`. Both rules
    integrate constants exactly, so ``Σ w = (t_end - t_0)²/2``.
    """
    check_integrator(integrator)
    t = np.ascontiguousarray(np.asarray(t, dtype=float))
    if t.ndim != 1 or t.shape[0] < 3:
        raise ValueError(f"t must be 1-D with at least 3 samples, got shape {t.shape}")
    return _weights_cached(t.tobytes(), t.shape[0], integrator)


def last_row(name: str, doc: str) -> property:
    """A read-only property of a run: a copy of the last row of its array ``name`` (the
    final value of a sampled quantity), documented by ``doc``."""

    def final(self) -> np.ndarray:
        return getattr(self, name)[-1].copy()

    return property(final, doc=doc)


@dataclass(frozen=True, eq=False, kw_only=True)
class SampledRun(ResultMixin):
    """What the two dead reckonings share (:class:`Trajectory`,
    :class:`calib.vehicle.turning_trajectory.TurningTrajectory`): the fields below, their float
    arrays frozen as copies (``_ARRAYS``, the samples a run adds; ``_FIXED``, the four
    below), and :meth:`to_state`, :meth:`to_dict` plus the samples.

    Attributes (keyword-only)
    ----------
    p0 : (2,) m.  v0 : (2,) m/s — the initial position and velocity (world axes).
    bias : (2,) m/s² and scale : (2,) dimensionless — the correction used.
    integrator : "trapezoid" or "simpson" (:func:`integrate_twice`).
    """

    p0: np.ndarray
    v0: np.ndarray
    bias: np.ndarray
    scale: np.ndarray
    integrator: Integrator = "trapezoid"

    _ARRAYS = ()
    _FIXED = ("p0", "v0", "bias", "scale")

    def __post_init__(self) -> None:
        for name in (*self._ARRAYS, *self._FIXED):
            object.__setattr__(self, name, readonly(getattr(self, name)))

    def to_state(self) -> dict:
        """:meth:`to_dict` plus every sample array (exact rebuild by ``from_dict``)."""
        d = self.to_dict()  # type: ignore[attr-defined]
        d.update({name: getattr(self, name).tolist() for name in self._ARRAYS})
        return d


@dataclass(frozen=True, eq=False)
class Trajectory(SampledRun):
    """Raw and corrected trajectories of a vehicle run.

    Attributes
    ----------
    t : (M,) s.
    acc_raw : (M, 2) measured ``A_m``, m/s².   acc_corrected : (M, 2) ``Â_r``, m/s².
    pos_raw, vel_raw : (M, 2) m, m/s — integrated from ``A_m`` as measured.
    pos_corrected, vel_corrected : (M, 2) m, m/s — integrated from ``Â_r``.
    p0 : (2,) m.  v0 : (2,) m/s.
    bias : (2,) m/s² and scale : (2,) used for the correction.
    integrator : "trapezoid" or "simpson".
    (``p0`` … ``integrator`` are keyword-only: :class:`SampledRun`.)

    Serialisation: :meth:`to_dict` (printed by ``trajectory --json``) holds the final values
    only; :meth:`to_state` adds every array and ``Trajectory.from_dict(tr.to_state()) == tr``.
    """

    _TITLE = "Trajectory"
    _UNITS = ("t s; positions and P0 m; velocities and V0 m/s; accelerations and bias m/s²; "
              "scale dimensionless")

    t: np.ndarray
    acc_raw: np.ndarray
    acc_corrected: np.ndarray
    pos_raw: np.ndarray
    vel_raw: np.ndarray
    pos_corrected: np.ndarray
    vel_corrected: np.ndarray

    _ARRAYS = ("t", "acc_raw", "acc_corrected", "pos_raw", "vel_raw", "pos_corrected",
               "vel_corrected")

    @property
    def duration(self) -> float:
        """``t_end - t_0``, s."""
        return float(self.t[-1] - self.t[0])

    final_raw = last_row("pos_raw", "(2,) final position integrated from the uncorrected "
                         "readings, m.")
    final_corrected = last_row("pos_corrected", "(2,) final position integrated from the "
                               "corrected accelerations, m.")
    final_velocity_raw = last_row("vel_raw", "(2,) final velocity integrated from the "
                                  "uncorrected readings, m/s.")
    final_velocity_corrected = last_row("vel_corrected", "(2,) final velocity integrated from "
                                        "the corrected accelerations, m/s.")

    def weights(self) -> np.ndarray:
        """Double-integration weights of this run (see :func:`double_integral_weights`)."""
        return double_integral_weights(self.t, self.integrator)

    def to_dict(self, include_arrays: bool = False) -> dict:
        d = {
            "final_raw": self.final_raw.tolist(),
            "final_corrected": self.final_corrected.tolist(),
            "final_velocity_raw": self.final_velocity_raw.tolist(),
            "final_velocity_corrected": self.final_velocity_corrected.tolist(),
            "p0": self.p0.tolist(), "v0": self.v0.tolist(),
            "bias": self.bias.tolist(), "scale": self.scale.tolist(),
            "integrator": self.integrator, "duration": self.duration,
            "n_samples": int(self.t.shape[0]),
        }
        if include_arrays:
            d.update(t=self.t.tolist(), pos_raw=self.pos_raw.tolist(),
                     pos_corrected=self.pos_corrected.tolist())
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Trajectory:
        """Rebuild from :meth:`to_state` (exact).

        Parameters
        ----------
        d : mapping with ``p0`` (2,) m, ``v0`` (2,) m/s, ``bias`` (2,) m/s², ``scale`` (2,),
            ``integrator`` and the sample arrays ``t`` (M,) s, ``acc_raw``, ``acc_corrected``
            (M, 2) m/s², ``pos_raw``, ``pos_corrected`` (M, 2) m, ``vel_raw``,
            ``vel_corrected`` (M, 2) m/s. With only ``t`` and ``acc_raw`` the rest is
            recomputed (:func:`correct_and_integrate`). :meth:`to_dict` alone holds no samples
            and raises ``ValueError``.

        Examples
        --------
        >>> import numpy as np
        >>> from calib import Trajectory
        >>> from calib.vehicle.trajectory import correct_and_integrate
        >>> t = np.linspace(0, 10, 101)
        >>> tr = correct_and_integrate(t, np.ones((101, 2)), [0.1, 0.0], [0.01, 0.0])
        >>> Trajectory.from_dict(tr.to_state()) == tr
        True
        """
        if all(k in d for k in cls._ARRAYS):
            return cls(*(d[k] for k in cls._ARRAYS), p0=d["p0"], v0=d["v0"], bias=d["bias"],
                       scale=d["scale"], integrator=d["integrator"])
        if "t" in d and "acc_raw" in d:
            return correct_and_integrate(d["t"], d["acc_raw"], d["bias"], d["scale"], d["p0"],
                                         d["v0"], d["integrator"])
        raise ValueError("this trajectory mapping has no samples (the printed summary of "
                         "to_dict()); rebuild from Trajectory.to_state()")

    def summary(self) -> str:
        fr, fc, vc = self.final_raw, self.final_corrected, self.final_velocity_corrected
        return "\n".join([
            f"Trajectory: {self.t.shape[0]} samples over {self.duration:g} s, "
            f"{self.integrator} double integration, P0 = {self.p0.tolist()} m, "
            f"V0 = {self.v0.tolist()} m/s",
            f"  correction: bias = [{self.bias[0]:.6g}, {self.bias[1]:.6g}] m/s², "
            f"scale = [{self.scale[0]:.6g}, {self.scale[1]:.6g}] (dimensionless)",
            f"  final position, raw       : ({fr[0]:10.3f}, {fr[1]:10.3f}) m",
            f"  final position, corrected : ({fc[0]:10.3f}, {fc[1]:10.3f}) m",
            f"  final velocity, corrected : ({vc[0]:10.3f}, {vc[1]:10.3f}) m/s",
        ])


def correct_and_integrate(
    t: np.ndarray, a_m: np.ndarray, bias, scale, p0=COURSE_P0, v0=COURSE_V0,
    integrator: Integrator = "trapezoid",
) -> Trajectory:
    """Correct the readings with ``(bias, scale)`` and integrate raw and corrected.

    Parameters
    ----------
    t : (M,) s, strictly increasing.  a_m : (M, 2) measured accelerations, m/s².
    bias : (2,) m/s².  scale : (2,) dimensionless.  p0 : (2,) m.  v0 : (2,) m/s.
    integrator : "trapezoid" (default, the course) or "simpson".
    """
    check_integrator(integrator)
    t = np.asarray(t, dtype=float)
    a_m = np.asarray(a_m, dtype=float)
    if a_m.ndim != 2 or a_m.shape != (t.shape[0], 2):
        raise ValueError(f"accelerations must be ({t.shape[0]}, 2), got {a_m.shape}")
    if t.shape[0] < 3:
        raise ValueError(f"need at least 3 samples to integrate, got {t.shape[0]}")
    bias = np.broadcast_to(np.asarray(bias, dtype=float), (2,))
    scale = np.broadcast_to(np.asarray(scale, dtype=float), (2,))
    p0 = np.broadcast_to(np.asarray(p0, dtype=float), (2,))
    v0 = np.broadcast_to(np.asarray(v0, dtype=float), (2,))
    a_c = correct(a_m, bias, scale)
    pos_r, vel_r = integrate_twice(t, a_m, p0, v0, integrator)
    pos_c, vel_c = integrate_twice(t, a_c, p0, v0, integrator)
    return Trajectory(t, a_m, a_c, pos_r, vel_r, pos_c, vel_c, p0=p0, v0=v0, bias=bias,
                      scale=scale, integrator=integrator)


def compute_trajectory(
    acel: Acel, calibration: Calibration, p0=COURSE_P0, v0=COURSE_V0,
    integrator: Integrator = "trapezoid",
) -> Trajectory:
    """Trajectory of a vehicle run corrected with a calibration.

    Parameters
    ----------
    acel : the run (``t`` (M,) s, ``aerr`` (M, 2) m/s², uncorrected).
    calibration : bias and scale of both axes (:func:`calib.calibration.tilt_plane.calibrate`).
    p0 : (2,) initial position, m (course: (0, 0)).  v0 : (2,) initial velocity, m/s
        (course: (1, 3)).
    integrator : "trapezoid" or "simpson".

    Returns
    -------
    Trajectory : raw and corrected positions (M, 2) m, velocities (M, 2) m/s, accelerations
    (M, 2) m/s²; ``final_corrected`` (2,) m.

    Examples
    --------
    >>> import numpy as np
    >>> from calib import Acel, Ensayo, calibrate, compute_trajectory
    >>> th = np.linspace(0.0, 2 * np.pi, 100, endpoint=False)
    >>> datos = np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)]) + 0.1
    >>> cal = calibrate(Ensayo(th, datos), noise_var=[0.25, 0.64])
    >>> t = np.arange(1001) * 0.01                      # 10 s at 100 Hz, standing still
    >>> tr = compute_trajectory(Acel(t, np.full((1001, 2), 0.1)), cal, v0=(0.0, 0.0))
    >>> np.round(tr.final_corrected, 9).tolist(), np.round(tr.final_raw, 6).tolist()
    ([0.0, 0.0], [5.0, 5.0])
    """
    return correct_and_integrate(acel.t, acel.aerr, calibration.bias, calibration.scale,
                                 p0, v0, integrator)


__all__ = [
    "COURSE_P0", "COURSE_V0", "INTEGRATORS", "SampledRun", "Trajectory", "check_integrator",
    "compute_trajectory", "correct_and_integrate", "cumulative_integral", "double_integral_weights",
    "integrate_twice", "last_row", "trapezoid_sum_w2_uniform", "trapezoid_weights_uniform",
]
