"""Least-squares calibration of the tilt-table accelerometers.

Model (course; IEEE Std 1293 K0 = bias, K1 = 1 + scale), per axis a ∈ {x, y}::

    A_m,a[i] = bias_a + (1 + scale_a) · A_r,a(θ_i) + v_a[i],     v_a ~ N(0, σ_a²) white

with ``A_rx = -g sin θ``, ``A_ry = -g cos θ``. Subtracting the reference gives the linear
model solved here, ``y = A_m - A_r = H p + v`` with ``H = [1, A_r]`` and ``p = [bias, scale]``.

Numerics: never ``inv(HᵀH)``. The regressors are centred on the intercept (an exact
reparametrisation ``p = M p_c``), the columns equilibrated, and the problem solved by one
Householder QR (LAPACK ``dgeqrf``) of the augmented design ``[H_c | y]``, which gives the
solution ``R p_c = Qᵀy`` and the covariance ``σ² · R⁻¹R⁻ᵀ`` (whitened, centred design), mapped
back with ``M``. Rank and conditioning are checked: a
parameter the design cannot identify raises :class:`NotIdentifiableError` naming it; a poorly
identified one warns with the condition number and the resulting standard deviation.
"""

from __future__ import annotations

import warnings
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from scipy import linalg as sla
from scipy.linalg import blas

from calib import distributions as stats
from calib.conventions import AXES, JOINT_PARAM_NAMES, PARAM_NAMES, G, reference_accel
from calib.numerics import design_cond, r_factor
from calib.results import ResultMixin

Sigma2Source = Literal["given", "estimated"]

POOR_SPAN_FRACTION = 1e-3
"""An axis whose reference acceleration spans less than ``g · 1e-3`` (θ spanning < 1e-3 rad
where that axis is most sensitive) identifies its scale only poorly: warn."""

COND_WARN = 1e8
"""Condition number (column-equilibrated design) above which a fit warns."""


class NotIdentifiableError(ValueError):
    """The design matrix is rank-deficient: some parameter cannot be estimated."""


class PoorlyIdentifiedWarning(UserWarning):
    """The design identifies a parameter only poorly (large condition number or std)."""


def _readonly(a) -> np.ndarray:
    """A read-only float array of ``a``: a copy, unless ``a`` already is one (nobody can
    change it then; the fast refit hands over its fresh residuals that way)."""
    if isinstance(a, np.ndarray) and a.dtype == float and not a.flags.writeable:
        return a
    arr = np.array(a, dtype=float)
    arr.setflags(write=False)
    return arr


def chi2_from_dof(chi2_dof: float, dof: int) -> float:
    """The χ² whose ``χ²/dof`` is exactly ``chi2_dof`` (rebuilding from a printed χ²/dof).

    ``chi2_dof · dof`` divided by ``dof`` may miss ``chi2_dof`` by one unit in the last place;
    the neighbours of the product are tried so that the rebuilt ``chi2_dof`` prints the same.
    """
    c = float(chi2_dof) * dof
    if dof <= 0 or not np.isfinite(c):
        return c
    lo = hi = c
    for _ in range(4):
        for v in (lo, hi):
            if v / dof == chi2_dof:
                return float(v)
        lo, hi = float(np.nextafter(lo, -np.inf)), float(np.nextafter(hi, np.inf))
    return c


