"""Lack of fit: does the model miss something, or is the residual scatter just noise?

When readings repeat at the same table position (held poses, or repeated θ values) the
residual sum of squares of a fit splits into two parts (Draper & Smith, *Applied Regression
Analysis*, 3rd ed., §2.1 "pure error and lack of fit"). Per axis, with ``c`` groups
(poses), ``n_i`` samples in group ``i``, ``N = Σ n_i`` and ``p`` parameters::

    RSS      = Σ_i Σ_j r_ij²                               dof N − p
    SS_pe    = Σ_i Σ_j (r_ij − r̄_i)²   (pure error)        dof N − c
    SS_lof   = RSS − SS_pe = Σ_i n_i r̄_i²  (lack of fit)   dof c − p
    F        = (SS_lof / (c − p)) / (SS_pe / (N − c))       ~ F(c − p, N − c) if the model holds

``r_ij`` are the fit residuals (data − model), m/s². Within a group the model is constant, so
the scatter of the residuals about their group mean is the scatter of the readings: pure
error, whatever the model. ``SS_pe / (N − c)`` is a model-free estimate of σ² (the
*pure-error variance*); a large F (small p) means the group means miss the model by more than
their own scatter allows: the model lacks an effect (run ``tiltbench gap``).

Caveat, stated once: the test assumes the samples within a pose are independent. A
low-pass-filtered or drifting sensor has correlated samples; their within-pose scatter then
understates the variance of a pose mean and the test reports lack of fit that is really
correlated noise (``tiltbench noise`` shows the correlation as a non-white Allan deviation).

Groups come from pose labels (:attr:`calib.logs.reader.ImuLog.pose`; label −1, a sample taken while
moving, is a group of its own) or, without labels, from exactly repeated θ values
(:func:`groups_from`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from calib import distributions as stats
from calib.conventions import AXES
from calib.numerics import lagged_sums
from calib.results import ResultMixin
from calib.units import format_p

LOF_ALPHA = 0.01
"""Significance level at which a command says "the model misses something" (one line)."""

Statistic = Literal["F", "chi2"]


@dataclass(frozen=True, eq=False)
class LackOfFit(ResultMixin):
    """The lack-of-fit test of one axis (or of both axes jointly, ``axis = "xy"``).

    Attributes
    ----------
    axis : "x", "y", or "xy" / "xyn" for the joint test of the planar / 3-axis
        multi-position fit.
    groups : c, number of groups (poses) with data.
    ss_lack_of_fit, ss_pure_error : the two sums of squares, (m/s²)²; for ``axis = "xy"``
        whitened (each residual divided by its std), dimensionless.
    dof_lack_of_fit, dof_pure_error : their degrees of freedom (c − p, N − c).
    statistic : "F" (pure error estimated from the data) or "chi2" (σ² known, whitened).
    value : the statistic; p_value : its upper-tail probability under "the model holds".
    """

    axis: str
    groups: int
    ss_lack_of_fit: float
    ss_pure_error: float
    dof_lack_of_fit: int
    dof_pure_error: int
    statistic: Statistic
    value: float
    p_value: float

    _TITLE = "Lack-of-fit test"
    _UNITS = ("sums of squares (m/s²)² per axis, dimensionless (whitened) for the joint test; "
              "F and χ² dimensionless; p probability")
    JSON_UNITS = {"ss_lack_of_fit": "(m/s²)² (1 when axis = xy)",
                  "ss_pure_error": "(m/s²)² (1 when axis = xy)", "dof_lack_of_fit": "count",
                  "dof_pure_error": "count", "groups": "count", "value": "1",
                  "p_value": "probability", "sigma2_pure_error": "(m/s²)² (1 when axis = xy)"}

    @property
    def sigma2_pure_error(self) -> float:
        """``SS_pe / (N − c)``: the model-free noise variance, (m/s²)²."""
        return (self.ss_pure_error / self.dof_pure_error if self.dof_pure_error > 0
                else float("nan"))

    def misses(self, alpha: float = LOF_ALPHA) -> bool:
        """True when the test rejects "the model holds" at ``alpha``."""
        return bool(self.p_value < alpha)

    def _stat_text(self) -> str:
        if self.statistic == "F":
            return (f"F = {self.value:.4g} (dof {self.dof_lack_of_fit}, "
                    f"{self.dof_pure_error}), {format_p(self.p_value)}")
        return f"χ² = {self.value:.4g} (dof {self.dof_lack_of_fit}), {format_p(self.p_value)}"

    def summary(self) -> str:
        """One line: the statistic, its dof, p and the pure-error variance."""
        # the joint tests ("xy", "xyn" of the 3-axis fit) are whitened: no σ² in m/s² to print
        pe = ("" if self.axis in ("xy", "xyn") or self.dof_pure_error <= 0 else
              f"; pure-error σ² = {self.sigma2_pure_error:.4g} (m/s²)² "
              f"(dof {self.dof_pure_error})")
        return f"axis {self.axis}: lack of fit {self._stat_text()} ({self.groups} poses){pe}"

    def warning_line(self) -> str:
        """The one line a command prints when :meth:`misses` is true: the lack-of-fit
        statistic and its p (its dof are in :meth:`summary`), within 100 columns after a
        ``warning:`` prefix."""
        name = "F" if self.statistic == "F" else "χ²"
        return (f"axis {self.axis}: the model misses something ({name} = {self.value:.3g}, "
                f"{format_p(self.p_value)}); run `tiltbench gap`")

    def to_dict(self) -> dict:
        return {"axis": self.axis, "groups": self.groups,
                "ss_lack_of_fit": self.ss_lack_of_fit, "ss_pure_error": self.ss_pure_error,
                "dof_lack_of_fit": self.dof_lack_of_fit, "dof_pure_error": self.dof_pure_error,
                "statistic": self.statistic, "value": self.value, "p_value": self.p_value,
                "sigma2_pure_error": self.sigma2_pure_error}

    @classmethod
    def from_dict(cls, d: dict) -> LackOfFit:
        """Rebuild from :meth:`to_dict` (exact)."""
        return cls(str(d["axis"]), int(d["groups"]), float(d["ss_lack_of_fit"]),
                   float(d["ss_pure_error"]), int(d["dof_lack_of_fit"]),
                   int(d["dof_pure_error"]), d["statistic"], float(d["value"]),
                   float(d["p_value"]))


def groups_from(tita: np.ndarray | None = None, pose: np.ndarray | None = None
                ) -> np.ndarray | None:
    """Group index per sample (0 … c−1), or None when nothing repeats.

    Parameters
    ----------
    tita : (N,) rad, or None — used when ``pose`` is None: equal θ values form a group.
    pose : (N,) int pose labels, or None; label −1 (moving) makes each such sample a group
        of its own.

    Returns None when every group has one sample (no pure error to measure).
    """
    if pose is not None:
        pose = np.asarray(pose, dtype=int)
        key = pose.copy()
        moving = pose < 0
        # each moving sample its own group: labels above every pose label
        key[moving] = pose.max(initial=-1) + 1 + np.arange(int(moving.sum()))
    elif tita is not None:
        key = np.asarray(tita, dtype=float)
    else:
        return None
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    if counts.size == 0 or counts.max() < 2:
        return None
    return inverse.astype(int)


def pure_error(values: np.ndarray, groups: np.ndarray) -> tuple[np.ndarray, int]:
    """Sum of squares of ``values`` about their group means and its dof ``N − c``.

    Parameters
    ----------
    values : (N,) or (N, k) readings or residuals, m/s².
    groups : (N,) group index per sample (:func:`groups_from`).

    Returns
    -------
    (ss, dof) : ss (k,) or scalar (m/s²)²; dof = N − c.
    """
    values = np.asarray(values, dtype=float)
    groups = np.asarray(groups, dtype=int)
    c = int(groups.max()) + 1
    counts = np.bincount(groups, minlength=c)
    flat = values.reshape(values.shape[0], -1)
    sums = np.stack([np.bincount(groups, weights=flat[:, k], minlength=c)
                     for k in range(flat.shape[1])], axis=1)
    means = sums / np.maximum(counts, 1)[:, None]
    dev = flat - means[groups]
    ss = np.sum(dev**2, axis=0)
    dof = int(values.shape[0] - np.count_nonzero(counts))
    return (ss if values.ndim > 1 else ss[0]), dof


def pure_error_variance(values: np.ndarray, groups: np.ndarray) -> tuple[np.ndarray, int]:
    """``(σ² per column, dof)``: the within-group (pure-error) variance ``SS_pe / (N − c)``,
    (m/s²)²; raises ValueError when no group repeats (dof 0)."""
    ss, dof = pure_error(values, groups)
    if dof <= 0:
        raise ValueError("no pose or θ value repeats: the within-pose scatter is not defined")
    return np.asarray(ss, dtype=float) / dof, dof


TAU_MIN = 1.5
"""Smallest integrated autocorrelation time (samples) :func:`pose_statistics` counts: white
noise has 1, and a log filtered or decimated below its Nyquist frequency has several (a 10 Hz
phone export with a 1-s correlation time: about 20)."""

TAU_Z = 4.0
"""… and only when it exceeds 1 by this many times the spread of its estimate on white noise
(:func:`integrated_correlation`: white logs keep their counts)."""

MAX_LAG = 2000
"""Longest lag (samples) of the autocorrelation sums."""


def integrated_correlation(dev: np.ndarray, pose: np.ndarray) -> tuple[float, float]:
    """``(τ_int, sd₀)``: the integrated autocorrelation time of the readings about their pose
    means, samples — the largest over the axes — and the spread of its estimate on white
    noise with the same window, ``sd₀ = 2·√(M/N)`` (each ρ_k then ≈ N(0, 1/N)).

    ``τ_int = 1 + 2·Σ_{k=1}^{M} ρ_k``, ρ_k the lag-k autocorrelation pooled over the held
    stretches (pairs never cross a stretch; each stretch about its pose's mean), M the
    smallest lag with ``M ≥ 5·τ_int(M)`` (Sokal's automatic window; Madras & Sokal 1988),
    over the N held samples; each stretch's deviations are about its own mean, which takes
    ``Var(mean) ≈ c₀τ/L̄`` from every autocovariance (L̄ the mean stretch length), so the sum
    is corrected, ``τ = τ̂/(1 − (2M + 1 − τ̂)/L̄)`` (while that deficit is under one half:
    Butterworth-filtered noise with τ = 16.3 on 300-sample holds reads 10.5 before, 15 after).
    The variance
    of a mean of n such readings is ``τ_int·σ²/n`` (n ≫ τ_int). Why by hand: numpy and scipy
    have no windowed integrated autocorrelation time over segments.

    dev : (N, k) deviations from the pose means (anything where ``pose`` < 0).
    pose : (N,) labels, −1 moving.
    """
    pose = np.asarray(pose)
    edges = np.r_[0, np.flatnonzero(np.diff(pose) != 0) + 1, pose.size]
    parts = [(a, min(b, a + 16 * MAX_LAG)) for a, b in zip(edges[:-1], edges[1:], strict=True)
             if pose[a] >= 0 and b - a >= 8]
    if not parts:
        return 1.0, 0.0
    lags = min(MAX_LAG, max(b - a for a, b in parts) // 2)
    sums = np.zeros((lags + 1, dev.shape[1]))
    pairs = np.zeros(lags + 1)
    for a, b in parts:
        m = b - a
        ac = lagged_sums(dev[a:b], lags)
        sums[:ac.shape[0]] += ac
        pairs[:ac.shape[0]] += m - np.arange(ac.shape[0])
    ok = pairs > 0
    cov = sums[ok] / pairs[ok, None]
    rho = cov / np.where(cov[0] > 0, cov[0], 1.0)
    tau = 1.0 + 2.0 * np.cumsum(rho[1:], axis=0)  # τ(M), M = 1 … lags
    n_held = sum(b - a for a, b in parts)
    mean_len = n_held / len(parts)
    best, best_se = 1.0, 0.0
    for k in range(tau.shape[1]):
        window = np.flatnonzero(np.arange(1, tau.shape[0] + 1) >= 5.0 * tau[:, k])
        m = int(window[0]) if window.size else tau.shape[0] - 1
        t_k = float(tau[m, k]) if tau.size else 1.0
        # each stretch about its own mean: every ĉ_j falls short by Var(mean) ≈ c₀τ/L̄, so
        # τ̂ = τ(1 − (2M+1)/L̄)/(1 − τ/L̄) (M = m + 1 lags); solved for τ, while the deficit
        # is a minor part of it (else the stretches are too short to tell and τ̂ stands)
        deficit = (2 * (m + 1) + 1 - t_k) / mean_len
        if 0.0 < deficit < 0.5:
            t_k /= 1.0 - deficit
        t_k = max(t_k, 1.0)
        if t_k > best:
            best, best_se = t_k, 2.0 * float(np.sqrt((m + 1) / n_held))
    return best, best_se


def correlated_groups(values: np.ndarray, groups: np.ndarray) -> float:
    """The integrated autocorrelation time (samples) of ``values`` (N,) or (N, k) about their
    group means (``groups`` (N,) int, −1 left out) when it counts — at least
    :data:`TAU_MIN` and above 1 by :data:`TAU_Z` times its spread on white noise — else 1.

    A group mean of n such samples has the variance of ``n/τ`` independent ones: the held
    poses' statistics (:func:`calib.calibration.multiposition.shared.pose_statistics`) and the
    θ-based least squares with groups (:func:`calib.calibration.tilt_plane.calibrate`) count
    it (docs/poses-calibration.md, Correlated samples)."""
    flat = np.asarray(values, dtype=float).reshape(len(groups), -1)
    groups = np.asarray(groups, dtype=int)
    held = groups >= 0
    if not np.any(held):
        return 1.0
    labels, inverse = np.unique(groups[held], return_inverse=True)
    counts = np.bincount(inverse)
    dev = np.zeros_like(flat)
    for k in range(flat.shape[1]):
        means = np.bincount(inverse, weights=flat[held, k]) / counts
        dev[held, k] = flat[held, k] - means[inverse]
    tau, spread = integrated_correlation(dev, groups)
    return tau if tau >= TAU_MIN and tau - 1.0 > TAU_Z * spread else 1.0


def effective_counts(counts: np.ndarray, tau: float, least: int = 1) -> np.ndarray:
    """Independent readings ``⌊n/τ⌋`` (at least ``least``) of groups of ``counts`` correlated
    samples (:func:`correlated_groups`); the counts themselves when τ = 1."""
    counts = np.asarray(counts, dtype=int)
    if tau <= 1.0:
        return counts
    return np.minimum(np.maximum(np.floor(counts / tau), least).astype(int), counts)


def pure_error_dof(groups: np.ndarray, tau: float = 1.0) -> int:
    """Pure-error dof ``Σ n_eff − c`` of ``groups`` (:func:`effective_counts`)."""
    counts = np.bincount(np.asarray(groups, dtype=int))
    counts = counts[counts > 0]
    return int(np.sum(effective_counts(counts, tau)) - counts.size)


def lack_of_fit(residuals: np.ndarray, groups: np.ndarray, n_params: int,
                axis: str = "x", tau: float = 1.0) -> LackOfFit | None:
    """Draper & Smith's F test of one axis (module docstring).

    Parameters
    ----------
    residuals : (N,) data − model of a fit with ``n_params`` parameters on this axis, m/s².
    groups : (N,) group index per sample.
    n_params : p, parameters of the fit on this axis (2: bias and scale).
    axis : name for messages.
    tau : the samples' integrated autocorrelation time (:func:`correlated_groups`): a group
        mean's variance is ``τ·σ²/n``, so the pure error is read per ``τ`` samples (its mean
        square ×τ, its dof ``Σ⌊n_i/τ⌋ − c``).

    Returns None when the test is undefined: fewer groups than ``p + 1`` (no lack-of-fit dof)
    or no repeated sample (no pure-error dof).

    Examples
    --------
    >>> import numpy as np
    >>> r = np.array([0.1, -0.1, 0.1, -0.1, 0.1, -0.1])   # groups' means are 0: a perfect fit
    >>> lof = lack_of_fit(r, np.array([0, 0, 1, 1, 2, 2]), 1)
    >>> (lof.value, lof.dof_lack_of_fit, lof.dof_pure_error)
    (0.0, 2, 3)
    """
    residuals = np.asarray(residuals, dtype=float)
    groups = np.asarray(groups, dtype=int)
    c = int(np.count_nonzero(np.bincount(groups)))
    ss_pe, dof_pe = pure_error(residuals, groups)
    if tau > 1.0:  # a group mean of n correlated samples varies as n/τ independent ones
        dof_eff = pure_error_dof(groups, tau)
        if dof_pe > 0 and dof_eff > 0:
            ss_pe, dof_pe = float(ss_pe) * tau * dof_eff / dof_pe, dof_eff
    dof_lof = c - n_params
    if dof_lof <= 0 or dof_pe <= 0:
        return None
    # SS_lof = Σ n_i r̄_i², computed directly (RSS − SS_pe loses digits when they are close)
    counts = np.bincount(groups)
    sums = np.bincount(groups, weights=residuals)
    nz = counts > 0
    ss_lof = float(np.sum(sums[nz] ** 2 / counts[nz]))
    ss_pe = float(ss_pe)
    if ss_pe <= 0:
        value = float("inf") if ss_lof > 0 else 0.0
    else:
        value = (ss_lof / dof_lof) / (ss_pe / dof_pe)
    p = float(stats.f.sf(value, dof_lof, dof_pe)) if np.isfinite(value) else 0.0
    return LackOfFit(axis, c, ss_lof, ss_pe, dof_lof, dof_pe, "F", float(value), p)


def lack_of_fit_axes(residuals: np.ndarray, groups: np.ndarray, n_params: int = 2,
                     tau: float = 1.0) -> dict[str, LackOfFit] | None:
    """:func:`lack_of_fit` of both columns of ``residuals`` (N, 2) → ``{"x": …, "y": …}``,
    or None when the test is undefined."""
    out = {a: lack_of_fit(np.asarray(residuals)[:, k], groups, n_params, a, tau)
           for k, a in enumerate(AXES)}
    if any(v is None for v in out.values()):
        return None
    return out  # type: ignore[return-value]


__all__ = ["LOF_ALPHA", "MAX_LAG", "TAU_MIN", "TAU_Z", "LackOfFit", "correlated_groups",
           "effective_counts", "groups_from", "integrated_correlation", "lack_of_fit",
           "lack_of_fit_axes", "pure_error", "pure_error_dof", "pure_error_variance"]
