"""What the planar and the 3-axis multi-position fits share: the held poses (:class:`Poses`,
:func:`pose_statistics`), the count of distinct orientations, the identifiability limits, the
result's common part (:class:`PoseFit`) and the steps of both fits (:class:`PoseProblem`:
checks, covariance, lack of fit, verdict; method and references:
:mod:`calib.calibration.multiposition`)."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import linalg as sla
from scipy import optimize, stats

from calib.calibration.lackoffit import LackOfFit, correlated_groups, effective_counts
from calib.calibration.ls import FitResult, NotIdentifiableError, PoorlyIdentifiedWarning
from calib.conventions import AXES, JOINT_PARAM_NAMES, PARAM_NAMES
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

_COUNT_WORDS = {2: "two", 3: "three"}


@dataclass(frozen=True, eq=False, kw_only=True)
class PoseFit:
    """What a multi-position fit (planar or 3-axis) shares: the fields below, parameters
    ordered ``[bias, scale]`` per axis, intervals, the parameter table, the summary's frame,
    the ``--json`` object and the tilt-plane :class:`~calib.calibration.tilt_plane.Calibration`.
    Intervals: normal quantiles when σ² was given, Student t with the pure-error dof when it
    was estimated within the poses.

    Attributes
    ----------
    params : (2k,) ``[bias, scale]`` per axis (m/s², 1); cov : (2k, 2k) their covariance
        (the pose angles or directions marginalised), products of those units.
    poses : the :class:`Poses` the fit used (labels, counts, means).
    residuals : (P, k) m/s², pose mean − model.
    sigma2 : (k,) (m/s²)², per-sample noise variance per axis; ``sigma2_source`` "given" or
        "estimated" (pure error, ``sigma2_dof = N − P`` dof: Student t).
    dof : residual dof of the pose means (P − 4 planar, P − 6 with 3 axes).
    chi2 : Σ r² (whitened).
    rank, cond : rank and 2-norm condition number of the column-equilibrated Jacobian.
    g : m/s².  lack_of_fit : the joint test of the pose means (None when dof = 0).
    param_names : the parameters' names (each fit's default).

    A fit adds its own fields, lists them in ``_ARRAYS`` (frozen here) and ``_DICT_KEYS``
    (the order of :meth:`to_dict`, after the ``(key, value)`` pairs of ``_DICT_HEAD``), and
    sets ``_SUMMARY_TITLE``, ``_SIGMA2_LINE`` (the arguments of :meth:`sigma2_line`) and
    :meth:`pose_lines`.
    """

    params: np.ndarray
    cov: np.ndarray
    poses: Poses
    residuals: np.ndarray
    sigma2: np.ndarray
    sigma2_source: Sigma2Source
    sigma2_dof: int
    dof: int
    chi2: float
    rank: int
    cond: float
    g: float
    lack_of_fit: LackOfFit | None = None
    param_names: tuple[str, ...]

    _ARRAYS = ("params", "cov", "residuals", "sigma2")
    _DICT_HEAD = ()
    _DICT_KEYS = ()
    _SUMMARY_TITLE = ""
    _SIGMA2_LINE = ("", "dof = 0")

    def __post_init__(self) -> None:
        for name in self._ARRAYS:
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "param_names", tuple(self.param_names))

    # only alike: sixface.SixFaceFit's accessors read four parameters per axis, not two
    @property
    def std(self) -> np.ndarray:
        """Standard deviations of ``params`` (the units of each)."""
        return np.sqrt(np.diag(self.cov))

    @property
    def n(self) -> int:
        """Samples used (held poses only; the effective count when the holds' noise is
        correlated, :attr:`Poses.tau_int`)."""
        return int(self.poses.n.sum())

    def _count(self) -> str:
        if self.poses.tau_int > 1.0:
            return (f"N = {self.n} effective (correlated noise: τ_int = "
                    f"{self.poses.tau_int:.3g} samples)")
        return f"N = {self.n}"

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

    def pose_lines(self) -> list[str]:
        """The fit's own summary lines: its identifiability and the per-pose table."""
        return []

    def summary(self, level: float = 0.95) -> str:
        out = [f"Calibration: {self._SUMMARY_TITLE}, g = {self.g} m/s², {self._count()}, "
               f"{self.poses.count} poses", *self.param_table(level),
               self.sigma2_line(*self._SIGMA2_LINE), *self.pose_lines()]
        if self.lack_of_fit is not None:
            out.append(self.lack_of_fit.summary())
        return "\n".join(out)

    def to_dict(self) -> dict:
        """The ``--json`` object: ``method``, the fit's head keys, then ``_DICT_KEYS`` in
        order (arrays and tuples as lists, the poses and the test as their own objects)."""
        out = {"method": "multiposition", **dict(self._DICT_HEAD)}
        for key in self._DICT_KEYS:
            value = getattr(self, key)
            if isinstance(value, np.ndarray):
                value = value.tolist()
            elif isinstance(value, tuple):
                value = list(value)
            elif isinstance(value, (Poses, LackOfFit)):
                value = value.to_dict()
            out[key] = value
        return out

    @classmethod
    def shared_fields(cls, d: dict, axes: int) -> dict:
        """The fields above from a :meth:`to_dict` mapping (``axes`` k: the residuals'
        columns), for a fit's ``from_dict`` (exact, also through JSON)."""
        lof = d.get("lack_of_fit")
        return {"params": d["params"], "cov": d["cov"], "poses": Poses.from_dict(d["poses"]),
                "residuals": np.asarray(d["residuals"], float).reshape(-1, axes),
                "sigma2": d["sigma2"], "sigma2_source": d["sigma2_source"],
                "sigma2_dof": int(d["sigma2_dof"]), "dof": int(d["dof"]),
                "chi2": float(d["chi2"]), "rank": int(d["rank"]), "cond": float(d["cond"]),
                "g": float(d["g"]),
                "lack_of_fit": None if lof is None else LackOfFit.from_dict(lof),
                "param_names": tuple(d["param_names"])}

    def plane_fits(self) -> tuple[dict, np.ndarray, dict]:
        """The tilt-plane axes' :class:`~calib.calibration.ls.FitResult` (x, y), the χ² of the
        samples per axis and the ``extra`` of the fits, for :meth:`to_calibration`.

        χ² of every held sample against its pose's model value,
        ``Σ_ij (m_ij − model_i)² / σ² = (SS_within + Σ n_i r_i²) / σ²`` per axis, with
        ``dof = N − P`` (samples less the poses' means): finite also when the pose means fit
        exactly. Residuals: the pose means' (P per axis), m/s²."""
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

    def tilt_plane_calibration(self, rank: int, extra: dict):
        """The project's :class:`calib.calibration.tilt_plane.Calibration` of the tilt plane
        (method "multiposition"): the per-axis fits of :meth:`plane_fits` and, in ``joint``,
        the first four parameters with their 4×4 block (the cross-axis terms the shared
        angles create), the x and y residuals and σ², ``2·sigma2_dof`` dof, the χ² of the
        samples of both axes, the Jacobian ``rank`` given and the fit's ``extra``."""
        from calib.calibration.tilt_plane import Calibration

        fits, chi2, shared = self.plane_fits()
        joint = FitResult(JOINT_PARAM_NAMES, self.params[:4], self.cov[:4, :4],
                          self.residuals[:, :2], self.sigma2[:2], self.sigma2_source,
                          2 * self.sigma2_dof, rank, self.cond, float(chi2[:2].sum()),
                          {**shared, **extra})
        return Calibration("multiposition", self.g, fits, self.n, joint=joint)

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
        # only alike: bench.validate.Validation's table prints truth and z, not intervals
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
    tau_int : the integrated autocorrelation time of the readings about their pose means,
        samples, when :func:`pose_statistics` found the noise correlated (a filtered or
        decimated log) and counted it: ``n`` and ``ss`` are then the effective ones
        (``n_eff = ⌊n/τ_int⌋``, ``ss·(n_eff − 1)/(n − 1)``: the same sample variance, the
        mean's variance ``τ_int·s²/n``); 1 for white noise.
    """

    # only alike (document.MethodComparison): a result's fields and title, not logic
    labels: np.ndarray
    n: np.ndarray
    means: np.ndarray
    ss: np.ndarray
    tau_int: float = 1.0

    _TITLE = "Held poses"
    _UNITS = "means m/s²; ss (m/s²)²; n count; tau_int samples"

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
                "means": self.means.tolist(), "ss": self.ss.tolist(),
                "tau_int": float(self.tau_int)}

    @classmethod
    def from_dict(cls, d: dict) -> Poses:
        return cls(d["labels"], d["n"], d["means"], d["ss"], float(d.get("tau_int", 1.0)))

    def subset(self, keep, axes: int | None = None) -> Poses:
        """The poses ``keep`` (a mask or indices), their first ``axes`` axes (all: None)."""
        k = self.axes if axes is None else axes
        return Poses(self.labels[keep], self.n[keep], self.means[keep][:, :k],
                     self.ss[keep][:, :k], self.tau_int)


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
    tau = correlated_groups(acc, pose)
    if tau == 1.0:
        return Poses(labels, n, means, ss)
    n_eff = effective_counts(n, tau, least=2)
    shrink = np.where(n > 1, (n_eff - 1) / np.maximum(n - 1, 1), 1.0)
    return Poses(labels, n_eff, means, ss * shrink[:, None], float(tau))




SAME_DIRECTION_DEG: float = 10.0
"""Held poses whose mean readings point within this angle (deg) of each other are re-holds of
one orientation: a hand or a fixture puts a face back within a few degrees, while the
orientations of a multi-position test differ by tens of degrees."""


def distinct_directions(means: np.ndarray, max_angle_deg: float = SAME_DIRECTION_DEG) -> int:
    """Number of distinct orientations among pose means (P, k) m/s²: poses whose readings
    point within ``max_angle_deg`` of each other are merged (single linkage). Unlike
    :func:`distinct_orientations` (a noise test, which tells re-holds apart once the samples
    are many) this is geometry: re-holding a face adds samples, not an orientation."""
    u = np.asarray(means, dtype=float)
    u = u / np.linalg.norm(u, axis=1, keepdims=True).clip(min=1e-300)
    same = u @ u.T >= np.cos(np.radians(max_angle_deg))
    parent = list(range(len(u)))

    def root(i: int) -> int:
        while parent[i] != i:
            i = parent[i]
        return i

    for i, j in zip(*np.nonzero(np.triu(same, 1)), strict=True):
        parent[root(int(i))] = root(int(j))
    return len({root(i) for i in range(len(u))})


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


@dataclass(frozen=True)
class PoseProblem:
    """The steps the planar and the 3-axis fits share on one set of held poses: the checks
    before the fit (:meth:`check_spans`, :meth:`noise_variances`, :meth:`require_distinct`),
    the solve (:meth:`solve_lm`), the covariance (:meth:`covariance`), the joint test
    (:meth:`lack_of_fit`) and the verdict on the result (:meth:`judge`). Refusals raise
    :class:`~calib.calibration.ls.NotIdentifiableError` in one line.

    Attributes
    ----------
    poses : the held poses fitted.  g : m/s².
    axes : the axis names, ("x", "y") or ("x", "y", "n").
    where : "" or "<file>: ", the start of every message.
    """

    poses: Poses
    g: float
    axes: tuple[str, ...]
    where: str

    def check_spans(self, hints: Mapping[str, str] | None = None) -> None:
        """Refuse an axis whose pose means span less than :data:`SPAN_FRACTION`·g: the poses
        hardly turn it, so its scale is not identified (``scale_<axis>`` named; ``hints``:
        axis → more advice)."""
        span = np.ptp(self.poses.means, axis=0)
        for k, a in enumerate(self.axes):
            if span[k] < SPAN_FRACTION * self.g:
                raise NotIdentifiableError(
                    f"{self.where}cannot identify scale_{a}: the {self.poses.count} poses "
                    f"hardly turn the {a} axis (its pose means span only {span[k]:.3g} m/s², "
                    f"under {SPAN_FRACTION:g}·g); hold poses where {a} reads clearly "
                    f"different values (e.g. {a} up and {a} down)" + (hints or {}).get(a, ""))

    def noise_variances(self, noise_var, floor: np.ndarray | None = None
                        ) -> tuple[np.ndarray, Sigma2Source]:
        """σ² per axis, (m/s²)², and where it came from: ``noise_var`` ("given": positive,
        one per axis; ValueError otherwise) or, when None, the pure error
        ``SS_within / (N − P)`` ("estimated"; at least ``floor`` per axis when given, e.g.
        quantization's q²/12). DataError when no pose has two samples or an axis does not
        scatter."""
        names = ",".join(f"σ{a}²" for a in self.axes)
        if noise_var is None:
            poses = self.poses
            if poses.dof_within <= 0:
                raise DataError(f"{self.where}every pose has a single sample: σ² cannot be "
                                f"estimated within the poses; give --noise-var {names}")
            sigma2 = poses.ss_within / poses.dof_within
            if floor is not None:
                sigma2 = np.maximum(sigma2, floor)
            if np.any(sigma2 <= 0):
                raise DataError(f"{self.where}the readings do not scatter within the poses "
                                f"(zero variance on an axis): give --noise-var {names}")
            return sigma2, "estimated"
        sigma2 = np.asarray(noise_var, dtype=float).reshape(-1)
        k = len(self.axes)
        if sigma2.shape != (k,) or np.any(~np.isfinite(sigma2)) or np.any(sigma2 <= 0):
            raise ValueError(f"noise variances must be {_COUNT_WORDS[k]} positive numbers, "
                             f"got {noise_var}")
        return sigma2, "given"

    def require_distinct(self, sigma2: np.ndarray, needed: int, purpose: str,
                         mean_var=0.0) -> None:
        """Refuse fewer than ``needed`` distinct orientations
        (:func:`distinct_orientations`; ``purpose``: what they are needed for)."""
        distinct = distinct_orientations(self.poses, sigma2, mean_var)
        if distinct < needed:
            raise NotIdentifiableError(
                f"{self.where}the {self.poses.count} poses hold only {distinct} distinct "
                f"orientation{'s' if distinct != 1 else ''} (poses whose mean readings agree "
                f"within {SAME_POSE_STD:g} std count as one): at least {needed} are needed "
                f"{purpose}; hold the sensor in other orientations")

    @staticmethod
    def solve_lm(residuals_and_jacobian: Callable[[np.ndarray], tuple], x0: np.ndarray,
                 max_nfev: int) -> np.ndarray:
        """Levenberg–Marquardt (``scipy.optimize.least_squares``, method "lm") from ``x0`` on
        the whitened residuals and Jacobian ``residuals_and_jacobian(x)[:2]``."""
        sol = optimize.least_squares(lambda x: residuals_and_jacobian(x)[0], x0,
                                     jac=lambda x: residuals_and_jacobian(x)[1], method="lm",
                                     max_nfev=max_nfev)
        return sol.x

    def covariance(self, J: np.ndarray, names: tuple[str, ...], advice: str
                   ) -> tuple[np.ndarray, int, float]:
        """``(cov, rank, cond)`` of all unknowns from the whitened Jacobian ``J`` at the
        solution: QR of its column-equilibrated form ``J D⁻¹ = Q R``,
        ``cov = D⁻¹ R⁻¹ R⁻ᵀ D⁻¹`` (no normal matrix inverted); rank and 2-norm condition
        number of ``R``. Refused when rank-deficient or ``cond >`` :data:`COND_REFUSE`,
        naming the calibration parameters (``names``, the first unknowns) of the weakest
        direction; ``advice`` ends the message."""
        norms = np.linalg.norm(J, axis=0)
        norms[norms == 0] = 1.0
        Js = J / norms
        _, R = np.linalg.qr(Js)
        sv = np.linalg.svd(R, compute_uv=False)
        m, n = Js.shape
        rank = int(np.sum(sv > sv[0] * max(m, n) * np.finfo(float).eps))
        cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
        if rank < n or cond > COND_REFUSE:
            _, _, vt = np.linalg.svd(Js)
            weak = np.abs(vt[-1][:len(names)])  # the calibration parameters in that direction
            how = "rank-deficient" if rank < n else f"near-singular (cond {cond:.3g})"
            involved = [names[i] for i in range(len(names))
                        if weak[i] > 0.1 * np.abs(vt[-1]).max()]
            raise NotIdentifiableError(
                f"{self.where}the {self.poses.count} poses cannot identify "
                f"{' / '.join(involved or names)}: the Jacobian is {how} — {advice}")
        Ri = sla.solve_triangular(R, np.eye(n))
        cov = (Ri @ Ri.T) / np.outer(norms, norms)
        return 0.5 * (cov + cov.T), rank, cond

    def lack_of_fit(self, sigma2: np.ndarray, source: Sigma2Source, chi2: float, dof: int
                    ) -> LackOfFit | None:
        """The joint test of the whitened pose means (None when dof = 0)."""
        if dof <= 0:
            return None
        # Draper & Smith's split, whitened per axis: pure error Σ_a SS_within,a / σ_a² with
        # k(N − P) dof, lack of fit χ² with ``dof`` dof
        label, P = "".join(self.axes), self.poses.count
        ss_pe = float(np.sum(self.poses.ss_within / sigma2))
        dof_pe = len(self.axes) * self.poses.dof_within
        if source == "given":
            return LackOfFit(label, P, chi2, ss_pe, dof, dof_pe, "chi2", chi2,
                             float(stats.chi2.sf(chi2, dof)))
        if dof_pe > 0:
            # σ_a² is the pure error itself, so SS_pe/dof_pe = 1 and F = χ²/dof, referred to
            # F(dof, k(N − P)) (approximate: k axes, k estimated σ²)
            value = chi2 / dof
            return LackOfFit(label, P, chi2, ss_pe, dof, dof_pe, "F", value,
                             float(stats.f.sf(value, dof, dof_pe)))
        return None

    def judge(self, fit: PoseFit, *, geometry: str, refuse: str, what: str, warn: str
              ) -> None:
        """Refuse a parameter whose std exceeds :data:`UNIDENTIFIED_STD` (named, with its
        std, the condition number and the poses' ``geometry``; ``refuse`` ends the message);
        warn (:class:`~calib.calibration.ls.PoorlyIdentifiedWarning`) above
        :data:`COND_WARN` (``what`` was identified only poorly; ``warn`` ends it)."""
        names = fit.param_names
        limit = np.array([UNIDENTIFIED_STD["bias"] * self.g, UNIDENTIFIED_STD["scale"]]
                         * (len(names) // 2))
        bad = [nm for nm, sd, lim in zip(names, fit.std, limit, strict=True)
               if not sd <= lim]
        if bad:
            raise NotIdentifiableError(
                f"{self.where}the {self.poses.count} poses do not identify {' / '.join(bad)} "
                f"(std {', '.join(f'{fit.std[names.index(nm)]:.3g}' for nm in bad)}; "
                f"condition number {fit.cond:.3g}, {geometry}): {refuse}")
        if fit.cond > COND_WARN:
            warnings.warn(
                f"{self.where}the poses identify the {what} only poorly (condition number "
                f"{fit.cond:.3g}, {geometry}): std = {np.round(fit.std, 5).tolist()}; {warn}",
                PoorlyIdentifiedWarning, stacklevel=3)