@dataclass(frozen=True, eq=False)
class FitResult(ResultMixin):
    """Result of a linear least-squares fit (statsmodels-like, frozen, holds no data).

    Attributes
    ----------
    param_names : names of the parameters, e.g. ``("bias", "scale")``; bias in m/s²,
        scale dimensionless.
    params : (p,) estimates.
    cov : (p, p) covariance of the estimates, ``σ² (HᵀWH)⁻¹`` computed from the QR factor.
    residuals : (n,) or (n, 2) data - model, m/s².
    sigma2 : noise variance used (per axis for joint fits), (m/s²)².
    sigma2_source : "given" (normal quantiles) or "estimated" from residuals (t quantiles).
    dof : n_obs - p.  rank : rank of the design.  cond : condition number of the
        column-equilibrated design.  chi2 : Σ whitened residual² with the given/used σ².
    """

    param_names: tuple[str, ...]
    params: np.ndarray
    cov: np.ndarray
    residuals: np.ndarray
    sigma2: np.ndarray
    sigma2_source: Sigma2Source
    dof: int
    rank: int
    cond: float
    chi2: float
    extra: dict = field(default_factory=dict, compare=False)

    _TITLE = "Least-squares fit"
    _UNITS = ("bias m/s²; scale dimensionless (other parameters: the units of their effect in "
              "calib.conventions.EFFECTS); std and confidence limits in the units of their "
              "parameter; σ² (m/s²)²; χ²/dof dimensionless")

    def __post_init__(self) -> None:
        for name in ("params", "cov", "residuals", "sigma2"):
            object.__setattr__(self, name, _readonly(getattr(self, name)))

    @property
    def std(self) -> np.ndarray:
        """Standard deviations of the estimates, sqrt(diag(cov))."""
        return np.sqrt(np.diag(self.cov))

    @property
    def chi2_dof(self) -> float:
        """χ²/dof of the residuals with the noise variance used (≈ 1 if the model fits)."""
        return self.chi2 / self.dof if self.dof > 0 else float("nan")

    def quantile(self, level: float) -> float:
        """Two-sided quantile: normal when σ² is given, Student t when estimated, with the
        dof of the σ² estimate: ``extra["sigma2_dof"]`` when σ² came from elsewhere than
        this fit's residuals (the pure error within poses, :mod:`calib.calibration.lackoffit`), else
        ``dof``."""
        if not 0 < level < 1:
            raise ValueError(f"level must be in (0, 1), got {level}")
        q = 0.5 + level / 2
        return float(stats.norm.ppf(q) if self.sigma2_source == "given"
                     else stats.t.ppf(q, int(self.extra.get("sigma2_dof", self.dof))))

    def conf_int(self, level: float = 0.95) -> np.ndarray:
        """(p, 2) two-sided confidence intervals at ``level`` for each parameter."""
        half = self.quantile(level) * self.std
        return np.column_stack([self.params - half, self.params + half])

    def param(self, name: str) -> float:
        return float(self.params[self.param_names.index(name)])

    def summary(self, level: float = 0.95) -> str:
        ci = self.conf_int(level)
        pct = f"{100 * level:g}%"
        lines = [f"{'param':<10}{'estimate':>14}{'std':>13}{'[' + pct:>14}{pct + ']':>14}"]
        for i, name in enumerate(self.param_names):
            lines.append(f"{name:<10}{self.params[i]:>14.6g}{self.std[i]:>13.4g}"
                         f"{ci[i, 0]:>14.6g}{ci[i, 1]:>14.6g}")
        s2 = np.atleast_1d(self.sigma2)
        lines.append(f"σ² = {', '.join(f'{v:.4g}' for v in s2)} ({self.sigma2_source}); "
                     f"χ²/dof = {self.chi2_dof:.4f}; dof = {self.dof}; cond = {self.cond:.3g}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {
            "param_names": list(self.param_names),
            "params": self.params.tolist(),
            "std": self.std.tolist(),
            "cov": self.cov.tolist(),
            "sigma2": self.sigma2.tolist(),
            "sigma2_source": self.sigma2_source,
            "chi2_dof": self.chi2_dof,
            "dof": self.dof,
            "cond": self.cond,
            "rank": self.rank,
            "chi2": self.chi2,
            "residuals": self.residuals.tolist(),
            "extra": self.extra,
        }

    @classmethod
    def from_dict(cls, d: dict) -> FitResult:
        """Rebuild from :meth:`to_dict` (exact: ``FitResult.from_dict(f.to_dict()) == f``).

        Parameters
        ----------
        d : the mapping of :meth:`to_dict`, possibly through JSON. Without ``residuals``,
            ``rank`` and ``chi2`` (a marginal block printed by a command) the residuals are
            empty, the rank is full and χ² comes from ``chi2_dof · dof``.

        Examples
        --------
        >>> import numpy as np
        >>> from calib.calibration.ls import FitResult, fit_axis
        >>> th = np.linspace(0, 2 * np.pi, 50)
        >>> f = fit_axis(th, -9.8 * np.sin(th) + 0.1, "x", sigma2=0.25)
        >>> FitResult.from_dict(f.to_dict()) == f
        True
        """
        params = np.asarray(d["params"], dtype=float)
        dof = int(d["dof"])
        return cls(
            param_names=tuple(d["param_names"]), params=params, cov=d["cov"],
            residuals=d.get("residuals", np.zeros(0)), sigma2=d["sigma2"],
            sigma2_source=d["sigma2_source"], dof=dof, rank=int(d.get("rank", params.size)),
            cond=float(d["cond"]),
            chi2=float(d["chi2"]) if "chi2" in d else chi2_from_dof(d["chi2_dof"], dof),
            extra=dict(d.get("extra", {})),
        )


