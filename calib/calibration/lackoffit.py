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
from scipy import stats

from calib.conventions import AXES
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


def lack_of_fit(residuals: np.ndarray, groups: np.ndarray, n_params: int,
                axis: str = "x") -> LackOfFit | None:
    """Draper & Smith's F test of one axis (module docstring).

    Parameters
    ----------
    residuals : (N,) data − model of a fit with ``n_params`` parameters on this axis, m/s².
    groups : (N,) group index per sample.
    n_params : p, parameters of the fit on this axis (2: bias and scale).
    axis : name for messages.

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


def lack_of_fit_axes(residuals: np.ndarray, groups: np.ndarray, n_params: int = 2
                     ) -> dict[str, LackOfFit] | None:
    """:func:`lack_of_fit` of both columns of ``residuals`` (N, 2) → ``{"x": …, "y": …}``,
    or None when the test is undefined."""
    out = {a: lack_of_fit(np.asarray(residuals)[:, k], groups, n_params, a)
           for k, a in enumerate(AXES)}
    if any(v is None for v in out.values()):
        return None
    return out  # type: ignore[return-value]


__all__ = ["LOF_ALPHA", "LackOfFit", "groups_from", "lack_of_fit", "lack_of_fit_axes",
           "pure_error", "pure_error_variance"]
