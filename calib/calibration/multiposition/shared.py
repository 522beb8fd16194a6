"""What the planar and the 3-axis multi-position fits share: the held poses (:class:`Poses`,
:func:`pose_statistics`), the count of distinct orientations and the identifiability limits
(method and references: :mod:`calib.calibration.multiposition`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import stats

from calib.input_rules import DataError
from calib.results import ResultMixin, readonly

COND_WARN = 100.0
"""Condition number of the equilibrated Jacobian above which the fit warns (poorly spread
poses: a small error in the data moves the estimates a lot). Poses evenly spread around the
turn give ≈ 2–3; six poses within 50° give ≈ 300 with a scale std of ≈ 0.3."""

COND_REFUSE = 1e6
"""Condition number above which the poses are taken as not identifying the calibration
(refused, naming the parameters of the weakest direction): e.g. four poses symmetric about
both axes (± α, π ± α), on which a family of ellipses fits, give ≈ 5e6 with noise."""

UNIDENTIFIED_STD = {"bias": 0.1, "scale": 0.1}
"""A parameter whose std exceeds this (bias: this fraction of g, m/s²; scale: this value) is
not identified by the poses in any useful sense (an accelerometer's scale error is a few per
cent): refused, naming it. Four noisy poses near ± 20°, 180° ± 20° give std(scale) ≈ 10³."""

SAME_POSE_STD = 3.0
"""Two poses whose mean readings differ by less than this many standard deviations of their
difference on both axes count as one orientation (:func:`distinct_orientations`)."""

SPAN_FRACTION = 0.05
"""An axis whose pose means span less than this fraction of g (poses all within ≈ ±3° of the
same line) cannot identify its scale: refused, naming ``scale_<axis>``."""

Sigma2Source = Literal["given", "estimated"]


class PoseFit:
    """What a multi-position fit (planar or 3-axis) shares: parameters ordered
    ``[bias, scale]`` per axis, intervals, the parameter table, the σ² line and the tilt-plane
    fits of :meth:`to_calibration`. The fit provides ``params``, ``cov``, ``param_names``,
    ``poses``, ``residuals`` (per pose mean, m/s²), ``sigma2``, ``sigma2_source``,
    ``sigma2_dof``, ``chi2``, ``dof`` and ``cond``. Intervals: normal quantiles when σ² was
    given, Student t with the pure-error dof when it was estimated within the poses."""

    @property
    def std(self) -> np.ndarray:
        """Standard deviations of ``params`` (the units of each)."""
        return np.sqrt(np.diag(self.cov))

    @property
    def n(self) -> int:
        """Samples used (held poses only)."""
        return int(self.poses.n.sum())

    @property
    def bias(self) -> np.ndarray:
        """Bias of each axis, m/s² (the fit's axis order)."""
        return self.params[0::2]

    @property
    def scale(self) -> np.ndarray:
        """Scale-factor error of each axis, dimensionless."""
        return self.params[1::2]

    @property
    def chi2_dof(self) -> float:
        return self.chi2 / self.dof if self.dof > 0 else float("nan")

    def sigma2_line(self, per: str, exact: str) -> str:
        """``σ² = … (m/s²)²<per> (given | estimated within poses, dof k); χ²/dof …`` —
        ``exact`` replaces the χ² part when dof = 0."""
        s2 = ", ".join(f"{v:.4g}" for v in self.sigma2)
        src = ("given" if self.sigma2_source == "given"
               else f"estimated within poses, dof {self.sigma2_dof}")
        fit = f"χ²/dof = {self.chi2_dof:.4f}; dof = {self.dof}" if self.dof > 0 else exact
        return f"σ² = {s2} (m/s²)²{per} ({src}); {fit}"

    def plane_fits(self) -> tuple[dict, np.ndarray, dict]:
        """The tilt-plane axes' :class:`~calib.calibration.ls.FitResult` (x, y), the χ² of the
        samples per axis and the ``extra`` of the fits, for :meth:`to_calibration`.

        χ² of every held sample against its pose's model value,
        ``Σ_ij (m_ij − model_i)² / σ² = (SS_within + Σ n_i r_i²) / σ²`` per axis, with
        ``dof = N − P`` (samples less the poses' means): finite also when the pose means fit
        exactly. Residuals: the pose means' (P per axis), m/s²."""
        from calib.calibration.ls import FitResult
        from calib.conventions import AXES, PARAM_NAMES

        chi2 = (self.poses.ss_within
                + np.sum(self.poses.n[:, None] * self.residuals**2, axis=0)) / self.sigma2
        extra = {"sigma2_dof": self.sigma2_dof} if self.sigma2_source == "estimated" else {}
        fits = {}
        for k, a in enumerate(AXES):
            sl = slice(2 * k, 2 * k + 2)
            fits[a] = FitResult(PARAM_NAMES, self.params[sl], self.cov[sl, sl],
                                self.residuals[:, k], self.sigma2[k], self.sigma2_source,
                                self.sigma2_dof, 2, self.cond, float(chi2[k]), dict(extra))
        return fits, chi2, extra

    def quantile(self, level: float) -> float:
        """Two-sided quantile: normal (σ² given) or Student t with ``sigma2_dof``."""
        if not 0 < level < 1:
            raise ValueError(f"level must be in (0, 1), got {level}")
        q = 0.5 + level / 2
        return float(stats.norm.ppf(q) if self.sigma2_source == "given"
                     else stats.t.ppf(q, self.sigma2_dof))

    def conf_int(self, level: float = 0.95) -> np.ndarray:
        """(p, 2) two-sided intervals at ``level``."""
        half = self.quantile(level) * self.std
        return np.column_stack([self.params - half, self.params + half])

    def param_table(self, level: float = 0.95) -> list[str]:
        """The header and one line per parameter: unit, estimate, std, interval."""
        lo, hi = self.conf_int(level).T
        pct = f"{100 * level:g}%"
        out = [f"{'param':<9}{'unit':<6}{'estimate':>14}{'std':>13}{'[' + pct:>14}"
               f"{pct + ']':>13}"]
        for i, name in enumerate(self.param_names):
            unit = "m/s²" if name.startswith("bias") else "1"
            out.append(f"{name:<9}{unit:<6}{self.params[i]:>14.6g}{self.std[i]:>13.4g}"
                       f"{lo[i]:>14.6g}{hi[i]:>13.6g}")
        return out


@dataclass(frozen=True, eq=False)
class Poses(ResultMixin):
    """Per-pose statistics of a log: the held poses' labels, sample counts and means.

    Attributes
    ----------
    labels : (P,) int pose labels (as in :attr:`calib.logs.reader.ImuLog.pose`).
    n : (P,) int samples per pose.
    means : (P, 2) m/s², mean reading ``[m̄x, m̄y]`` of each pose; (P, 3) with the normal
        axis ``[m̄x, m̄y, m̄n]`` for the 3-axis fit (:func:`fit_multiposition3d`).
    ss : (P, 2) or (P, 3) (m/s²)², each pose's sum of squares about its mean (pure error).
    """

    labels: np.ndarray
    n: np.ndarray
    means: np.ndarray
    ss: np.ndarray

    _TITLE = "Held poses"
    _UNITS = "means m/s²; ss (m/s²)²; n count"

    def __post_init__(self) -> None:
        object.__setattr__(self, "labels", readonly(self.labels, int))
        object.__setattr__(self, "n", readonly(self.n, int))
        object.__setattr__(self, "means", readonly(self.means))
        k = self.means.shape[1] if self.means.ndim == 2 else 2
        object.__setattr__(self, "ss", readonly(np.reshape(self.ss, (-1, k))))

    @property
    def count(self) -> int:
        return int(self.labels.size)

    @property
    def axes(self) -> int:
        """Axes per pose: 2 (tilt plane) or 3 (with the normal axis)."""
        return int(self.means.shape[1])

    @property
    def ss_within(self) -> np.ndarray:
        """(2,) or (3,) (m/s²)², pure-error sum of squares of each axis (all poses)."""
        return self.ss.sum(axis=0)

    @property
    def dof_within(self) -> int:
        """Pure-error dof, N − P."""
        return int(self.n.sum() - self.n.size)

    def summary(self) -> str:
        names = "xyn"[:self.axes]
        rows = [f"{'pose':>5}{'n':>8}" + "".join(f"{'mean ' + a + ' m/s²':>14}" for a in names)]
        rows += [f"{lab:>5}{k:>8}" + "".join(f"{v:>14.5f}" for v in m)
                 for lab, k, m in zip(self.labels, self.n, self.means, strict=True)]
        return "\n".join(rows)

    def to_dict(self) -> dict:
        return {"labels": self.labels.tolist(), "n": self.n.tolist(),
                "means": self.means.tolist(), "ss": self.ss.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> Poses:
        return cls(d["labels"], d["n"], d["means"], d["ss"])


def pose_statistics(acc: np.ndarray, pose: np.ndarray, source: str = "<memory>") -> Poses:
    """The :class:`Poses` of readings ``acc`` (N, 2) m/s² — or (N, 3) with the normal axis —
    with labels ``pose`` (N,) int (−1: moving, left out). DataError when no sample is
    labelled."""
    acc = np.asarray(acc, dtype=float)
    pose = np.asarray(pose, dtype=int)
    if acc.ndim != 2 or acc.shape[1] not in (2, 3) or pose.shape != (acc.shape[0],):
        raise DataError(f"{source}: readings must be (N, 2) or (N, 3) with one pose label per "
                        f"sample, got {acc.shape} and {pose.shape}")
    held = pose >= 0
    if not np.any(held):
        raise DataError(f"{source}: no held pose (every sample is labelled moving, -1); the "
                        "multi-position calibration needs the sensor held still in several "
                        "orientations")
    labels, inverse = np.unique(pose[held], return_inverse=True)
    a = acc[held]
    n = np.bincount(inverse)
    k_ax = acc.shape[1]
    means = np.stack([np.bincount(inverse, weights=a[:, k]) / n for k in range(k_ax)], axis=1)
    dev2 = (a - means[inverse]) ** 2
    ss = np.stack([np.bincount(inverse, weights=dev2[:, k]) for k in range(k_ax)], axis=1)
    return Poses(labels, n, means, ss)


def distinct_orientations(poses: Poses, sigma2: np.ndarray, mean_var=0.0) -> int:
    """Number of distinct orientations among the poses: poses whose means differ by less
    than :data:`SAME_POSE_STD` std of their difference on every axis (``σ_a² (1/n_i +
    1/n_j) + 2·mean_var_a``; ``mean_var`` (m/s²)², a variance every pose mean has whatever
    n, e.g. quantization's q²/12) are merged (single linkage). Repeating an orientation adds
    samples, not geometry."""
    P = poses.count
    parent = list(range(P))

    def root(i: int) -> int:
        while parent[i] != i:
            i = parent[i]
        return i

    inv_n = 1.0 / poses.n
    for i in range(P):
        for j in range(i + 1, P):
            sd = np.sqrt(sigma2 * (inv_n[i] + inv_n[j]) + 2 * np.asarray(mean_var))
            if np.all(np.abs(poses.means[i] - poses.means[j]) < SAME_POSE_STD * sd):
                parent[root(j)] = root(i)
    return len({root(i) for i in range(P)})
