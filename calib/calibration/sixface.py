"""The six-face test of a 3-axis accelerometer: bias, scale and misalignment of all three axes
from holds on the faces of its case, with hold-to-hold repeatability in every interval.

Model (IEEE Std 1293 accelerometer model, its linear terms; MATLAB ``accelcal``'s
``C = U·A + b``). Hold h rests on a face of the case, so that the specific force of gravity
points along a case axis ``u_h = ±e_k`` (face ``+z``: the z axis points up and reads about
+1 g). Each axis a reads the hold's mean::

    m̄_h,a = b_a + g · (K_a · u_h) + ε_h,a,      ε_h,a ~ N(0, σ_B,a² + σ_W,a² / n_h)

    K = (I + S)(I + M):  K_aa = 1 + s_a,   K_ab = (1 + s_a) · m_ab    (a ≠ b)

``b`` bias (m/s², K0), ``s`` scale (dimensionless, K1 − 1; positive: the axis reads too much),
``m_ab`` misalignment (rad, small angle: the sensitive axis a leans toward case axis b; positive
when a reads +m_ab·g with case axis b up). Each row ``[b_a, K_ax, K_ay, K_az]`` enters linearly
(design rows ``[1, g·u_h]``) and is fitted by weighted least squares with a QR factor; the
misalignments ``m_ab = K_ab / K_aa`` get their covariance by the delta method. The axes are
fitted separately: their noises are taken as independent.

The noise of a hold mean has two parts (one-way random effects, Searle, Casella & McCulloch,
*Variance Components*, 1992, ch. 3):

* within the hold, ``σ_W,a²`` — the pooled scatter of the samples about their hold's mean,
  ``MS_W = SS_W / (N − H)``;
* between holds, ``σ_B,a²`` — re-holding the same face reads differently (the case sits
  differently, the bias wanders). Measured only when a face is held more than once: the hold
  means of one face scatter about that face's mean by ``SS_PE`` with ``H − F`` dof and
  ``E[SS_PE] = (H − F)·σ_B² + σ_W²·c``, ``c = Σ_f (1 − 1/H_f) Σ_{h∈f} 1/n_h`` (ANOVA
  estimator, truncated at 0).

Every interval uses ``v_h = σ̂_B² + σ̂_W²/n_h`` and a Student t quantile with Satterthwaite's
dof for ``v̄ = MS_PE·1 + MS_W·(1/n̄ − c/(H − F))``. With ``σ_B`` truly zero the estimate is
zero about half the time and otherwise small, so the intervals do not widen beyond chance;
with no face held twice the repeatability is not measured and the result says so.

Lack of fit (per axis): the hold means that the linear model misses beyond the pure error —
``F = (SS_LOF/(F − 4)) / (SS_PE/(H − F))`` from the unweighted fit — or, without re-holds,
the weighted residuals against the within-hold scatter, ``(RSS_W/(H − 4))`` on
``F(H − 4, N − H)``. A missing term (a second-order K2, a face that is not flat) shows here,
not in σ_B.

When an axis's lack of fit is significant (p < :data:`LOF_ALPHA`) the misfit is not left out
of its intervals: the face means then miss the model by more than the repeatability explains
(a face that is not flat, a missing term), so that axis is estimated from the F face means with
equal weights and its covariance taken from their scatter about the model,
``s² = RSS_F/(F − 4)``, Student t on F − 4 dof (``_misfit_axis``; one line of the summary names
the axes). The rule is a pre-test, and its coverage is what a pre-test gives (measured in
``tests/test_sixface.py``): with no misfit it triggers in α of the fits and coverage stays in
its band; on the axes it flags, the intervals cover (0.97–0.99 with face errors of 0.02–0.05 m/s²
against a hold-mean noise of 0.004 m/s²); a misfit too small for the test to see is not in the
intervals, and the printed lack-of-fit p-value is then the only sign of it.

What the faces identify: per axis the four columns ``1, u_x, u_y, u_z`` need faces along every
case axis and at least four faces in all; a design that misses one is refused with the names
of the parameters it cannot identify and the faces that would. The case's own placement on the
table cannot be told apart from the sensor's misalignment relative to the case: ``m_ab`` is the
misalignment relative to the faces used.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import linalg, stats

from calib.calibration.ls import NotIdentifiableError
from calib.calibration.multiposition.shared import Poses
from calib.conventions import G
from calib.input_rules import DataError
from calib.results import ResultMixin, readonly

AXES_3: tuple[str, str, str] = ("x", "y", "z")
FACE_COS: float = float(np.cos(np.radians(20.0)))
"""A hold is on a face when its mean reading lies within 20° of one case axis."""
LOF_ALPHA: float = 0.05


def face_name(u: np.ndarray) -> str:
    """``"+z"`` for ``u = (0, 0, 1)``: the case axis that points up, with its sign."""
    k = int(np.argmax(np.abs(u)))
    return ("+" if u[k] > 0 else "-") + AXES_3[k]


def face_vectors(faces: tuple[str, ...]) -> np.ndarray:
    """The inverse of :func:`face_name`: (H, 3) unit vectors ``±e_k`` of faces ``"+x"`` …"""
    u = np.zeros((len(faces), 3))
    for h, f in enumerate(faces):
        u[h, AXES_3.index(f[1])] = 1.0 if f[0] == "+" else -1.0
    return u


def faces_of(means: np.ndarray, source: str = "<memory>") -> np.ndarray:
    """The face ``u_h = ±e_k`` (H, 3) of each hold from its mean reading ``means`` (H, 3) m/s²:
    the axis with the largest |mean| and its sign; DataError for a hold more than 20° from
    every face (a tilted hold belongs to the multi-position fit, not the six-face test)."""
    means = np.asarray(means, dtype=float)
    norm = np.linalg.norm(means, axis=1)
    k = np.argmax(np.abs(means), axis=1)
    lead = np.abs(means[np.arange(len(means)), k])
    off = np.flatnonzero(lead < FACE_COS * norm)
    if off.size:
        i = int(off[0])
        angle = np.degrees(np.arccos(np.clip(lead[i] / norm[i], -1, 1)))
        raise DataError(f"{source}: hold {i} is not on a face of the case: its reading is "
                        f"{angle:.0f}° from the nearest axis (a face is within 20°); use the "
                        "multi-position fit for tilted holds")
    u = np.zeros_like(means)
    u[np.arange(len(means)), k] = np.sign(means[np.arange(len(means)), k])
    return u


def on_faces(poses: Poses) -> bool:
    """True when the holds of a 3-axis log make a six-face test: every hold within 20° of a
    case axis, on faces that identify every parameter (:func:`fit_six_face` would not refuse
    the design)."""
    means = np.asarray(poses.means, dtype=float)
    if means.ndim != 2 or means.shape[1] != 3 or len(means) < 4:
        return False
    try:
        u = faces_of(means)
    except DataError:
        return False
    x = np.column_stack([np.ones(len(u)), u])
    return not _unidentified(x)


def _unidentified(x: np.ndarray) -> list[str]:
    """Names of the parameters the faces cannot identify: every row shares the design ``x``
    (H, 4) = ``[1, g·u_h]``, so a column in its null space leaves that parameter free on each
    axis. Empty when ``x`` has full rank (which needs at least 4 distinct faces)."""
    _, s, vt = np.linalg.svd(x / np.linalg.norm(x, axis=0).clip(min=1e-300),
                             full_matrices=True)
    rank = int(np.sum(s > s[0] * 1e-10)) if s.size else 0
    free = np.flatnonzero(np.any(np.abs(vt[rank:]) > 1e-8, axis=0))
    out = []
    for axis in AXES_3:
        for j in free:
            if j == 0:
                out.append(f"bias_{axis}")
            elif AXES_3[j - 1] == axis:
                out.append(f"scale_{axis}")
            else:
                out.append(f"misalignment_{axis}{AXES_3[j - 1]}")
    return out


@dataclass(frozen=True, eq=False)
class SixFaceFit(ResultMixin):
    """Bias, scale and misalignment of three axes from a six-face test (module docstring).

    Attributes
    ----------
    param_names : the 12 names, per axis a: ``bias_a`` (m/s²), ``scale_a`` (dimensionless),
        then its two misalignments ``misalignment_ab`` (rad).
    params : (12,) estimates in that order.
    cov : (12, 12) covariance (block diagonal by axis), hold-to-hold repeatability included.
    dof : (3,) Satterthwaite dof of each axis' variance (Student t quantiles).
    k_matrix : (3, 3) K = (I + S)(I + M), dimensionless (rows: sensor axes; columns: case
        axes).
    residuals : (H, 3) m/s², hold means minus the model.
    hold_std : (H, 3) m/s², the std of each hold mean the fit used, ``√(σ̂_B² + σ̂_W²/n_h)``.
    faces : tuple of H face names (``"+x"`` …), one per hold.
    n : (H,) samples per hold.
    sigma_within : (3,) σ_W per axis, m/s²; ``sigma_between``: (3,) σ_B, m/s², NaN when no face
        is held twice (not measured).
    widening : (3,) how much hold-to-hold repeatability widened each axis' intervals (ratio
        of the bias half-width to the within-hold-only one; 1 when σ_B = 0, NaN if not
        measured).
    lack_of_fit_p : (3,) p-value of each axis' lack-of-fit test (NaN with no dof left).
    misfit_in_intervals : (3,) True for an axis whose lack of fit was significant: its
        estimate and intervals come from the face means and their scatter about the model
        (Student t on F − 4 dof), the misfit counted as uncertainty (:func:`_misfit_axis`).
    g : gravity used, m/s²; ``g_source``: where it came from.
    level : the level of the intervals :meth:`summary` prints.
    """

    param_names: tuple[str, ...]
    params: np.ndarray
    cov: np.ndarray
    dof: np.ndarray
    k_matrix: np.ndarray
    residuals: np.ndarray
    hold_std: np.ndarray
    faces: tuple[str, ...]
    n: np.ndarray
    sigma_within: np.ndarray
    sigma_between: np.ndarray
    widening: np.ndarray
    lack_of_fit_p: np.ndarray
    g: float
    g_source: str = "given"
    level: float = 0.95
    source: str = field(default="<memory>", compare=False)
    misfit_in_intervals: tuple[bool, ...] = (False, False, False)

    _TITLE = "Six-face calibration (3 axes)"
    _UNITS = "bias m/s²; scale dimensionless; misalignment rad; σ m/s²; g m/s²"

    def __post_init__(self) -> None:
        for name in ("params", "cov", "dof", "k_matrix", "residuals", "hold_std", "sigma_within",
                     "sigma_between", "widening", "lack_of_fit_p"):
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "n", readonly(self.n, int))
        object.__setattr__(self, "param_names", tuple(self.param_names))
        object.__setattr__(self, "faces", tuple(self.faces))
        object.__setattr__(self, "misfit_in_intervals",
                           tuple(bool(v) for v in self.misfit_in_intervals))

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.diag(self.cov))

    @property
    def bias(self) -> np.ndarray:
        """(3,) m/s²."""
        return self.params[0::4]

    @property
    def scale(self) -> np.ndarray:
        """(3,) dimensionless."""
        return self.params[1::4]

    @property
    def misalignment(self) -> np.ndarray:
        """(3, 3) rad, ``m_ab`` off the diagonal, 0 on it."""
        return self.k_matrix / np.diag(self.k_matrix)[:, None] - np.eye(3)

    @property
    def repeatability_measured(self) -> bool:
        return bool(np.all(np.isfinite(self.sigma_between)))

    def quantiles(self, level: float | None = None) -> np.ndarray:
        """(12,) two-sided Student t quantile of each parameter (its axis' dof)."""
        lv = self.level if level is None else level
        if not 0 < lv < 1:
            raise ValueError(f"level must be in (0, 1), got {lv}")
        return np.repeat(stats.t.ppf(0.5 + lv / 2, self.dof), 4)

    def conf_int(self, level: float | None = None) -> np.ndarray:
        """(12, 2) intervals at ``level`` (default: :attr:`level`)."""
        half = self.quantiles(level) * self.std
        return np.column_stack([self.params - half, self.params + half])

    def apply_errors(self, acc: np.ndarray) -> np.ndarray:
        """The readings a sensor with these errors gives, without noise: ``m = b + K a``.

        Parameters
        ----------
        acc : (3,) or (N, 3) specific force in the case frame, m/s² (columns x, y, z).

        Returns
        -------
        (3,) or (N, 3) readings, m/s² (the sensor axes x, y, z). :meth:`correct` inverts it.
        """
        a = np.asarray(acc, dtype=float)
        return self.bias + a @ self.k_matrix.T

    def correct(self, readings: np.ndarray) -> np.ndarray:
        """Corrected specific force ``a = K⁻¹ (m − b)``, the model of the module docstring
        inverted.

        Parameters
        ----------
        readings : (3,) or (N, 3) readings ``m`` of the sensor axes x, y, z, m/s² (a log
            read with the calibration's ``--axes a,b``: x = a, y = b, z = â × b̂).

        Returns
        -------
        (3,) or (N, 3) specific force ``a`` in the case frame, m/s²: a still sensor on face
        ``+z`` reads ``a ≈ (0, 0, +g)``.

        Notes
        -----
        IEEE Std 1293 accelerometer model, linear terms: ``m = b + K a`` with
        ``K = (I + S)(I + M)``, ``b`` the bias (K0, m/s²), ``S = diag(s)`` the scale-factor
        errors (K1 − 1; positive: the axis reads too much) and ``M`` the misalignments
        ``m_ab`` (rad; positive: axis a reads ``+m_ab·g`` with case axis b up). The bias is
        subtracted first, then ``K a = m − b`` is solved by one LU factorisation of K for
        every sample (no explicit inverse). With ``M = 0`` each axis reduces to the course's
        ``A_r = (A_m − bias)/(1 + scale)``.
        """
        m = np.asarray(readings, dtype=float)
        if m.shape[-1:] != (3,) or m.ndim > 2:
            raise ValueError(f"readings must have shape (3,) or (N, 3), got {m.shape}")
        lu = linalg.lu_factor(self.k_matrix)
        return linalg.lu_solve(lu, (m - self.bias).T).T

    def repeatability_line(self) -> str:
        """What hold-to-hold repeatability did to the intervals (one or two lines)."""
        if not self.repeatability_measured:
            return ("hold-to-hold repeatability: not measured (no face held twice); the "
                    "intervals count the scatter within holds only")
        sb = ", ".join(f"{a} {v:.3g}" for a, v in zip(AXES_3, self.sigma_between, strict=True))
        wd = ", ".join(f"{a} ×{v:.2f}" for a, v in zip(AXES_3, self.widening, strict=True))
        return (f"hold-to-hold repeatability σ_B (m/s²): {sb}\n  intervals widened by it"
                f"{' and the misfit' if any(self.misfit_in_intervals) else ''}: {wd}")

    def misfit_line(self) -> str | None:
        """One line naming the axes whose significant lack of fit was put into their
        intervals, or None."""
        axes = [a for a, m in zip(AXES_3, self.misfit_in_intervals, strict=True) if m]
        if not axes:
            return None
        dof = ", ".join(f"{a} {self.dof[AXES_3.index(a)]:.0f}" for a in axes)
        return (f"lack of fit on {', '.join(axes)}: the face means miss the model beyond the "
                "repeatability (a face not flat, or a missing term), so those axes' estimates "
                "and intervals come from the face means and their scatter about the model "
                f"(Student t, dof {dof})")

    def summary(self) -> str:
        ci = self.conf_int()
        pct = f"{100 * self.level:g} %"
        lines = [f"six-face calibration of {self.source}: {len(self.faces)} holds on "
                 f"{len(set(self.faces))} faces ({', '.join(sorted(set(self.faces)))}), "
                 f"g = {self.g:.7g} m/s² ({self.g_source})",
                 f"{'parameter':<18} {'estimate':>12} {'std':>10}   {pct} interval"]
        for name, v, s, (lo, hi) in zip(self.param_names, self.params, self.std, ci,
                                        strict=True):
            unit = "m/s²" if name.startswith("bias") else (
                "rad" if name.startswith("misalignment") else "")
            lines.append(f"{name:<18} {v:>12.6g} {s:>10.3g}   [{lo:.6g}, {hi:.6g}] {unit}".rstrip())
        lines.append(self.repeatability_line())
        if self.misfit_line():
            lines.append(self.misfit_line())
        lof = ", ".join("n/a" if not np.isfinite(p) else f"{a} p = {p:.2g}"
                        for a, p in zip(AXES_3, self.lack_of_fit_p, strict=True))
        lines.append(f"lack of fit (α = {LOF_ALPHA}): {lof}")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {"method": "six-face", "source": self.source,
                "param_names": list(self.param_names), "params": self.params.tolist(),
                "cov": self.cov.tolist(), "dof": self.dof.tolist(),
                "k_matrix": self.k_matrix.tolist(), "residuals": self.residuals.tolist(),
                "hold_std": self.hold_std.tolist(),
                "faces": list(self.faces), "n": self.n.tolist(),
                "sigma_within": self.sigma_within.tolist(),
                "sigma_between": [None if not np.isfinite(v) else v
                                  for v in self.sigma_between.tolist()],
                "widening": [None if not np.isfinite(v) else v
                             for v in self.widening.tolist()],
                "lack_of_fit_p": [None if not np.isfinite(v) else v
                                  for v in self.lack_of_fit_p.tolist()],
                "g": self.g, "g_source": self.g_source, "level": self.level,
                "misfit_in_intervals": list(self.misfit_in_intervals)}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> SixFaceFit:
        def arr(key: str) -> np.ndarray:
            return np.array([np.nan if v is None else v for v in d[key]], dtype=float)

        return cls(param_names=tuple(d["param_names"]), params=np.array(d["params"]),
                   cov=np.array(d["cov"]), dof=np.array(d["dof"]),
                   k_matrix=np.array(d["k_matrix"]), residuals=np.array(d["residuals"]),
                   hold_std=np.array(d["hold_std"]),
                   faces=tuple(d["faces"]), n=np.array(d["n"]),
                   sigma_within=np.array(d["sigma_within"]), sigma_between=arr("sigma_between"),
                   widening=arr("widening"), lack_of_fit_p=arr("lack_of_fit_p"),
                   g=float(d["g"]), g_source=d["g_source"], level=float(d["level"]),
                   source=d.get("source", "<memory>"),
                   misfit_in_intervals=tuple(d.get("misfit_in_intervals",
                                                   (False, False, False))))


@dataclass(frozen=True)
class _AxisFit:
    row: np.ndarray  # (4,) [b, K_x, K_y, K_z]
    cov: np.ndarray  # (4, 4)
    dof: float
    resid: np.ndarray  # (H,)
    hold_std: np.ndarray  # (H,) √v_h
    sigma_w: float
    sigma_b: float  # NaN: not measured
    widening: float
    lof_p: float
    lof_in_intervals: bool = False


def _wls(x: np.ndarray, y: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row estimate and covariance of ``y = x p + ε``, ``Var ε = diag(v)``: QR of the
    whitened design, ``cov = R⁻¹R⁻ᵀ`` (no normal matrix)."""
    w = 1.0 / np.sqrt(v)
    p, *_ = np.linalg.lstsq(x * w[:, None], y * w, rcond=None)
    r = np.linalg.qr(x * w[:, None], mode="r")
    ri = linalg.solve_triangular(r, np.eye(r.shape[0]))
    return p, ri @ ri.T


def _fit_axis(x: np.ndarray, y: np.ndarray, n: np.ndarray, ss_w: float,
              face: np.ndarray) -> _AxisFit:
    h, p = x.shape
    dof_w = int(n.sum()) - h
    ms_w = ss_w / dof_w
    groups = [np.flatnonzero(face == f) for f in np.unique(face)]
    n_faces = len(groups)
    dof_pe = h - n_faces
    nbar = h / float(np.sum(1.0 / n))  # harmonic mean: v̄ = σ_B² + σ_W²/n̄
    if dof_pe > 0:
        ss_pe = float(sum(np.sum((y[g] - y[g].mean()) ** 2) for g in groups))
        c = float(sum((1 - 1 / len(g)) * np.sum(1.0 / n[g]) for g in groups))
        sigma_b2 = max(0.0, (ss_pe - ms_w * c) / dof_pe)
        if sigma_b2 > 0:  # Satterthwaite: v̄ = 1·MS_PE + (1/n̄ − c/dof_pe)·MS_W
            ms_pe = ss_pe / dof_pe
            a2 = 1 / nbar - c / dof_pe
            vbar = ms_pe + a2 * ms_w
            dof = vbar**2 / (ms_pe**2 / dof_pe + (a2 * ms_w) ** 2 / dof_w)
        else:
            dof = float(dof_w)
    else:
        ss_pe, sigma_b2, dof = np.nan, np.nan, float(dof_w)
    v = (0.0 if np.isnan(sigma_b2) else sigma_b2) + ms_w / n
    row, cov = _wls(x, y, v)
    resid = y - x @ row
    if np.isnan(sigma_b2):
        widening = np.nan
    else:
        _, cov_w = _wls(x, y, ms_w / n)
        q = stats.t.ppf(0.975, dof) / stats.t.ppf(0.975, dof_w)
        widening = float(q * np.sqrt(cov[0, 0] / cov_w[0, 0]))
    dof_lof = n_faces - p
    if dof_pe > 0 and dof_lof > 0:  # unweighted fit: RSS = SS_PE + SS_LOF
        p_u, *_ = np.linalg.lstsq(x, y, rcond=None)
        ss_lof = max(0.0, float(np.sum((y - x @ p_u) ** 2)) - ss_pe)
        f = (ss_lof / dof_lof) / (ss_pe / dof_pe) if ss_pe > 0 else np.inf
        lof_p = float(stats.f.sf(f, dof_lof, dof_pe))
    elif dof_pe <= 0 and h > p:
        f = float(np.sum(resid**2 / v)) / (h - p)
        lof_p = float(stats.f.sf(f, h - p, dof_w))
    else:
        lof_p = np.nan
    sigma_b = float(np.sqrt(sigma_b2)) if np.isfinite(sigma_b2) else np.nan
    if np.isfinite(lof_p) and lof_p < LOF_ALPHA:
        return _misfit_axis(x, y, n, ms_w, face, groups, v, sigma_b, lof_p, dof_w)
    return _AxisFit(row, cov, float(dof), resid, np.sqrt(v), float(np.sqrt(ms_w)), sigma_b,
                    widening, lof_p)


def _misfit_axis(x: np.ndarray, y: np.ndarray, n: np.ndarray, ms_w: float, face: np.ndarray,
                 groups: list[np.ndarray], v: np.ndarray, sigma_b: float, lof_p: float,
                 dof_w: int) -> _AxisFit:
    """The axis fit when its lack of fit is significant (:data:`LOF_ALPHA`): the face means
    miss the linear model by more than the holds' repeatability explains (a face that is not
    flat, a term the model lacks). That misfit is then part of the uncertainty: each face f
    gets an error ``φ_f`` of unknown variance shared by its re-holds, so the estimate comes
    from the F face means ``ȳ_f = x_f p + φ_f + ε̄_f`` by least squares with equal weights,
    and its covariance from their scatter about the model, ``s² = RSS_F / (F − 4)``, with a
    Student t on F − 4 dof (``cov = s²·R⁻¹R⁻ᵀ`` from the QR of the face design). With six
    faces that is 2 dof: wide, as a misfit seen on six points deserves. Under the null (no
    misfit) the rule triggers in a fraction α of the fits and the wider interval still
    covers, so coverage does not fall; when the misfit is real the repeatability-only
    interval would not cover (the imucal session: 4 of 12 parameters outside it)."""
    h, p = x.shape
    xf = np.array([x[g[0]] for g in groups])
    yf = np.array([y[g].mean() for g in groups])
    f = len(groups)
    row, *_ = np.linalg.lstsq(xf, yf, rcond=None)
    s2 = float(np.sum((yf - xf @ row) ** 2)) / (f - p)
    r = np.linalg.qr(xf, mode="r")
    ri = linalg.solve_triangular(r, np.eye(p))
    cov = s2 * (ri @ ri.T)
    dof = float(f - p)
    _, cov_w = _wls(x, y, ms_w / n)
    widening = float(stats.t.ppf(0.975, dof) / stats.t.ppf(0.975, dof_w)
                     * np.sqrt(cov[0, 0] / cov_w[0, 0]))
    # each hold's std as drawn: at least the face-level scatter s² (shared by its re-holds)
    hold_std = np.sqrt(np.maximum(v, s2))
    return _AxisFit(row, cov, dof, y - x @ row, hold_std, float(np.sqrt(ms_w)), sigma_b,
                    widening, lof_p, lof_in_intervals=True)


def fit_six_face(poses: Poses, g: float = G, g_source: str = "given", level: float = 0.95,
                 source: str = "<memory>") -> SixFaceFit:
    """Bias, scale and misalignment of three axes from holds on the faces of the case.

    Parameters
    ----------
    poses : the holds (:func:`calib.calibration.multiposition.pose_statistics` of an (N, 3)
        log in m/s² with hold labels): means (H, 3), counts, within-hold sums of squares.
        Re-holds of one face are separate holds (that is how repeatability is measured).
    g : the local gravity the sensor feels, m/s² (``--g``, or
        :func:`calib.conventions.normal_gravity` of the latitude and height).
    g_source : where ``g`` came from, for the record (e.g. ``"--latitude 55 --height 5000"``).
    level : the level of the printed intervals.
    source : the log's name, for messages.

    Returns
    -------
    SixFaceFit

    Examples
    --------
    >>> import numpy as np
    >>> from calib.calibration.multiposition import Poses
    >>> u = np.repeat(np.vstack([np.eye(3), -np.eye(3)]), 2, axis=0)  # six faces, twice
    >>> k = np.array([[1.01, 0.002, 0.0], [0.0, 0.99, -0.001], [0.003, 0.0, 1.02]])
    >>> means = 0.05 + 9.8 * u @ k.T
    >>> fit = fit_six_face(Poses(np.arange(12), np.full(12, 100), means, np.ones((12, 3))))
    >>> np.round(fit.scale, 9).tolist(), round(float(fit.misalignment[0, 1]), 9)
    ([0.01, -0.01, 0.02], 0.001980198)
    """
    means = np.asarray(poses.means, dtype=float)
    if means.ndim != 2 or means.shape[1] != 3:
        raise DataError(f"{source}: the six-face test needs three axes; the holds have "
                        f"{means.shape[-1]} (give the log's third axis)")
    if not (np.isfinite(g) and g > 0):
        raise ValueError(f"g must be a positive number of m/s², got {g}")
    u = faces_of(means, source)
    names_h = tuple(face_name(r) for r in u)
    face = np.array([AXES_3.index(f[1]) * 2 + (f[0] == "-") for f in names_h])
    x = np.column_stack([np.ones(len(u)), g * u])
    missing = [f"{s}{a}" for a in AXES_3 for s in "+-" if f"{s}{a}" not in names_h]
    bad = _unidentified(x)
    if bad:
        raise NotIdentifiableError(
            f"{source}: the faces held ({', '.join(sorted(set(names_h)))}) cannot identify "
            f"{', '.join(bad)}; hold the case also on {', '.join(missing) or 'more faces'}")
    n = np.asarray(poses.n, dtype=int)
    if np.any(n < 2):
        raise DataError(f"{source}: every hold needs at least 2 samples (the scatter within "
                        "it); got a hold of 1")
    ss_w = np.sum(np.asarray(poses.ss, dtype=float), axis=0)
    if np.any(ss_w <= 0):
        axis = AXES_3[int(np.argmin(ss_w))]
        raise DataError(f"{source}: axis {axis} does not vary within any hold (no scatter to "
                        "weigh the holds by): its readings are quantized coarser than their "
                        "noise; the six-face test needs noise to estimate its intervals")
    fits = [_fit_axis(x, means[:, k], n, float(ss_w[k]), face) for k in range(3)]
    k_matrix = np.array([f.row[1:] for f in fits])
    params, blocks, names = [], [], []
    for k, (a, f) in enumerate(zip(AXES_3, fits, strict=True)):
        kaa = f.row[1 + k]
        others = [j for j in range(3) if j != k]
        # derived d = [b, K_aa − 1, K_ab/K_aa, K_ac/K_aa]; J = ∂d/∂[b, K_ax, K_ay, K_az]
        jac = np.zeros((4, 4))
        jac[0, 0] = 1.0
        jac[1, 1 + k] = 1.0
        for i, j in enumerate(others):
            jac[2 + i, 1 + j] = 1.0 / kaa
            jac[2 + i, 1 + k] = -f.row[1 + j] / kaa**2
        params += [f.row[0], kaa - 1.0, *(f.row[1 + j] / kaa for j in others)]
        blocks.append(jac @ f.cov @ jac.T)
        names += [f"bias_{a}", f"scale_{a}", *(f"misalignment_{a}{AXES_3[j]}" for j in others)]
    return SixFaceFit(
        param_names=tuple(names), params=np.array(params), cov=linalg.block_diag(*blocks),
        dof=np.array([f.dof for f in fits]), k_matrix=k_matrix,
        residuals=np.column_stack([f.resid for f in fits]),
        hold_std=np.column_stack([f.hold_std for f in fits]), faces=names_h, n=n,
        sigma_within=np.array([f.sigma_w for f in fits]),
        sigma_between=np.array([f.sigma_b for f in fits]),
        widening=np.array([f.widening for f in fits]),
        lack_of_fit_p=np.array([f.lof_p for f in fits]), g=float(g), g_source=g_source,
        level=level, source=source,
        misfit_in_intervals=tuple(f.lof_in_intervals for f in fits))


__all__ = ["AXES_3", "FACE_COS", "LOF_ALPHA", "SixFaceFit", "face_name", "face_vectors", "faces_of",
           "fit_six_face", "on_faces"]
