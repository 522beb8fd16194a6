"""Calibration of both axes: the result object the CLI, the trajectory and the reports use."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from calib.calibration.lackoffit import (
    LackOfFit,
    correlated_groups,
    lack_of_fit_axes,
    pure_error_dof,
    pure_error_variance,
)
from calib.calibration.ls import FitResult, NotIdentifiableError, chi2_from_dof, fit_axis, fit_joint
from calib.conventions import AXES, JOINT_PARAM_NAMES, PARAM_NAMES, G
from calib.files.course import Ensayo
from calib.results import ResultMixin
from calib.units import nest, with_units

Method = Literal["ols", "wls", "multiposition"]
METHODS: tuple[str, ...] = ("ols", "wls", "multiposition")
"""Every method a :class:`Calibration` may come from (``multiposition``:
:meth:`calib.calibration.multiposition.MultiPositionFit.to_calibration`, θ unknown)."""


@dataclass(frozen=True, eq=False)
class Calibration(ResultMixin):
    """Bias and scale of both accelerometers with their joint covariance.

    Attributes
    ----------
    method : "ols" (per-axis, course method), "wls" (joint four-parameter WLS) or
        "multiposition" (θ unknown, :mod:`calib.calibration.multiposition`; ``joint`` holds the 4×4
        covariance, whose cross-axis terms the shared pose angles create).
    g : gravity used for the reference, m/s².
    fits : per-axis :class:`FitResult` (``("bias", "scale")``); for WLS the marginal blocks.
    joint : the joint four-parameter fit (WLS), or None.
    n : number of samples.
    lack_of_fit : per axis, the Draper & Smith test of the fit against the scatter within
        repeated poses (:mod:`calib.calibration.lackoffit`), or None when no pose repeats.

    σ² from the pure error (no ``noise_var``, poses repeat): ``sigma2_source`` is
    "estimated" and each fit's ``extra["sigma2_dof"]`` holds its dof N − c (Student t).

    ``params`` and ``cov`` are ordered ``[bias_x, scale_x, bias_y, scale_y]``.

    Serialisation: :meth:`to_dict` is the ``calibrate --json`` object (frozen by the snapshot
    test); it has no residuals, condition numbers or joint cross-covariances, so
    :meth:`to_state` adds them (keys ``fits`` and ``joint``) and
    ``Calibration.from_dict(c.to_state()) == c``. ``from_dict(c.to_dict())`` rebuilds the
    same printed object (what a ``cal.json`` holds) with empty residuals.
    """

    _TITLE = "Calibration"
    _UNITS = ("bias m/s² (positive: the reading is shifted up); scale dimensionless "
              "(positive: the sensor reads too much); std and confidence limits in the units of "
              "their parameter; σ² (m/s²)²; g m/s²; N samples")

    _JSON_UNITS = {  # the units of to_dict(), one home (docs/units.md)
        "g": "m/s²", "axes.*.bias": "m/s²", "axes.*.bias_std": "m/s²", "axes.*.scale": "1",
        "axes.*.scale_std": "1", "axes.*.cov": "[(m/s²)², m/s², m/s², 1]",
        "axes.*.sigma2": "(m/s²)²", "axes.*.chi2_dof": "1", "axes.*.n": "count",
    }

    method: Method
    g: float
    fits: dict[str, FitResult]
    n: int
    joint: FitResult | None = None
    lack_of_fit: dict[str, LackOfFit] | None = None

    @property
    def params(self) -> np.ndarray:
        if self.joint is not None:
            return self.joint.params.copy()
        return np.concatenate([self.fits[a].params for a in AXES])

    @property
    def cov(self) -> np.ndarray:
        if self.joint is not None:
            return self.joint.cov.copy()
        c = np.zeros((4, 4))
        c[:2, :2], c[2:, 2:] = self.fits["x"].cov, self.fits["y"].cov
        return c

    @property
    def bias(self) -> np.ndarray:
        """(2,) bias [x, y], m/s²."""
        return self.params[[0, 2]]

    @property
    def scale(self) -> np.ndarray:
        """(2,) scale factor error [x, y], dimensionless."""
        return self.params[[1, 3]]

    def to_dict(self) -> dict:
        """The documented ``calibrate --json`` object."""
        axes = {}
        for a in AXES:
            f = self.fits[a]
            axes[a] = {
                "bias": f.param("bias"), "bias_std": float(f.std[0]),
                "scale": f.param("scale"), "scale_std": float(f.std[1]),
                "cov": f.cov.tolist(), "sigma2": f.sigma2.item(),
                "sigma2_source": f.sigma2_source, "chi2_dof": f.chi2_dof, "n": self.n,
            }
            if "sigma2_dof" in f.extra:
                axes[a]["sigma2_dof"] = int(f.extra["sigma2_dof"])
        out = {"method": self.method, "g": self.g, "axes": axes}
        if self.lack_of_fit is not None:
            out["lack_of_fit"] = {a: v.to_dict() for a, v in self.lack_of_fit.items()}
        return with_units(out, {**self._JSON_UNITS, **self._optional_units(state=False)})

    def _optional_units(self, state: bool = True) -> dict[str, str]:
        """Units of the keys only some calibrations carry (pure-error dof, lack of fit,
        the multi-position angles), for :meth:`to_dict` (``state=False``) or
        :meth:`to_state`; empty for a course fit, whose documents stay as they were."""
        out: dict[str, str] = {}
        if any("sigma2_dof" in self.fits[a].extra for a in AXES):
            out["axes.*.sigma2_dof"] = "count"
            if state:
                out["fits.*.extra.sigma2_dof"] = "count"
                out["joint.extra.sigma2_dof"] = "count"
        if self.lack_of_fit is not None:
            out.update(nest("lack_of_fit.*", LackOfFit.JSON_UNITS))
        if state and self.joint is not None and "angles" in self.joint.extra:
            out["joint.extra.angles"] = "rad"
            out["joint.extra.angles_std"] = "rad"
        return out

    def state_units(self) -> dict[str, str]:
        """Units of the optional keys of :meth:`to_state` (added to a ``cal.json``'s
        ``units`` by :func:`calib.calibration.calfile.calibration_document`)."""
        return self._optional_units(state=True)

    def to_state(self) -> dict:
        """:meth:`to_dict` plus the full per-axis fits and the joint fit (exact rebuild)."""
        return {**self.to_dict(), "fits": {a: self.fits[a].to_dict() for a in AXES},
                "joint": None if self.joint is None else self.joint.to_dict()}

    @classmethod
    def from_dict(cls, d: dict) -> Calibration:
        """Rebuild from :meth:`to_state` (exact) or from :meth:`to_dict` / a ``cal.json``.

        Parameters
        ----------
        d : mapping with ``method``, ``g`` (m/s²) and ``axes`` → ``x``/``y`` →
            ``bias`` (m/s²), ``scale``, ``cov`` (2×2, order [bias, scale]), ``sigma2``
            ((m/s²)²), ``sigma2_source``, ``chi2_dof``, ``n``; optionally ``fits`` / ``joint``
            (from :meth:`to_state`).

        Examples
        --------
        >>> import numpy as np
        >>> from calib import Calibration, Ensayo, calibrate
        >>> th = np.linspace(0, 2 * np.pi, 100)
        >>> e = Ensayo(th, np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)]) + 0.05)
        >>> cal = calibrate(e, noise_var=[0.25, 0.64])
        >>> Calibration.from_dict(cal.to_state()) == cal
        True
        >>> Calibration.from_dict(cal.to_dict()).to_dict() == cal.to_dict()
        True
        """
        method, g = d["method"], float(d["g"])
        if d.get("fits") is not None:
            fits = {a: FitResult.from_dict(d["fits"][a]) for a in AXES}
            joint = None if d.get("joint") is None else FitResult.from_dict(d["joint"])
            n = int(d["axes"][AXES[0]]["n"])
            return cls(method, g, fits, n, joint, _lof_from(d))
        fits = {}
        n = 0
        for a in AXES:
            ax = d["axes"][a]
            n = int(ax["n"])
            fits[a] = FitResult(
                PARAM_NAMES, [ax["bias"], ax["scale"]], ax["cov"], np.zeros(0), ax["sigma2"],
                ax["sigma2_source"], n - 2, 2, float("nan"), chi2_from_dof(ax["chi2_dof"], n - 2),
                {"sigma2_dof": int(ax["sigma2_dof"])} if "sigma2_dof" in ax else {})
        return cls(method, g, fits, n, None, _lof_from(d))

    @property
    def std(self) -> np.ndarray:
        """(4,) standard deviations ``[bias_x, scale_x, bias_y, scale_y]`` (m/s², 1, m/s², 1)."""
        return np.sqrt(np.diag(self.cov))

    def summary(self, level: float = 0.95) -> str:
        title = {"ols": "per-axis OLS (course method)", "wls": "joint WLS (4 parameters)",
                 "multiposition": "multi-position (θ unknown, gravity norm)"}
        out = [f"Calibration: {title[self.method]}, g = {self.g} m/s², N = {self.n}"]
        for a in AXES:
            out.append(f"-- axis {a}")
            out += _axis_table(self.fits[a], level)
            if self.lack_of_fit is not None:
                out.append(self.lack_of_fit[a].summary())
        return "\n".join(out)

    def lack_of_fit_warnings(self, alpha: float | None = None) -> list[str]:
        """One line per axis whose lack-of-fit test rejects at ``alpha``
        (:data:`calib.calibration.lackoffit.LOF_ALPHA` by default): "the model misses something"."""
        from calib.calibration.lackoffit import LOF_ALPHA

        if self.lack_of_fit is None:
            return []
        a = LOF_ALPHA if alpha is None else alpha
        return [v.warning_line() for v in self.lack_of_fit.values() if v.misses(a)]


def _lof_from(d: dict) -> dict[str, LackOfFit] | None:
    lof = d.get("lack_of_fit")
    return None if lof is None else {a: LackOfFit.from_dict(v) for a, v in lof.items()}


_ROW_UNITS = {"bias": "m/s²", "scale": "1"}  # scale is dimensionless (1 + scale = gain)


def _axis_table(fit: FitResult, level: float) -> list[str]:
    """One axis: estimate, std and the ``level`` interval per parameter, each row with its
    unit; then σ² in (m/s²)², χ²/dof, dof and the condition number."""
    lo, hi = fit.conf_int(level).T
    pct = f"{100 * level:g}%"
    rows = [f"{'param':<8}{'unit':<6}{'estimate':>14}{'std':>13}{'[' + pct:>14}{pct + ']':>13}"]
    for i, name in enumerate(fit.param_names):
        rows.append(f"{name:<8}{_ROW_UNITS.get(name, ''):<6}{fit.params[i]:>14.6g}"
                    f"{fit.std[i]:>13.4g}{lo[i]:>14.6g}{hi[i]:>13.6g}")
    s2 = fit.sigma2.item()
    rows.append(f"σ² = {s2:.4g} (m/s²)² ({fit.sigma2_source}); χ²/dof = {fit.chi2_dof:.4f}; "
                f"dof = {fit.dof}; cond = {fit.cond:.3g}")
    return rows


def calibrate(
    ensayo: Ensayo, noise_var=None, method: Method = "ols", g: float = G,
    groups: np.ndarray | None = None,
) -> Calibration:
    """Estimate bias and scale of both axes from a calibration run.

    Parameters
    ----------
    ensayo : the run (θ in rad, readings in m/s²), or a measured log
        (:class:`calib.logs.reader.ImuLog`) that gives θ (its held poses, if any, are the
        groups).
    noise_var : (2,) noise variances [σx², σy²] (m/s²)², a 2×2 covariance (WLS only), or
        None to estimate them from the residuals.
    method : "ols" — per axis, ``A_m - A_r = bias + scale·A_r`` (course method);
        "wls" — joint four-parameter WLS weighted by the noise covariance.
    g : gravity, m/s² (reference ``A_rx = -g sin θ``, ``A_ry = -g cos θ``).
    groups : (N,) int, the held pose (or repeated θ) of each sample
        (:func:`calib.calibration.lackoffit.groups_from`), or None. When samples repeat: the
        lack-of-fit F test of each axis (``lack_of_fit``) and, with ``noise_var`` None, σ² from the
        pure error (scatter within the groups, N − c dof, Student t) instead of the residuals
        — which would absorb what the model misses and print χ²/dof = 1.

    Returns
    -------
    Calibration : ``bias`` (2,) m/s², ``scale`` (2,), ``params`` (4,) and ``cov`` (4, 4)
    ordered ``[bias_x, scale_x, bias_y, scale_y]``; per-axis fits in ``fits``.

    Examples
    --------
    >>> import numpy as np
    >>> from calib import Ensayo, calibrate
    >>> th = np.linspace(0.0, 2 * np.pi, 100, endpoint=False)
    >>> datos = np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)]) * 0.97 + 0.08
    >>> cal = calibrate(Ensayo(th, datos), noise_var=[0.25, 0.64])
    >>> np.round(cal.bias, 9).tolist(), np.round(cal.scale, 9).tolist()
    ([0.08, 0.08], [-0.03, -0.03])
    """
    if method not in ("ols", "wls"):
        raise ValueError(f"method must be 'ols' or 'wls', got {method!r}")
    if not isinstance(ensayo, Ensayo) and hasattr(ensayo, "to_ensayo"):  # a measured log
        if getattr(ensayo, "theta", None) is None:
            raise TypeError(f"{ensayo.source}: calibrate needs the table angle θ, which this log "
                            "does not give; for held poses without θ call "
                            "calib.fit_multiposition(pose_statistics(log.acc, log.pose)) (or "
                            "fit_multiposition3d / fit_six_face with the third axis)")
        if groups is None and ensayo.pose is not None:
            groups = ensayo.pose
        ensayo = ensayo.to_ensayo()
    try:
        if groups is None:
            return _calibrate(ensayo, noise_var, method, g)
        return _with_groups(ensayo, noise_var, method, g, np.asarray(groups, dtype=int))
    except NotIdentifiableError as exc:  # name the file the design came from
        if ensayo.source == "<memory>" or str(exc).startswith(ensayo.source):
            raise
        raise NotIdentifiableError(f"{ensayo.source}: {exc}") from exc


def _with_groups(ensayo: Ensayo, noise_var, method: Method, g: float,
                 groups: np.ndarray) -> Calibration:
    """:func:`calibrate` with repeated poses: pure-error σ² (when not given), lack of fit."""
    if groups.shape != (ensayo.n,):
        raise ValueError(f"groups must have shape ({ensayo.n},), got {groups.shape}")
    # correlated samples (a filtered log): each group counts n/τ independent ones, so every
    # variance of a mean — the stated σ² and the pure error alike — is read per τ samples
    tau = correlated_groups(ensayo.datos, groups)
    pe = None
    if noise_var is None:
        try:
            s2, dof = pure_error_variance(ensayo.datos, groups)
        except ValueError:
            s2, dof = None, 0
        if s2 is not None and np.all(s2 > 0):
            pe = (s2 * tau, pure_error_dof(groups, tau) if tau > 1.0 else dof)
    if noise_var is not None and tau > 1.0:
        noise_var = np.asarray(noise_var, dtype=float) * tau
    cal = _calibrate(ensayo, noise_var if pe is None else pe[0], method, g)
    if pe is not None:
        extra = {"sigma2_dof": pe[1]}
        if tau > 1.0:
            extra["tau_int"] = float(tau)

        def est(f: FitResult) -> FitResult:
            return replace(f, sigma2_source="estimated", extra={**f.extra, **extra})

        cal = replace(cal, fits={a: est(cal.fits[a]) for a in AXES},
                      joint=None if cal.joint is None else est(cal.joint))
    resid = np.column_stack([cal.fits[a].residuals for a in AXES])
    return replace(cal, lack_of_fit=lack_of_fit_axes(resid, groups, 2, tau))


def _calibrate(ensayo: Ensayo, noise_var, method: Method, g: float) -> Calibration:
    if method == "ols":
        nv = [None, None] if noise_var is None else np.asarray(noise_var, dtype=float)
        if noise_var is not None and nv.shape == (2, 2):
            nv = np.diag(nv)
        fits = {a: fit_axis(ensayo.tita, ensayo.datos[:, k], a,
                            None if nv[k] is None else float(nv[k]), g)
                for k, a in enumerate(AXES)}
        return Calibration("ols", g, fits, ensayo.n)
    joint = fit_joint(ensayo.tita, ensayo.datos, noise_var, g)
    n = ensayo.n
    fits = {}
    for k, a in enumerate(AXES):
        sl = slice(2 * k, 2 * k + 2)
        r = joint.residuals[:, k]
        s2 = joint.sigma2[k]
        fits[a] = FitResult(PARAM_NAMES, joint.params[sl], joint.cov[sl, sl], r, s2,
                            joint.sigma2_source, n - 2, 2, joint.cond, float(r @ r / s2))
    return Calibration("wls", g, fits, n, joint=joint)


__all__ = ["METHODS", "Calibration", "calibrate", "JOINT_PARAM_NAMES"]
