"""The six-face test of a 3-axis accelerometer: bias, scale and misalignment of all three axes
from holds on the faces of its case, with hold-to-hold repeatability in every interval.

Model (IEEE Std 1293 accelerometer model, its linear terms; MATLAB ``accelcal``'s
``C = U·A + b``). Hold h rests on a face of the case, so that the specific force of gravity
points along a case axis ``u_h = ±e_k`` (face ``+z``: the z axis points up and reads about
+1 g). Each axis a reads the hold's mean::

    m̄_h,a = b_a + g · (K_a · u_h) + ε_h,a,      ε_h,a ~ N(0, σ_c(h),a² + σ_W,a² / n_h)

    K = (I + S)(I + M):  K_aa = 1 + s_a,   K_ab = (1 + s_a) · m_ab    (a ≠ b)

``b`` bias (m/s², K0), ``s`` scale (dimensionless, K1 − 1; positive: the axis reads too much),
``m_ab`` misalignment (rad, small angle: the sensitive axis a leans toward case axis b; positive
when a reads +m_ab·g with case axis b up). Each row ``[b_a, K_ax, K_ay, K_az]`` enters linearly
(design rows ``[1, g·u_h]``) and is fitted by weighted least squares with a QR factor; the
misalignments ``m_ab = K_ab / K_aa`` get their covariance by the delta method. The axes are
fitted separately: their noises are taken as independent (a placement tilt moves two level
axes by tilts about two different horizontal axes). ``σ_c(h),a``: the hold-to-hold
repeatability of axis a in the class of hold h (below).

The noise of a hold mean has two parts (one-way random effects, Searle, Casella & McCulloch,
*Variance Components*, 1992, ch. 3):

* within the hold, ``σ_W,a²`` — the pooled scatter of the samples about their hold's mean,
  ``MS_W = SS_W / (N − H)`` with ``dof_W = N − H``;
* between holds — re-holding the same face reads differently. Two causes, and they do not
  move every hold alike, so each axis a has **two classes** of holds:

  - **vertical** (``c = V``: faces ``±a``, the axis along gravity): the bias repeatability
    (turn-on, wander) only. A placement tilt δ of the case moves this axis by
    ``g·(1 − cos δ) ≈ g·δ²/2``: nothing at 1e-3 rad.
  - **level** (``c = L``: the other faces, the axis horizontal): the bias repeatability plus
    the placement tilt about the horizontal axis across a, which moves it by ``g·δ``:
    ``σ_L² ≈ σ_V² + g²·σ_δ²``.

  ``ε_h,a ~ N(0, σ_c(h),a² + σ_W,a²/n_h)``. One σ_B pooled over all holds (the fit before)
  put the level holds' tilt scatter onto the vertical ones: the scale, read from the faces
  ±a, got intervals 5–8× too wide, the misalignments, read from the level faces, too narrow
  (0.88–0.95 at 95 %), and lack of fit false-alarmed (docs/six-face-twin.md).

Each class is estimated from its own re-held faces (ANOVA estimator, truncated at 0): the
hold means of a face scatter about that face's mean by ``SS_c`` (summed over the class'
faces) on ``dof_c = H_c − F_c``, ``E[SS_c] = dof_c·σ_c² + σ_W²·c_c``,
``c_c = Σ_{f∈c} (1 − 1/H_f) Σ_{h∈f} 1/n_h``, so ``σ̂_c² = max(0, MS_c − MS_W·c_c/dof_c)``. A
class with no re-held face takes the other class' estimate (and its mean square below);
with no face held twice the repeatability is not measured (0 in the weights) and the result
says so.

The fit weighs hold h by ``v_h = σ̂_c(h)² + σ̂_W²/n_h``. Every parameter j gets its own
Satterthwaite dof: with ``G = (XᵀWX)⁻¹XᵀW`` (from the QR/lstsq of the whitened design, no
normal matrix) and, for the derived parameters, the delta-method rows ``L = J·G`` (J the
Jacobian of ``[b, K_aa − 1, K_ab/K_aa, K_ac/K_aa]``; for b and the scale L is a row of G),
``var_j = Σ_h L_jh²·v_h = Σ_c A_jc·σ̂_c² + B_j·σ̂_W²``, ``A_jc = Σ_{h∈c} L_jh²``,
``B_j = Σ_h L_jh²/n_h``. Substituting the ANOVA estimates::

    var_j = Σ_c A_jc·MS_c + (B_j − Σ_c A_jc·c_c/dof_c)·MS_W
    ν_j   = var_j² / (Σ_c (A_jc·MS_c)²/dof_c + ((B_j − Σ_c A_jc·c_c/dof_c)·MS_W)²/dof_W)

(a class truncated at 0 contributes no MS_c term; a borrowing class adds its A to the class
it borrows from). So the scale's Student t takes the dof of the vertical class, the
misalignments the level class', the bias a mix: the derived parameters' dof come from
Satterthwaite on their own (delta-method) variance, not from the K entry they lean on. With
σ_B truly zero an estimate is zero about half the time and otherwise small, so the intervals
do not widen beyond chance.

The weights are estimated, and two classes estimated apart weigh the vertical against the
level holds by a ratio of two noisy mean squares (2–8 dof each): where that ratio came out
low, the holds it favours are the ones whose variance came out low, and ``G·V̂·Gᵀ``
understates the variance (the bias, which combines the pair sums of all three axes: 0.90
coverage at 95 % with a dominant σ_B and faces held three times). The covariance is
therefore Kenward & Roger's (1997) ``Φ + 2Λ``: ``Φ = (XᵀV̂⁻¹X)⁻¹`` and Kackar & Harville's
``Λ = Φ·Σ_ij Cov(θ̂_i, θ̂_j)·X_wᵀE_i M E_j X_w·Φ`` (``θ`` the estimated σ_c², σ_W²,
``E_i = diag(∂v_h/∂θ_i / v_h)``, ``M = I − X_wΦX_wᵀ``, ``Var MS = 2·MS²/dof``). The scale and
the misalignments barely move (in a full six-face design they hardly depend on the weights);
the dof stay those of ``var_j`` above.

Lack of fit (per axis): the weighted residual χ² of the fit splits into the pure error
within faces and the misfit of the face means, ``Q = RSS_w − SS_PE,w =
Σ_f w̃_f (ỹ_f − x_f·p̂)²`` (``ỹ_f`` the weighted face mean, ``w̃_f = Σ_{h∈f} 1/v_h``): each face
in units of its own class' noise. Under the model ``E[Q] = Σ_h C_hh·v_h`` (C the quadratic
form of Q, ``= F − 4`` at the fitted weights), estimated unbiasedly (no truncation) from the
mean squares as above with ν dof: ``F = Q/Ê`` on ``F(F − 4, ν)``. Without re-holds: the
weighted residuals against the within-hold scatter, ``(RSS_W/(H − 4))`` on
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

import textwrap
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
    cov : (12, 12) covariance (block diagonal by axis), hold-to-hold repeatability and the
        estimated weights (Kenward–Roger) included.
    dof : (12,) Satterthwaite dof of each parameter's variance (Student t quantiles): from
        the mean squares of the classes and of the within-hold scatter (module docstring); on
        an axis whose misfit is in its intervals, F − 4 for its four parameters.
    k_matrix : (3, 3) K = (I + S)(I + M), dimensionless (rows: sensor axes; columns: case
        axes).
    residuals : (H, 3) m/s², hold means minus the model.
    hold_std : (H, 3) m/s², the std of each hold mean the fit used,
        ``√(σ̂_c(h)² + σ̂_W²/n_h)`` with c(h) the hold's class for that axis (:func:`hold_classes`).
    faces : tuple of H face names (``"+x"`` …), one per hold.
    n : (H,) samples per hold.
    sigma_within : (3,) σ_W per axis, m/s²; ``sigma_between``: (3, 2) σ_B per axis and class,
        m/s², columns :data:`CLASSES` (axis vertical, axis level); NaN when no face is held
        twice (not measured); a class none of whose faces is re-held holds the other
        class' estimate (:meth:`borrowed`).
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

    def borrowed(self) -> np.ndarray:
        """(3, 2) True for a class (axis, vertical/level) none of whose faces is held twice:
        its σ_B is the other class' estimate (all False when nothing is measured)."""
        return _class_dof(self.faces) == 0 if self.repeatability_measured else np.zeros(
            (3, 2), dtype=bool)

    def hold_dof(self) -> np.ndarray:
        """(H, 3) Satterthwaite dof of each hold's variance ``hold_std²`` (the Student t of a
        bar around one hold mean): ``σ̂_c² + MS_W/n_h`` from the class' mean square and
        ``MS_W``, rebuilt from σ_B, σ_W, the faces and n; F − 4 on an axis whose misfit is
        in its intervals."""
        n = np.asarray(self.n, dtype=float)
        face = _face_codes(self.faces)
        cls = hold_classes(self.faces)
        dof_w = int(np.sum(self.n)) - len(self.faces)
        out = np.empty((len(self.faces), 3))
        for a in range(3):
            if self.misfit_in_intervals[a]:
                out[:, a] = self.dof[4 * a]
                continue
            comps = _rebuild(face, cls[:, a], n, float(self.sigma_within[a]) ** 2, dof_w,
                             self.sigma_between[a])
            out[:, a] = comps.combine(np.eye(len(n)), cls[:, a], n)[1]
        return out

    def quantiles(self, level: float | None = None) -> np.ndarray:
        """(12,) two-sided Student t quantile of each parameter (its own dof)."""
        lv = self.level if level is None else level
        if not 0 < lv < 1:
            raise ValueError(f"level must be in (0, 1), got {lv}")
        return stats.t.ppf(0.5 + lv / 2, self.dof)

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
        lent = self.borrowed()
        sb = ", ".join(f"{a} " + " / ".join(f"{v:.2g}{'*' if b else ''}"
                                             for v, b in zip(row, rows_b, strict=True))
                       for a, row, rows_b in zip(AXES_3, self.sigma_between, lent, strict=True))
        wd = ", ".join(f"{a} ×{v:.2f}" for a, v in zip(AXES_3, self.widening, strict=True))
        note = ("\n  * no face of that class held twice: the other class' σ_B"
                if lent.any() else "")
        misfit = " and the misfit" if any(self.misfit_in_intervals) else ""
        return (f"σ_B (m/s², axis vertical / level): {sb}\n  intervals widened by the "
                f"hold-to-hold repeatability{misfit}: {wd}{note}")

    def misfit_line(self) -> str | None:
        """One paragraph (lines of at most 100 columns) naming the axes whose significant lack
        of fit was put into their intervals, or None."""
        axes = [a for a, m in zip(AXES_3, self.misfit_in_intervals, strict=True) if m]
        if not axes:
            return None
        dof = ", ".join(f"{a} {self.dof[4 * AXES_3.index(a)]:.0f}" for a in axes)
        return textwrap.fill(
            f"lack of fit on {', '.join(axes)}: the face means miss the model beyond the "
            "repeatability (a face not flat, or a missing term), so those axes' estimates and "
            f"intervals come from the face means and their scatter about the model (Student t, "
            f"dof {dof})", width=100, subsequent_indent="  ")

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
                "sigma_between": [[None if not np.isfinite(v) else v for v in row]
                                  for row in self.sigma_between.tolist()],
                "widening": [None if not np.isfinite(v) else v
                             for v in self.widening.tolist()],
                "lack_of_fit_p": [None if not np.isfinite(v) else v
                                  for v in self.lack_of_fit_p.tolist()],
                "g": self.g, "g_source": self.g_source, "level": self.level,
                "misfit_in_intervals": list(self.misfit_in_intervals)}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> SixFaceFit:
        def arr(key: str) -> np.ndarray:
            def num(v: Any) -> Any:
                return [num(x) for x in v] if isinstance(v, list) else (
                    np.nan if v is None else v)
            return np.array(num(d[key]), dtype=float)

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