def _equilibrate(Hc: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(norms, scale, Hs)``: column norms of ``Hc``, the divisors (1 for a zero column) and
    the equilibrated ``Hs = Hc / scale`` (unit-norm columns)."""
    norms = np.linalg.norm(Hc, axis=0)
    scale = np.where(norms > 0, norms, 1.0)
    return norms, scale, Hc / scale


def _solve_centred(
    Hc: np.ndarray, y: np.ndarray, M: np.ndarray, names: tuple[str, ...],
    equilibrated: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Solve ``y ≈ Hc p_c`` (rows already whitened), return ``p = M p_c``, unit covariance.

    One Householder QR of the equilibrated, augmented design ``[Hs | y] = Q [[R, z], [0, ρ]]``
    gives the solution ``R p = z`` and the unit covariance ``M R⁻¹R⁻ᵀ Mᵀ`` (σ² = 1), never
    ``HᵀH`` or its inverse. The rank is that of ``R`` with ``numpy.linalg.lstsq``'s default
    cut-off (singular values below ``eps·max(n, p)·s_max``).
    """
    n, p = Hc.shape
    norms, scale, Hs = _equilibrate(Hc) if equilibrated is None else equilibrated
    aug = np.empty((n, p + 1), order="F")
    aug[:, :p], aug[:, p] = Hs, y
    Ra = r_factor(aug)
    R, z = Ra[:p, :p], Ra[:p, p]
    sv = np.linalg.svd(R, compute_uv=False)
    rank = int(np.sum(sv > sv[0] * max(n, p) * np.finfo(float).eps)) if sv[0] > 0 else 0
    if rank < p or np.any(norms == 0):
        _raise_rank(Hs, names, M)
    pc_s = sla.solve_triangular(R, z)
    Ri = sla.solve_triangular(R, np.eye(p))
    cov_cs = Ri @ Ri.T
    Mi = M / scale  # p = M diag(1/scale) p_cs
    params = Mi @ pc_s
    cov = Mi @ cov_cs @ Mi.T
    resid = y - Hs @ pc_s
    return params, 0.5 * (cov + cov.T), resid, rank


def _raise_rank(Hs: np.ndarray, names: tuple[str, ...], M: np.ndarray) -> None:
    _, s, vt = np.linalg.svd(Hs, full_matrices=False)
    null = vt[-1]
    # Parameters taking part in the null direction (mapped back through M) are the
    # ones the design cannot tell apart.
    involved = [names[i] for i in np.flatnonzero(np.abs(M @ null) > 1e-6)] or list(names)
    raise NotIdentifiableError(
        "design matrix is rank-deficient: cannot identify "
        + " / ".join(involved)
        + " (they are confounded in this experiment; the design needs more distinct θ)"
    )


def centre_design(
    H: np.ndarray, names: tuple[str, ...], intercept: int | None = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Centre the regressors on the intercept: ``H = Hc M⁻¹``, i.e. ``p = M p_c``.

    Column ``intercept`` (all ones) stays; every other column ``j`` becomes
    ``H[:, j] - mean_j`` and ``M[intercept, j] = -mean_j`` (``p_intercept = p_c,intercept -
    Σ mean_j p_j``), an exact reparametrisation that keeps the digits of a regressor with a
    large constant offset (``A_ry ≈ -g`` for small θ).

    Raises
    ------
    ValueError : column ``intercept`` is not all ones.
    NotIdentifiableError : a regressor is constant over the run (collinear with the intercept).
    """
    H = np.asarray(H, dtype=float, order="F")
    p = H.shape[1]
    M = np.eye(p)
    Hc = H.copy(order="F")
    if intercept is not None:
        if not np.all(H[:, intercept] == 1.0):
            raise ValueError(f"column {intercept} is not an intercept (all ones)")
        means = H.mean(axis=0)
        for j in range(p):
            if j != intercept:
                Hc[:, j] = H[:, j] - means[j]
                M[intercept, j] = -means[j]  # p_intercept = p_c,intercept - Σ mean_j p_j
    # A regressor that is constant over the run is exactly collinear with the intercept.
    for j in range(p):
        if intercept is not None and j != intercept and np.ptp(H[:, j]) == 0.0:
            raise NotIdentifiableError(
                f"cannot identify '{names[j]}': its regressor is constant over the run, so it "
                f"is confounded with '{names[intercept]}' (all θ equal?); use at least two "
                "distinct θ"
            )
    return Hc, M


@dataclass(frozen=True, eq=False)
class DesignFactor:
    """The part of an OLS fit that depends on the design only (for many ``y`` at once).

    With the centred (:func:`centre_design`), column-equilibrated design
    ``Hs = Hc D⁻¹ = Q R`` (reduced Householder QR, ``Q`` (n, p) orthonormal columns):

    * solution ``p̂ = A Qᵀy`` with ``A = M D⁻¹ R⁻¹`` (``solve_map``),
    * unit covariance ``cov1 = A Aᵀ`` (multiply by σ²), never ``(HᵀH)⁻¹``,
    * residual sum of squares ``RSS = ‖y‖² − ‖Qᵀy‖²`` (Pythagoras: ``y − Q Qᵀy ⊥ Q``).

    These are the equations of :func:`fit_linear` (same centring, scaling and rank rule);
    there the QR is of the augmented ``[Hs | y]``, so the two agree to rounding (≈ 1e-15
    relative), not bit for bit.
    """

    q: np.ndarray
    solve_map: np.ndarray
    cov1: np.ndarray
    rank: int
    cond: float

    def __post_init__(self) -> None:
        for name in ("q", "solve_map", "cov1"):
            object.__setattr__(self, name, _readonly(getattr(self, name)))


def factor_design(
    H: np.ndarray, names: tuple[str, ...], intercept: int | None = 0
) -> DesignFactor:
    """Factor the design ``H`` (n, p) once (:class:`DesignFactor`); the rank and
    identifiability checks of :func:`fit_linear` apply (``NotIdentifiableError``)."""
    H = np.asarray(H, dtype=float, order="F")
    n, p = H.shape
    if n <= p:
        raise NotIdentifiableError(
            f"{n} samples cannot identify {p} parameters ({', '.join(names)})")
    Hc, M = centre_design(H, names, intercept)
    norms, scale, Hs = _equilibrate(Hc)
    Q, R = np.linalg.qr(Hs)
    sv = np.linalg.svd(R, compute_uv=False)
    rank = int(np.sum(sv > sv[0] * max(n, p) * np.finfo(float).eps)) if sv[0] > 0 else 0
    if rank < p or np.any(norms == 0):
        _raise_rank(Hs, names, M)
    A = (M / scale) @ sla.solve_triangular(R, np.eye(p))
    cov1 = A @ A.T
    return DesignFactor(q=Q, solve_map=A, cov1=0.5 * (cov1 + cov1.T), rank=rank,
                        cond=design_cond(H))


def axis_factor(tita: np.ndarray, axis: str = "x", g: float = G
                ) -> tuple[np.ndarray, DesignFactor]:
    """``(A_r, factor)`` of the per-axis course design ``H = [1, A_r]`` (:func:`fit_axis`).

    ``A_r`` (N,) m/s² is ``-g sin θ`` (x) or ``-g cos θ`` (y). Raises
    :class:`NotIdentifiableError` as :func:`fit_axis` does when every θ gives the same A_r.
    """
    tita = np.asarray(tita, dtype=float)
    a_r = reference_accel(tita, g)[:, AXES.index(axis)]
    try:
        if _blind(a_r, g):
            raise NotIdentifiableError(f"A_r{axis} constant to rounding")
        fac = factor_design(np.column_stack([np.ones_like(a_r), a_r]), PARAM_NAMES)
    except NotIdentifiableError as exc:
        raise NotIdentifiableError(
            f"axis {axis}: cannot identify scale_{axis} (bias_{axis} and scale_{axis} are "
            f"confounded): every θ gives the same A_r{axis}; use at least two θ with "
            f"different A_r{axis}. [{exc}]") from None
    return a_r, fac


def fit_linear(
    H: np.ndarray,
    y: np.ndarray,
    names: tuple[str, ...],
    sigma2: float | None = None,
    intercept: int | None = 0,
) -> FitResult:
    """Ordinary least squares ``y = H p + v``, ``v ~ N(0, σ² I)``.

    Parameters
    ----------
    H : (n, p) design; column ``intercept`` (if not None) must be all ones.
    y : (n,) observations.
    names : parameter names, one per column.
    sigma2 : known noise variance; ``None`` estimates it as RSS/(n - p).
    intercept : index of the constant column. The other columns are centred on it (an exact
        reparametrisation) so that a design with a large constant offset in a regressor
        (e.g. ``A_ry ≈ -g`` for small θ) loses no digits.

    Raises
    ------
    NotIdentifiableError : the design is rank-deficient (message names the parameters).
    """
    H = np.asarray(H, dtype=float, order="F")  # column-major: column reductions and LAPACK
    y = np.asarray(y, dtype=float)
    n, p = H.shape
    if y.shape != (n,):
        raise ValueError(f"y must have shape ({n},), got {y.shape}")
    if n <= p:
        raise NotIdentifiableError(
            f"{n} samples cannot identify {p} parameters ({', '.join(names)})")
    Hc, M = centre_design(H, names, intercept)
    return _fit_centred(Hc, M, y, names, sigma2, lambda: design_cond(H))


def _chi2(rss: float, s2: float, dof: int, source: Sigma2Source) -> float:
    """``RSS/σ²``; with σ² estimated as ``RSS/dof`` it is ``dof`` by construction, also on
    noiseless data (RSS = 0 exactly, where the ratio would divide by zero)."""
    return float(dof) if source == "estimated" else rss / s2


def _sigma2_used(rss: float, dof: int, sigma2: float | None) -> tuple[float, Sigma2Source]:
    """The noise variance a fit uses, (m/s²)²: the given one, else ``RSS/dof``."""
    if sigma2 is None:
        return rss / dof, "estimated"
    s2 = float(sigma2)
    if not np.isfinite(s2) or s2 <= 0:
        raise ValueError(f"noise variance must be positive and finite, got {sigma2}")
    return s2, "given"


def _fit_centred(Hc: np.ndarray, M: np.ndarray, y: np.ndarray, names: tuple[str, ...],
                 sigma2: float | None, cond, equilibrated=None) -> FitResult:
    """The data-dependent half of :func:`fit_linear` (``Hc``, ``M`` from
    :func:`centre_design`; ``cond()`` gives the design's condition number; ``equilibrated``
    :func:`_equilibrate` of ``Hc`` if already known)."""
    n, p = Hc.shape
    params, cov1, resid, rank = _solve_centred(Hc, y, M, names, equilibrated)
    rss = float(resid @ resid)
    dof = n - p
    s2, source = _sigma2_used(rss, dof, sigma2)
    return FitResult(
        param_names=tuple(names), params=params, cov=s2 * cov1, residuals=resid,
        sigma2=np.array(s2), sigma2_source=source, dof=dof, rank=rank,
        cond=cond(), chi2=_chi2(rss, s2, dof, source),
    )


@dataclass(frozen=True, eq=False)
class _AxisDesign:
    """Everything :func:`fit_axis` computes from θ alone: the reference ``A_r``, the design's
    :class:`DesignFactor` (``Q`` stored transposed, the solution map, the unit covariance, the
    condition number) and the span of ``A_r``. Cached, so a refit of the same design does only
    the data-dependent work (:func:`_refit`)."""

    tita: np.ndarray
    a_r: np.ndarray
    qt: np.ndarray
    factor: DesignFactor
    span: float


DESIGN_CACHE_SIZE = 8
"""Designs (θ, g, axis) kept by :func:`fit_axis`: ≈ 1 MB each at N = 20001."""
_DESIGN_CACHE: OrderedDict = OrderedDict()


def _axis_design(tita: np.ndarray, axis: str, g: float) -> _AxisDesign:
    """The cached :class:`_AxisDesign` of ``(θ, axis, g)``; the key is a cheap fingerprint
    of θ (size, three samples) and a hit is confirmed by comparing θ itself (exact: no
    collision can return another design). Raises :class:`NotIdentifiableError` (unwrapped;
    :func:`fit_axis` words it)."""
    n = tita.shape[0] if tita.ndim == 1 else -1
    probe = (float(tita[0]), float(tita[n // 2]), float(tita[-1])) if n > 0 else ()
    key = (tita.shape, probe, float(g), axis)
    hit = _DESIGN_CACHE.get(key)
    if hit is not None and np.array_equal(hit.tita, tita):
        _DESIGN_CACHE.move_to_end(key)
        return hit
    a_r = reference_accel(tita, g)[:, AXES.index(axis)]
    H = np.column_stack([np.ones_like(a_r), a_r])
    if _blind(a_r, g):
        raise NotIdentifiableError(f"A_r{axis} constant to rounding")
    H = np.asarray(H, dtype=float, order="F")
    n, p = H.shape
    if n <= p:
        raise NotIdentifiableError(
            f"{n} samples cannot identify {p} parameters ({', '.join(PARAM_NAMES)})")
    fac = factor_design(H, PARAM_NAMES)
    d = _AxisDesign(_readonly(tita), a_r, np.ascontiguousarray(fac.q.T), fac,
                    float(np.ptp(a_r)))
    _DESIGN_CACHE[key] = d
    while len(_DESIGN_CACHE) > DESIGN_CACHE_SIZE:
        _DESIGN_CACHE.popitem(last=False)
    return d


def _refit(d: _AxisDesign, y: np.ndarray, sigma2: float | None) -> FitResult:
    """The per-axis OLS of ``y = A_m - A_r`` (N,) on the factored design ``d``.

    The equations of :class:`DesignFactor`: ``z = Qᵀy``, ``p̂ = A z``, residuals
    ``r = y - Q z`` (the projection's complement, computed, not ``‖y‖² - ‖z‖²``, so small
    residuals keep their digits), ``RSS = rᵀr``, covariance ``σ² A Aᵀ``; the same solution as
    :func:`fit_linear` to rounding (≈ 1e-15 relative). ``y`` must be a fresh array: it
    becomes the residuals. Cost: two passes over the data per axis (BLAS level 1–2).
    """
    fac = d.factor
    n, p = y.shape[0], fac.solve_map.shape[0]
    z = d.qt @ y
    # y ← y - Q z in place (BLAS dgemv on Qᵀ's Fortran view, no temporary): the residuals
    y = blas.dgemv(-1.0, d.qt.T, z, beta=1.0, y=y, overwrite_y=True)
    y.setflags(write=False)
    rss = float(y @ y)
    dof = n - p
    s2, source = _sigma2_used(rss, dof, sigma2)
    return FitResult(
        param_names=PARAM_NAMES, params=fac.solve_map @ z, cov=s2 * fac.cov1, residuals=y,
        sigma2=np.array(s2), sigma2_source=source, dof=dof, rank=fac.rank, cond=fac.cond,
        chi2=_chi2(rss, s2, dof, source),
    )


def _blind(a_r: np.ndarray, g: float) -> bool:
    """True when the reference is constant to rounding (e.g. sin 0 and sin π): no spread
    at all relative to g, so the scale is not identifiable, not merely poorly identified."""
    return float(np.ptp(a_r)) <= 1e-12 * abs(g)


def _check_poor(a_r: np.ndarray, g: float, axis: str, fit: FitResult,
                span: float | None = None) -> None:
    span = float(np.ptp(a_r)) if span is None else span
    if span < POOR_SPAN_FRACTION * g or fit.cond > COND_WARN:
        warnings.warn(
            f"axis {axis}: the reference acceleration spans only {span:.3g} m/s² over the run "
            f"(θ range too small); scale_{axis} is poorly identified: condition number "
            f"{fit.cond:.3g}, std(scale_{axis}) = {fit.std[1]:.3g}, std(bias_{axis}) = "
            f"{fit.std[0]:.3g}. Spread θ over a wider range (a full turn is best).",
            PoorlyIdentifiedWarning, stacklevel=3,
        )


def fit_axis(
    tita: np.ndarray, a_m: np.ndarray, axis: str = "x", sigma2: float | None = None,
    g: float = G,
) -> FitResult:
    """Per-axis OLS of the course model ``A_m - A_r = bias + scale · A_r + v``.

    Parameters
    ----------
    tita : (N,) table angles, rad (any finite value; ≥ 2 distinct ``A_r`` needed).
    a_m : (N,) measured acceleration of ``axis``, m/s².
    axis : 'x' (``A_r = -g sin θ``) or 'y' (``A_r = -g cos θ``).
    sigma2 : known noise variance, (m/s²)² — the course method (normal quantiles); ``None``
        estimates it as RSS/(N - 2) (Student t quantiles).
    g : gravity, m/s².

    Returns
    -------
    FitResult with ``param_names = ("bias", "scale")`` (bias m/s², scale dimensionless);
    ``cov`` (2, 2) in that order; ``residuals`` (N,) m/s².

    Raises
    ------
    NotIdentifiableError : every θ gives the same ``A_r`` (bias and scale confounded).

    Examples
    --------
    >>> import numpy as np
    >>> from calib import fit_axis
    >>> th = np.linspace(0.0, 2 * np.pi, 100, endpoint=False)
    >>> f = fit_axis(th, 1.02 * -9.8 * np.sin(th) + 0.1, "x", sigma2=0.25)
    >>> np.round(f.params, 9).tolist()        # [bias m/s², scale]
    [0.1, 0.02]
    """
    tita = np.asarray(tita, dtype=float)
    try:
        d = _axis_design(tita, axis, g)
        a_r = d.a_r
        y = np.asarray(a_m, dtype=float) - a_r
        if y.shape != a_r.shape:
            raise ValueError(f"y must have shape {a_r.shape}, got {y.shape}")
        fit = _refit(d, y, sigma2)
    except NotIdentifiableError as exc:
        raise NotIdentifiableError(
            f"axis {axis}: cannot identify scale_{axis} (bias_{axis} and scale_{axis} are "
            f"confounded): every θ gives the same A_r{axis} "
            f"({'-g sin θ' if axis == 'x' else '-g cos θ'}); use at least two θ with "
            f"different A_r{axis}. [{exc}]"
        ) from None
    _check_poor(a_r, g, axis, fit, d.span)
    return fit


def _noise_cov(noise_var) -> np.ndarray:
    c = np.asarray(noise_var, dtype=float)
    c = np.diag(c) if c.shape == (2,) else c
    if c.shape != (2, 2) or not np.allclose(c, c.T):
        raise ValueError("noise covariance must be two variances or a symmetric 2×2 matrix")
    if np.any(np.linalg.eigvalsh(c) <= 0):
        raise ValueError(f"noise covariance must be positive definite, got {c.tolist()}")
    return c


def fit_joint(
    tita: np.ndarray, datos: np.ndarray, noise_var=None, g: float = G
) -> FitResult:
    """Joint four-parameter WLS (second course report): both axes in one weighted problem.

    ``y = [A_mx - A_rx; A_my - A_ry]``, ``p = [bias_x, scale_x, bias_y, scale_y]``, weights
    ``W = C⁻¹ ⊗ I_N`` with ``C`` the 2×2 noise covariance (diagonal in the course:
    diag(0.25, 0.64)). Solved by whitening each sample with the Cholesky factor of ``C``
    (``C = L Lᵀ``, rows ``L⁻¹[...]``) and a QR least squares — never ``(AᵀGA)⁻¹``. With a
    diagonal ``C`` this equals the two per-axis fits; a correlated ``C`` couples them.

    ``noise_var=None``: two-stage feasible WLS, per-axis σ² estimated from per-axis OLS
    residuals (``sigma2_source = "estimated"``).

    Parameters
    ----------
    tita : (N,) table angles, rad.
    datos : (N, 2) measured ``[A_mx, A_my]``, m/s².
    noise_var : (2,) variances ``[σx², σy²]`` or a (2, 2) covariance, (m/s²)²; None
        estimates them.
    g : gravity, m/s².

    Returns
    -------
    FitResult with ``param_names = ("bias_x", "scale_x", "bias_y", "scale_y")``, ``cov``
    (4, 4), ``residuals`` (N, 2) m/s², ``sigma2`` (2,); ``extra["noise_cov"]`` the 2×2 C.

    Examples
    --------
    >>> import numpy as np
    >>> from calib import fit_joint
    >>> th = np.linspace(0.0, 2 * np.pi, 100, endpoint=False)
    >>> datos = np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)]) + [0.1, -0.2]
    >>> f = fit_joint(th, datos, [0.25, 0.64])
    >>> (np.round(f.params, 9) + 0.0).tolist()  # [bias_x, scale_x, bias_y, scale_y]
    [0.1, 0.0, -0.2, 0.0]
    """
    tita = np.asarray(tita, dtype=float)
    datos = np.asarray(datos, dtype=float)
    a_r = reference_accel(tita, g)
    n = tita.shape[0]
    source: Sigma2Source = "given"
    if noise_var is None:
        source = "estimated"
        noise_var = [fit_axis(tita, datos[:, k], ax, None, g).sigma2.item()
                     for k, ax in enumerate(AXES)]
        for ax, v in zip(AXES, noise_var, strict=True):
            if not v > 0:  # exact data: no weight can be estimated (a zero variance)
                raise NotIdentifiableError(
                    f"axis {ax}: the residuals are exactly zero (noiseless data), so the "
                    "noise variance of the joint WLS weights cannot be estimated; state the "
                    "noise variances or fit per axis (OLS)")
    C = _noise_cov(noise_var)
    Li = sla.solve_triangular(np.linalg.cholesky(C), np.eye(2), lower=True)
    means = a_r.mean(axis=0)
    # Centred design per sample: rows x and y, columns [bx', sx, by', sy].
    Hx = np.zeros((n, 4))
    Hy = np.zeros((n, 4))
    Hx[:, 0], Hx[:, 1] = 1.0, a_r[:, 0] - means[0]
    Hy[:, 2], Hy[:, 3] = 1.0, a_r[:, 1] - means[1]
    blind = [ax for k, ax in enumerate(AXES) if _blind(a_r[:, k], g)]
    if blind:
        raise NotIdentifiableError("; ".join(
            f"axis {ax}: cannot identify scale_{ax} (confounded with bias_{ax}): every θ gives "
            f"the same A_r{ax}" for ax in blind) + "; use at least two θ with different A_r")
    Hw = np.concatenate([Li[0, 0] * Hx + Li[0, 1] * Hy, Li[1, 0] * Hx + Li[1, 1] * Hy])
    r = datos - a_r
    yw = np.concatenate([Li[0, 0] * r[:, 0] + Li[0, 1] * r[:, 1],
                         Li[1, 0] * r[:, 0] + Li[1, 1] * r[:, 1]])
    M = np.eye(4)
    M[0, 1], M[2, 3] = -means[0], -means[1]
    params, cov, _, rank = _solve_centred(Hw, yw, M, JOINT_PARAM_NAMES)
    resid = r - np.column_stack([params[0] + params[1] * a_r[:, 0],
                                 params[2] + params[3] * a_r[:, 1]])
    white = resid @ Li.T
    H_full = np.zeros((2 * n, 4))
    H_full[:n, 0], H_full[:n, 1], H_full[n:, 2], H_full[n:, 3] = 1, a_r[:, 0], 1, a_r[:, 1]
    fit = FitResult(
        param_names=JOINT_PARAM_NAMES, params=params, cov=cov, residuals=resid,
        sigma2=np.diag(C), sigma2_source=source, dof=2 * n - 4, rank=rank,
        cond=design_cond(H_full), chi2=float(np.sum(white**2)),
        extra={"noise_cov": C.tolist()},
    )
    for k, ax in enumerate(AXES):
        sub = FitResult(PARAM_NAMES, params[2 * k:2 * k + 2], cov[2 * k:2 * k + 2, 2 * k:2 * k + 2],
                        resid[:, k], np.array(C[k, k]), source, n - 2, 2,
                        design_cond(H_full[k * n:(k + 1) * n, 2 * k:2 * k + 2]),
                        float(resid[:, k] @ resid[:, k] / C[k, k]))
        _check_poor(a_r[:, k], g, ax, sub)
    return fit
