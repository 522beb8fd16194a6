"""Before fusing: do the receiver's fixes (``gps.mat``) and the gyro agree with the
dead-reckoned path at all? Unit, axis, time and offset mistakes named in one line (issue 23).

The free run
------------
The filter with every fix rejected (``gate_alpha = 1``, :func:`calib.fusion.kalman.gate_threshold`)
is the dead reckoning with its covariance, and it still records each fix's innovation
against it: ``ν_j = z_j - p̂(t_j)``, ``S_j = P_pp(t_j) + σ_pos² I`` (m, m²). Under the right
inputs ``ν_j ~ N(0, S_j)``, so ``NIS_j = ν_jᵀ S_j⁻¹ ν_j ~ χ²(2)`` for each j — but the NIS of
different fixes are strongly dependent (one calibration error moves the whole dead-reckoned
path).

The test
--------
The statistic is the median of the M NIS. Whatever their dependence, the median reaches x
only if at least M/2 of them do, and by Markov's inequality on that count
``P(median ≥ x) ≤ 2 P(χ²₂ ≥ x)``. So the inputs are refused when::

    median_j NIS_j ≥ x = χ²₂⁻¹(1 - α/2),     α = 10⁻⁴ (PRECHECK_ALPHA)  →  x = 19.8

a false refusal rate ≤ 10⁻⁴ on right inputs, whatever the correlation; the median also
ignores a few outliers (the gate's job, :mod:`calib.fusion.innovation_check`). On a refusal each
mistake below is tried as an alternative reading of the inputs; the one with the smallest
median NIS, if that median is below x, is named (one line, the file and variable, what to
do); if none fits, the message says the fixes disagree with the path and lists what to
check. Nothing is corrected silently.

| mistake | alternative tried | message says |
|---|---|---|
| km instead of m | ``1000·pos`` (and ``pos/1000``: mm) | multiply ``pos`` by 1000 |
| swapped columns | ``pos[:, ::-1]`` (also with ×1000) | swap the columns |
| time offset | ``p̂(t_j - τ)``, τ over ±¾ run, step ¼ fix interval | ``t_gps`` τ s late |
| constant offset | ``ν_j - ō``, ``ō`` the S⁻¹-weighted mean of ν | ``pos`` is offset by ō m |
| gyro in deg/s | the turning free run from ``gyro·π/180`` (and ``·180/π``) | convert ``gyro`` |
| wrong ψ0 | the path's driven part turned by δ (:func:`heading_offset`) | ψ0 off by δ |

The lag scan interpolates the free run's path and covariance linearly between its nodes (the
IMU samples, 10 ms apart on the bench). Units: m, m², s, rad/s.

Gyro plausibility (:func:`check_gyro`, before any run): finite, not exactly constant (a live
gyro has white noise; an all-zero or frozen channel cannot give the heading a turning run
needs) and ``|ω| ≤ 35 rad/s`` (:data:`MAX_YAW_RATE`, 2000 °/s: the largest full scale of
common MEMS gyros, e.g. Bosch BMI088, InvenSense ICM-20948; a value beyond it is not a
reading of a yaw rate in rad/s).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import stats

from calib.input_rules import DataError

PRECHECK_ALPHA = 1e-4
"""Largest false-refusal rate of the free-run test on right inputs (module docstring)."""

MAX_SCAN_FIXES = 600
"""At most this many fixes (evenly spread) enter the lag scan (bounded work)."""

MAX_SCAN_LAGS = 1200
"""At most about this many lags are scanned (the step grows with the run)."""

MAX_YAW_RATE = 35.0
"""|ω| bound, rad/s (2000 °/s, the largest common MEMS full scale)."""


def median_threshold(alpha: float = PRECHECK_ALPHA, d: int = 2) -> float:
    """``x = χ²_d⁻¹(1 - α/2)``: the median NIS refused at false-refusal rate ≤ α."""
    return float(stats.chi2.isf(alpha / 2.0, d))


@dataclass(frozen=True)
class FreeRun:
    """The dead reckoning with its covariance and each fix's innovation against it.

    t_gps : (M,) s.  z : (M, 2) fixes, m.  nu : (M, 2) innovations, m.  S : (M, 2, 2) m².
    path_t : (K,) s the nodes; path_p : (K, 2) m; path_cov : (K, 2, 2) m²; R : (2, 2) m².
    """

    t_gps: np.ndarray
    z: np.ndarray
    nu: np.ndarray
    S: np.ndarray
    path_t: np.ndarray
    path_p: np.ndarray
    path_cov: np.ndarray
    R: np.ndarray
    v0: np.ndarray | None = None

    @classmethod
    def of(cls, fusion, z) -> FreeRun:
        """From a single-run :class:`calib.fusion.linear.FusionResult` run with ``gate_alpha=1`` and
        ``keep="all"``, and the position fixes ``z`` (M, 2) m it was given."""
        return cls(np.asarray(fusion.t_gps, float), np.asarray(z, float)[:, :2],
                   np.asarray(fusion.innovations, float)[:, :2],
                   np.asarray(fusion.innovation_covs, float)[:, :2, :2],
                   np.asarray(fusion.times, float), np.asarray(fusion.estimates, float)[:, :2],
                   np.asarray(fusion.covariances, float)[:, :2, :2],
                   np.asarray(fusion.R, float)[:2, :2],
                   np.asarray(fusion.estimates, float)[0, 2:4])

    @property
    def p_hat(self) -> np.ndarray:
        """(M, 2) the dead-reckoned position at each fix, m."""
        return self.z - self.nu

    def median_nis(self, nu: np.ndarray | None = None, S: np.ndarray | None = None) -> float:
        """Median of ``νᵀ S⁻¹ ν`` (this run's, or of other ν/S of the same shape)."""
        nu = self.nu if nu is None else nu
        S = self.S if S is None else S
        return float(np.median(_nis(nu, S)))


def _nis(nu: np.ndarray, S: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", nu, np.linalg.solve(S, nu[..., None])[..., 0])


def best_lag(free: FreeRun) -> tuple[float, float]:
    """``(τ, median NIS)`` of the best time shift: the fix at ``t_j`` compared with the path
    at ``t_j - τ`` (s), τ over ±¾ of the run in steps of a quarter of the median fix interval
    (coarser on long runs: at most :data:`MAX_SCAN_LAGS` lags, :data:`MAX_SCAN_FIXES` fixes),
    each τ with at least ``max(3, M/4)`` fixes whose shifted time is inside the run."""
    t, z, m = free.t_gps, free.z, free.t_gps.shape[0]
    if m < 3:
        return 0.0, math.inf
    if m > MAX_SCAN_FIXES:  # bounded work: evenly spread fixes are enough to find a lag
        keep = np.linspace(0, m - 1, MAX_SCAN_FIXES).round().astype(int)
        t, z, m = t[keep], z[keep], MAX_SCAN_FIXES
    span = float(free.path_t[-1] - free.path_t[0])
    step = max(0.25 * float(np.median(np.diff(t))), 1.5 * span / MAX_SCAN_LAGS)
    n_side = int(0.75 * span / step)
    taus = np.arange(-n_side, n_side + 1) * step
    tt = t[None, :] - taus[:, None]                       # (L, M) the path's times
    ok = (tt >= free.path_t[0]) & (tt <= free.path_t[-1])
    p = np.stack([np.interp(tt, free.path_t, free.path_p[:, i]) for i in range(2)], -1)
    P = np.empty((*tt.shape, 2, 2))
    for i in range(2):
        for j in range(2):
            P[..., i, j] = np.interp(tt, free.path_t, free.path_cov[:, i, j])
    nis = _nis(z[None] - p, P + free.R)
    nis = np.where(ok, nis, np.nan)
    enough = ok.sum(axis=1) >= max(3, math.ceil(m / 4))
    med = np.full(taus.shape, np.inf)
    med[enough] = np.nanmedian(nis[enough], axis=1)
    k = int(np.argmin(med))
    # the median finds the lag; the mean NIS (all fixes, more efficient) refines it on the
    # neighbouring grid points by a parabola through the three
    if 0 < k < taus.size - 1 and np.all(enough[k - 1:k + 2]):
        f = np.nanmean(nis[k - 1:k + 2], axis=1)
        curv = f[0] - 2 * f[1] + f[2]
        if curv > 0:
            tau = float(taus[k] + 0.5 * step * (f[0] - f[2]) / curv)
            return tau, float(med[k])
    return float(taus[k]), float(med[k])


def heading_offset(free: FreeRun, psi0: float, source: str) -> tuple[float, str]:
    """The turning run's alternative "ψ0 is off by δ" as ``(median NIS, message)``.

    A constant heading error δ rotates every world acceleration by δ, so the dead-reckoned
    path is ``p0 + v0 t + R(δ) d(t)`` with ``d`` the acceleration-driven part (``v0`` world
    axes, not rotated). δ from the fixes in closed form (2-D Procrustes on
    ``e_j = z_j - p0 - v0 t_j`` against ``d_j``): ``δ = atan2(Σ d_j × e_j, Σ d_j · e_j)``;
    the residuals ``e_j - R(δ) d_j`` against the same S_j. ``psi0`` rad, the one given."""
    t0 = free.path_t[0]
    base = free.path_p[0] + np.outer(free.t_gps - t0, free.v0)
    d, e = free.p_hat - base, free.z - base
    delta = math.atan2(float(np.sum(d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0])),
                       float(np.sum(d[:, 0] * e[:, 0] + d[:, 1] * e[:, 1])))
    c, s = math.cos(delta), math.sin(delta)
    rd = d @ np.array([[c, -s], [s, c]]).T
    return (free.median_nis(e - rd, free.S),
            f"{source}: the fixes match the dead-reckoned path turned by {delta:+.3g} rad: the "
            f"initial heading psi0 = {psi0:g} rad looks off; try psi0 = {psi0 + delta:.4g} rad "
            "(or give --psi0-sigma)")


def explain(free: FreeRun, source: str) -> list[tuple[float, str]]:
    """The alternative readings of the fixes of ``source`` (module docstring table), as
    ``(median NIS, one-line message)``, best first."""
    p_hat, z, S = free.p_hat, free.z, free.S
    out = []
    for z2, what in ((1000.0 * z, "'pos' looks like km (the dead-reckoned path is ≈ 1000× "
                                  "larger): give metres, multiply 'pos' by 1000"),
                     (z / 1000.0, "'pos' looks like mm (≈ 1000× the dead-reckoned path): "
                                  "give metres, divide 'pos' by 1000"),
                     (z[:, ::-1], "'pos' columns look swapped (the path matches (y, x)): "
                                  "the first column must be x, the second y"),
                     (1000.0 * z[:, ::-1], "'pos' looks like km with its columns swapped: "
                                           "give metres, x first")):
        out.append((free.median_nis(z2 - p_hat), f"{source}: {what}"))
    Si = np.linalg.solve(S, np.broadcast_to(np.eye(2), S.shape))  # weights S_j⁻¹ (2×2 each)
    o = np.linalg.solve(Si.sum(axis=0), np.einsum("mij,mj->i", Si, free.nu))
    out.append((free.median_nis(free.nu - o),
                f"{source}: 'pos' looks offset by a constant ({o[0]:.3g}, {o[1]:.3g}) m from the "
                "dead-reckoned path (another origin or datum, or datos.txt's P0 is off): "
                "subtract it"))
    tau, med = best_lag(free)
    if tau != 0.0:
        late = "late" if tau > 0 else "early"
        a = f"{abs(tau):.3g}"
        out.append((med, f"{source}: 't_gps' looks {a} s {late} (the fix at t matches the "
                         f"path at t {'-' if tau > 0 else '+'} {a} s): "
                         f"{'subtract' if tau > 0 else 'add'} {a} s"))
    return sorted(out, key=lambda c: c[0])


def check_fixes(free: FreeRun, source: str, *, alpha: float = PRECHECK_ALPHA,
                alternatives: Callable[[], list[tuple[float, str]]] | None = None,
                suspects: str = "") -> None:
    """Refuse fixes that disagree with the dead-reckoned path (module docstring).

    Passes silently when the median NIS is below :func:`median_threshold`; else raises
    :class:`calib.input_rules.DataError` with the best-fitting mistake among
    :func:`explain` and ``alternatives()`` (each ``(median NIS, one-line message naming its
    file)``, e.g. a gyro read in deg/s), or, when none fits, naming ``source`` and the things
    to check (``suspects`` added).
    """
    x = median_threshold(alpha)
    med = free.median_nis()
    if not med >= x:
        return
    cands = explain(free, source) + (alternatives() if alternatives else [])
    cands = [c for c in cands if c[0] < x]
    if cands:
        best = min(cands, key=lambda c: c[0])
        raise DataError(f"{best[1]} (median NIS {med:.3g} against the dead-reckoned "
                        f"path, {best[0]:.3g} so; right fixes give < {x:.3g})")
    raise DataError(f"{source}: the fixes disagree with the dead-reckoned path (median NIS "
                    f"{med:.3g}, right fixes give < {x:.3g}); no unit, axis, time or offset "
                    f"mistake explains it: check 'pos' and 't_gps', the calibration"
                    f"{suspects}")


def check_gyro(gyro, source: str) -> None:
    """Refuse a gyro that cannot be a turning run's yaw rate (module docstring): non-finite,
    exactly constant, or ``|ω| > MAX_YAW_RATE``. DataError naming ``source`` and 'gyro'."""
    w = np.asarray(gyro, dtype=float).reshape(-1)
    if w.size == 0:
        raise DataError(f"{source}: 'gyro' is empty: a turning run needs the yaw rate (rad/s)")
    if not np.all(np.isfinite(w)):
        raise DataError(f"{source}: 'gyro' has NaN or Inf: remove or interpolate those samples")
    if np.ptp(w) == 0.0:
        raise DataError(f"{source}: 'gyro' is constant ({w[0] + 0.0:g} rad/s in every sample): "
                        "a live gyro has noise, so the channel is dead or was zeroed; give the "
                        "measured yaw rate, or remove 'gyro' for a vehicle that does not turn")
    big = float(np.max(np.abs(w)))
    if big > MAX_YAW_RATE:
        raise DataError(f"{source}: 'gyro' reaches {big:.4g} rad/s, beyond any yaw-rate "
                        f"gyro's full scale ({MAX_YAW_RATE:g} rad/s = 2000 °/s): give rad/s")


def check_heading(psi0: float, name: str = "psi0") -> float:
    """The initial heading, rad: refused when not finite or beyond one turn (|ψ0| > 2π:
    most likely degrees); returned as given otherwise (ValueError)."""
    psi0 = float(psi0)
    if not math.isfinite(psi0):
        raise ValueError(f"{name} must be a finite heading in rad, got {psi0!r}")
    if abs(psi0) > 2.0 * math.pi:
        raise ValueError(f"{name} = {psi0:g} rad is more than one turn: a heading in rad is "
                         f"within ±2π (degrees? {psi0:g}° = {math.radians(psi0):.6g} rad)")
    return psi0


__all__ = ["FreeRun", "MAX_SCAN_FIXES", "MAX_SCAN_LAGS", "MAX_YAW_RATE", "PRECHECK_ALPHA",
           "best_lag", "check_fixes", "check_gyro", "check_heading", "explain",
           "heading_offset", "median_threshold"]