VERTICAL, LEVEL = 0, 1
CLASSES: tuple[str, str] = ("vertical", "level")
"""The two classes of holds of an axis a (module docstring): ``vertical`` on faces ±a (the
axis along gravity), ``level`` on the other faces (the axis horizontal)."""


def hold_classes(faces: tuple[str, ...]) -> np.ndarray:
    """(H, 3) class of each hold for each axis: :data:`VERTICAL` (0) where the hold's face is
    along that axis (``±a``), :data:`LEVEL` (1) where the axis lies level."""
    k = np.array([AXES_3.index(f[1]) for f in faces])
    return (k[:, None] != np.arange(3)[None, :]).astype(int)


@dataclass(frozen=True)
class _Components:
    """The one-way ANOVA of an axis' re-held faces, per class (module docstring)."""

    ms: np.ndarray  # (2,) MS_c = SS_c / dof_c (NaN with no dof)
    dof: np.ndarray  # (2,) dof_c = H_c − F_c
    c: np.ndarray  # (2,) c_c = Σ_{f∈c} (1 − 1/H_f) Σ_{h∈f} 1/n_h
    source: tuple[int, int]  # the class whose estimate each class uses (−1: none)
    sigma2: np.ndarray  # (2,) σ̂_c² used in the weights (truncated at 0, borrowed; 0: none)
    ms_w: float
    dof_w: int

    @property
    def measured(self) -> bool:
        return self.source[0] >= 0

    def combine(self, q: np.ndarray, cls: np.ndarray, n: np.ndarray,
                truncate: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Var ``Σ_h q_kh·(σ̂_c(h)² + MS_W/n_h)`` (k,) written as a linear combination of the
        mean squares, and its Satterthwaite dof (k,). ``truncate``: a class whose σ̂_c² is
        truncated at 0 contributes no MS_c term (the variances of the intervals); False: the
        unbiased combination, every measured class' MS_c (the lack-of-fit denominator)."""
        q = np.atleast_2d(q)
        a = np.column_stack([q[:, cls == c].sum(axis=1) for c in (VERTICAL, LEVEL)])
        coef = np.zeros_like(a)
        coef_w = (q / n).sum(axis=1)
        for c in (VERTICAL, LEVEL):
            s = self.source[c]
            if s < 0 or (truncate and self.sigma2[s] <= 0.0):
                continue
            coef[:, s] += a[:, c]
            coef_w = coef_w - a[:, c] * self.c[s] / self.dof[s]
        terms = [(coef[:, s] * self.ms[s], self.dof[s]) for s in (VERTICAL, LEVEL)
                 if self.dof[s] > 0]
        terms.append((coef_w * self.ms_w, self.dof_w))
        var = np.sum([t for t, _ in terms], axis=0)
        den = np.sum([t**2 / d for t, d in terms], axis=0)
        with np.errstate(divide="ignore", invalid="ignore"):
            dof = np.where(den > 0, var**2 / den, float(self.dof_w))
        return var, dof

    def theta_cov(self, cls: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The estimated variance parameters θ (every class estimated from its own re-holds
        and not truncated, then σ_W²): ``∂v_h/∂θ_i`` (k, H) and ``Cov θ̂`` (k, k), from
        ``σ̂_c² = MS_c − MS_W·c_c/dof_c`` with ``Var MS = 2·MS²/dof``."""
        est = [s for s in (VERTICAL, LEVEL) if self.dof[s] > 0 and self.sigma2[s] > 0]
        grads = [np.isin(cls, [c for c in (VERTICAL, LEVEL) if self.source[c] == s])
                 .astype(float) for s in est] + [1.0 / n]
        var_w = 2 * self.ms_w**2 / self.dof_w
        kk = np.array([self.c[s] / self.dof[s] for s in est] + [-1.0])
        cov = var_w * np.outer(kk, kk)  # the MS_W part of every estimate
        for i, s in enumerate(est):
            cov[i, i] += 2 * self.ms[s] ** 2 / self.dof[s]
        return np.array(grads), cov


def _class_design(face: np.ndarray, cls: np.ndarray, n: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """Per class of one axis: ``dof_c = H_c − F_c``, ``c_c`` (module docstring) and the class
    whose estimate it uses (itself, the other when it has no re-held face, −1: none)."""
    dof, c = np.zeros(2, dtype=int), np.zeros(2)
    for f in np.unique(face):
        g = np.flatnonzero(face == f)
        dof[cls[g[0]]] += len(g) - 1
        c[cls[g[0]]] += (1 - 1 / len(g)) * float(np.sum(1.0 / n[g]))
    source = tuple(k if dof[k] > 0 else (1 - k if dof[1 - k] > 0 else -1) for k in (0, 1))
    return dof, c, source


def _anova(y: np.ndarray, n: np.ndarray, face: np.ndarray, cls: np.ndarray, ms_w: float,
           dof_w: int) -> _Components:
    """σ̂_c² of each class from the scatter of its re-held faces (module docstring)."""
    dof, c, source = _class_design(face, cls, n)
    ss = np.zeros(2)
    for f in np.unique(face):
        g = np.flatnonzero(face == f)
        ss[cls[g[0]]] += float(np.sum((y[g] - y[g].mean()) ** 2))
    with np.errstate(divide="ignore", invalid="ignore"):
        ms = np.where(dof > 0, ss / dof, np.nan)
        own = np.where(dof > 0, np.maximum(0.0, ms - ms_w * c / dof), np.nan)
    sigma2 = np.array([own[s] if s >= 0 else 0.0 for s in source])
    return _Components(ms, dof, c, source, sigma2, ms_w, dof_w)


def _face_codes(faces: tuple[str, ...]) -> np.ndarray:
    """(H,) one integer per face (``2·axis + (sign == "-")``): the groups of re-holds."""
    return np.array([AXES_3.index(f[1]) * 2 + (f[0] == "-") for f in faces], dtype=int)


def _class_dof(faces: tuple[str, ...]) -> np.ndarray:
    """(3, 2) ANOVA dof ``H_c − F_c`` of each axis' vertical and level class."""
    face, cls = _face_codes(faces), hold_classes(faces)
    ones = np.ones(len(faces))
    return np.array([_class_design(face, cls[:, a], ones)[0] for a in range(3)])


def _rebuild(face: np.ndarray, cls: np.ndarray, n: np.ndarray, ms_w: float, dof_w: int,
             sigma_between: np.ndarray) -> _Components:
    """The :class:`_Components` of an axis from its stored σ_B (2,) and σ_W² (a fit read back):
    ``MS_c = σ̂_c² + MS_W·c_c/dof_c`` for a class not truncated (the one that enters a
    Satterthwaite dof)."""
    dof, c, source = _class_design(face, cls, n)
    sb2 = np.where(np.isfinite(sigma_between), np.asarray(sigma_between, float), 0.0) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        ms = np.where(dof > 0, sb2 + ms_w * c / dof, np.nan)
    return _Components(ms, dof, c, source, sb2, ms_w, dof_w)


@dataclass(frozen=True)
class _AxisFit:
    row: np.ndarray  # (4,) [b, K_x, K_y, K_z]
    cov: np.ndarray  # (4, 4)
    dof: np.ndarray  # (4,) of the derived parameters [b, s, m_ab, m_ac]
    resid: np.ndarray  # (H,)
    hold_std: np.ndarray  # (H,) √v_h
    sigma_w: float
    sigma_b: np.ndarray  # (2,) vertical, level; NaN: not measured
    widening: float
    lof_p: float
    lof_in_intervals: bool = False


def _derived(row: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Axis k's ``d = [b, K_aa − 1, K_ab/K_aa, K_ac/K_aa]`` and ``J = ∂d/∂[b, K_ax, K_ay, K_az]``
    (the delta method)."""
    kaa = row[1 + k]
    others = [j for j in range(3) if j != k]
    jac = np.zeros((4, 4))
    jac[0, 0] = 1.0
    jac[1, 1 + k] = 1.0
    for i, j in enumerate(others):
        jac[2 + i, 1 + j] = 1.0 / kaa
        jac[2 + i, 1 + k] = -row[1 + j] / kaa**2
    return np.array([row[0], kaa - 1.0, *(row[1 + j] / kaa for j in others)]), jac


def _wls(x: np.ndarray, y: np.ndarray, v: np.ndarray
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row estimate, covariance and ``G = (XᵀWX)⁻¹XᵀW`` of ``y = x p + ε``,
    ``Var ε = diag(v)``: the pseudo-inverse ``X_w⁺`` of the whitened design by least squares
    (no normal matrix), ``cov = X_w⁺X_w⁺ᵀ`` and ``G = X_w⁺·diag(w)``, ``w = v^(−1/2)``."""
    w = 1.0 / np.sqrt(v)
    xw = x * w[:, None]
    p, *_ = np.linalg.lstsq(xw, y * w, rcond=None)
    pinv, *_ = np.linalg.lstsq(xw, np.eye(len(v)), rcond=None)
    return p, pinv @ pinv.T, pinv * w[None, :]


def _estimated_weights(pinv: np.ndarray, xw: np.ndarray, v: np.ndarray, cls: np.ndarray,
                       n: np.ndarray, comps: _Components) -> np.ndarray:
    """Λ (4, 4) of Kackar & Harville (1984, JASA 79, 853): what estimating the weights adds
    to the variance of the estimate, ``Λ = Φ·Σ_ij Cov(θ̂_i, θ̂_j)·X_wᵀ E_i M E_j X_w·Φ`` with
    ``E_i = diag(∂v_h/∂θ_i / v_h)``, ``M = I − X_w Φ X_wᵀ``, ``Φ X_wᵀ = X_w⁺``; the covariance
    is ``Φ + 2Λ`` (Kenward & Roger 1997; V is linear in θ)."""
    grads, theta = comps.theta_cov(cls, n)
    e = grads / v[None, :]
    m = np.eye(len(v)) - xw @ pinv
    return pinv @ (m * (e.T @ theta @ e)) @ pinv.T


def _lack_of_fit(x: np.ndarray, y: np.ndarray, v: np.ndarray, groups: list[np.ndarray],
                 comps: _Components, cls: np.ndarray, n: np.ndarray) -> float:
    """p-value of the weighted lack-of-fit test (module docstring), NaN with no dof."""
    h, p = x.shape
    n_faces = len(groups)
    if not comps.measured:
        if h <= p:
            return np.nan
        row, *_ = _wls(x, y, v)
        f = float(np.sum((y - x @ row) ** 2 / v)) / (h - p)
        return float(stats.f.sf(f, h - p, comps.dof_w))
    if n_faces <= p:
        return np.nan
    sw = 1.0 / np.sqrt(v)
    z = np.zeros((h, n_faces))
    for i, g in enumerate(groups):
        z[g, i] = 1.0
    qx, _ = np.linalg.qr(x * sw[:, None])
    qz, _ = np.linalg.qr(z * sw[:, None])
    yw = y * sw
    rx = yw - qx @ (qx.T @ yw)
    rz = yw - qz @ (qz.T @ yw)
    q = float(rx @ rx - rz @ rz)  # RSS_w − SS_PE,w
    diag = sw**2 * (np.sum(qz**2, axis=1) - np.sum(qx**2, axis=1))  # C_hh
    e, nu = comps.combine(diag, cls, n, truncate=False)
    if not e[0] > 0:  # the unbiased estimate came out ≤ 0 (unequal n): the truncated one
        e, nu = comps.combine(diag, cls, n)
    return float(stats.f.sf(max(q, 0.0) / e[0], n_faces - p, nu[0]))


def _fit_axis(x: np.ndarray, y: np.ndarray, n: np.ndarray, ss_w: float, face: np.ndarray,
              cls: np.ndarray, k: int) -> _AxisFit:
    """Axis k: the classes' ANOVA, the weighted fit, per-parameter Satterthwaite dof of the
    derived parameters, the lack-of-fit test (module docstring)."""
    h, p = x.shape
    dof_w = int(n.sum()) - h
    ms_w = ss_w / dof_w
    groups = [np.flatnonzero(face == f) for f in np.unique(face)]
    comps = _anova(y, n, face, cls, ms_w, dof_w)
    v = comps.sigma2[cls] + ms_w / n
    row, cov, gmat = _wls(x, y, v)
    resid = y - x @ row
    _, jac = _derived(row, k)
    _, dof = comps.combine((jac @ gmat) ** 2, cls, n)
    if comps.measured:  # the weights are estimated: Kenward–Roger's Φ + 2Λ
        sw = 1.0 / np.sqrt(v)
        cov = cov + 2 * _estimated_weights(gmat / sw[None, :], x * sw[:, None], v, cls, n,
                                           comps)
        _, cov_w, _ = _wls(x, y, ms_w / n)
        q = stats.t.ppf(0.975, dof[0]) / stats.t.ppf(0.975, dof_w)
        widening = float(q * np.sqrt(cov[0, 0] / cov_w[0, 0]))
        sigma_b = np.sqrt(comps.sigma2)
    else:
        widening, sigma_b = np.nan, np.full(2, np.nan)
    lof_p = _lack_of_fit(x, y, v, groups, comps, cls, n)
    if np.isfinite(lof_p) and lof_p < LOF_ALPHA:
        return _misfit_axis(x, y, n, ms_w, face, groups, v, sigma_b, lof_p, dof_w)
    return _AxisFit(row, cov, dof, resid, np.sqrt(v), float(np.sqrt(ms_w)), sigma_b,
                    widening, lof_p)


def _misfit_axis(x: np.ndarray, y: np.ndarray, n: np.ndarray, ms_w: float, face: np.ndarray,
                 groups: list[np.ndarray], v: np.ndarray, sigma_b: np.ndarray, lof_p: float,
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
    _, cov_w, _ = _wls(x, y, ms_w / n)
    widening = float(stats.t.ppf(0.975, dof) / stats.t.ppf(0.975, dof_w)
                     * np.sqrt(cov[0, 0] / cov_w[0, 0]))
    # each hold's std as drawn: at least the face-level scatter s² (shared by its re-holds)
    hold_std = np.sqrt(np.maximum(v, s2))
    return _AxisFit(row, cov, np.full(p, dof), y - x @ row, hold_std, float(np.sqrt(ms_w)),
                    sigma_b, widening, lof_p, lof_in_intervals=True)


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
    face = _face_codes(names_h)
    cls = hold_classes(names_h)
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
    fits = [_fit_axis(x, means[:, k], n, float(ss_w[k]), face, cls[:, k], k)
            for k in range(3)]
    k_matrix = np.array([f.row[1:] for f in fits])
    params, blocks, names = [], [], []
    for k, (a, f) in enumerate(zip(AXES_3, fits, strict=True)):
        others = [j for j in range(3) if j != k]
        d, jac = _derived(f.row, k)  # [b, K_aa − 1, K_ab/K_aa, K_ac/K_aa], the delta method
        params += d.tolist()
        blocks.append(jac @ f.cov @ jac.T)
        names += [f"bias_{a}", f"scale_{a}", *(f"misalignment_{a}{AXES_3[j]}" for j in others)]
    return SixFaceFit(
        param_names=tuple(names), params=np.array(params), cov=linalg.block_diag(*blocks),
        dof=np.concatenate([f.dof for f in fits]), k_matrix=k_matrix,
        residuals=np.column_stack([f.resid for f in fits]),
        hold_std=np.column_stack([f.hold_std for f in fits]), faces=names_h, n=n,
        sigma_within=np.array([f.sigma_w for f in fits]),
        sigma_between=np.array([f.sigma_b for f in fits]),
        widening=np.array([f.widening for f in fits]),
        lack_of_fit_p=np.array([f.lof_p for f in fits]), g=float(g), g_source=g_source,
        level=level, source=source,
        misfit_in_intervals=tuple(f.lof_in_intervals for f in fits))


__all__ = ["AXES_3", "CLASSES", "FACE_COS", "LEVEL", "LOF_ALPHA", "VERTICAL", "SixFaceFit",
           "face_name", "face_vectors", "faces_of", "fit_six_face", "hold_classes", "on_faces"]
