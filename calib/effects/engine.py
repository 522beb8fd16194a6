"""The likelihood of any model of the catalog on one run (:class:`Extensions`).

Generic: the effects in a model are read from its :class:`~calib.effects.base.ModelState`
and every effect-specific step (design columns, tests, profiles, refinement) is asked of the
registered effect objects (:mod:`calib.effects.catalog`). Equations: package docstring.

How ``-2 log L`` is evaluated (O(N) per model, nothing recomputed that did not change)
--------------------------------------------------------------------------------------
Axis a's whitened system is ``W Δ [H_a | z_a | y_a]`` with ``H_a = [r, extension columns]``
(p_a columns), ``z_a`` the shared tilt column (tilt models only) and ``y_a = A_m - r``;
``W = L⁻¹`` for ``Σ_Δ = L Lᵀ``. One Householder QR per axis (LAPACK ``dgeqrf``) gives

    R_a = [[R_HH, r_Hz, r_Hy],
           [0,    α_a,  β_a ],
           [0,    0,    γ_a ]]

(the z row and column only with tilt). Without tilt ``RSS_a`` is the square of the last
diagonal entry. With tilt the joint fit shares ``s = sin δ``: per axis the residual left
after ``H_a`` is ``(β_a - α_a s)² + γ_a²``, so ``ŝ = Σ α_a β_a / Σ α_a²`` and
``RSS = Σ γ_a² + (α_x β_y - α_y β_x)² / (α_x² + α_y²)`` — the joint least squares of the
package docstring without forming the 2N-row joint design. ``log det(H_wᵀH_w) =
Σ_a 2 Σ log|diag R_HH| (+ log(α_x² + α_y²) with tilt)`` (REML), and the equilibrated condition
number of the whitened design comes from the same triangles (equal column norms and Gram).
The factor of each axis is cached by its state, so a profile or a test on one axis never
refits the other.

Whitening, three exact forms:

* q = 0: ``Σ_Δ = σ² T = σ² Δ Δᵀ`` and ``Δᵀ(ΔΔᵀ)⁻¹Δ = I - 11ᵀ/N``, so
  ``⟨L⁻¹Δu, L⁻¹Δv⟩ = ⟨u - ū, v - v̄⟩ / σ²``: the centred columns over σ are an isometric image
  of the whitened ones (same RSS, Gram, condition number, score statistics) with no solve;
  their factor does not depend on σ², and ``log det Σ_Δ = (N - 1) log σ² + log N``
  (``det T = N``).
* q > 0: ``Σ_Δ = L D Lᵀ`` (LAPACK ``dpttrf``, tridiagonal, O(N)) and ``W = D^{-1/2} L⁻¹``, one
  unit-bidiagonal forward substitution (``dtbtrs``) for all new columns at once; whitened
  columns are cached per (σ², q) and ``W Δ(A_m - r) = WΔA_m - WΔr``.
* q > 0 with a uniform step Δt (every untimed run, and timed runs whose steps agree to 1e-9,
  as for :func:`calib.filters.lowpass`), when the same columns are asked for a second
  (σ², q) — the profiles and the interval of q and σ²: ``Δ = U S Vᵀ`` with V the orthonormal
  DCT-II basis and ``S² = λ_j = 2 - 2 cos(πj/N)`` (j = 1 … N-1; the constant, j = 0, is what
  differencing removes), so ``ΔᵀΣ_Δ⁻¹Δ = V diag(λ_j / (σ²λ_j + q²Δt)) Vᵀ`` and
  ``ũ_j·sqrt(λ_j / (σ²λ_j + q²Δt))`` (ũ = DCT-II of u, j ≥ 1) is an isometric image of the
  whitened column. The transforms do not depend on (σ², q), so each new (σ², q) costs one
  scaling and one QR, no O(N) recursion. With a uniform step ``log det Σ_Δ`` comes in
  closed form (:meth:`Extensions._weights`) for every q > 0, so the two forms give one
  likelihood.

Every cache is bounded (least recently used), so memory stays O(N).
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable
from functools import cached_property

import numpy as np
from scipy import fft
from scipy import linalg as sla
from scipy.linalg import lapack

from calib.calibration.ls import FitResult, NotIdentifiableError, fit_linear
from calib.effects.base import AxisState, ModelState, Trial, UntestableError, effect
from calib.effects.catalog import CATALOG, REFINED, SHARED
from calib.effects.run import RunData
from calib.filters import lowpass
from calib.numerics import equilibrated_cond as _equilibrated_cond
from calib.numerics import equilibrated_cond_within as _cond_within
from calib.numerics import r_factor as _r_factor

COND_MAX = 1e10
"""An extension whose whitened design has a larger (equilibrated) condition number is not
testable in this experiment (its columns are collinear with the model's)."""


class _LRU(OrderedDict):
    """A bounded cache: the least recently used entry goes first."""

    def __init__(self, size: int) -> None:
        super().__init__()
        self.size = size

    def get_or(self, key: Hashable, make: Callable[[], object]):
        if key in self:
            self.move_to_end(key)
            return self[key]
        value = make()
        self[key] = value
        if len(self) > self.size:
            self.popitem(last=False)
        return value


class _Fit:
    """The fit of a model at its nonlinear values.

    nll : ``-2 log L``.  logdet_h : ``log det(H_wᵀH_w)`` of the whitened design (REML term).
    rss : (2,) whitened RSS per axis (of the joint fit with tilt).  names : parameter names.
    On demand (one full solve, :meth:`Extensions.fit` docs): ``fit`` the joint
    :class:`~calib.calibration.ls.FitResult` (σ² = 1 on the whitened rows), ``blocks`` per axis
    ``(yw, Hw, names)`` of the whitened system ``L⁻¹Δ·``, ``resid`` per axis whitened residuals.
    """

    def __init__(self, ext: Extensions, state: ModelState, nll: float, logdet_h: float,
                 rss: tuple[float, float], names: tuple[str, ...]) -> None:
        self._ext, self._state = ext, state
        self.nll, self.logdet_h, self.rss, self.names = nll, logdet_h, rss, names

    @cached_property
    def _full(self) -> tuple[FitResult, tuple, tuple[np.ndarray, np.ndarray]]:
        return self._ext._full_fit(self._state)

    @property
    def fit(self) -> FitResult:
        return self._full[0]

    @property
    def blocks(self) -> tuple:
        return self._full[1]

    @property
    def resid(self) -> tuple[np.ndarray, np.ndarray]:
        return self._full[2]


class Extensions:
    """Likelihood of any model of the catalog on one run, and tests of each extension.

    Parameters
    ----------
    run : the prepared run.
    gains : (2,) ``1 + scale`` per axis from the nominal fit: the multipliers of the shared
        tilt column (``(1 + s_a)·sin δ``), fixed while testing.
    """

    def __init__(self, run: RunData, gains: np.ndarray) -> None:
        self.run = run
        self.walk_bounds: dict[int, tuple[float, float]] = {}
        """Axis index → (low, high) of a random walk's q stated by a sensor profile (``gap
        --sensor``): the walk's q is searched only there and it is charged no parameter."""
        self.gains = np.asarray(gains, dtype=float)
        self._nll_cache = _LRU(16384)    # (state, reml) -> float
        self._fit_cache = _LRU(16)       # state -> _Fit
        self._axis_cache = _LRU(4096)    # axis factors (small triangles)
        self._ref_cache = _LRU(24)       # (k, τ, L) -> r (N,)
        self._phys_cache = _LRU(24)      # (k, τ, name) -> physical column (N,)
        self._col_cache = _LRU(16)       # (k, linear, τ, L) -> (names, columns)
        self._white_cache = _LRU(48)     # (column key, σ², q) -> whitened column (N-1,)
        self._factor_cache = _LRU(8)     # (σ², q) -> LDLᵀ factor of Σ_Δ
        self._spec_cache = _LRU(48)      # column key -> DCT-II (j ≥ 1) of the column (N-1,)
        self._weight_cache = _LRU(8)     # (σ², q) -> spectral weights, log det Σ_Δ
        self._seen = _LRU(512)           # axis column set -> the (σ², q) asked for it
        self._memo = _LRU(8)             # derived arrays of the effects (:meth:`memo`)
        dt = run.dt_walk
        uniform = dt.size > 0 and float(np.ptp(dt)) <= 1e-9 * float(np.mean(dt))
        self._dt_uniform = float(np.mean(dt)) if uniform else None
        if uniform:  # λ_j = 2 - 2 cos(πj/N) = 4 sin²(πj/2N), j = 1 … N-1
            self._lam = 4.0 * np.sin(0.5 * np.pi * np.arange(1, run.n) / run.n) ** 2

    # --- columns -------------------------------------------------------------------------

    def filter(self, u: np.ndarray, tau: float) -> np.ndarray:
        """The sensor's low-pass ``LPF_τ`` along the run (identity for τ = 0)."""
        if tau <= 0:
            return u
        return lowpass(u, self.run.t, tau, self.run.h_uniform)

    def reference(self, k: int, tau: float = 0.0, limit: float = float("inf")) -> np.ndarray:
        """r = LPF_τ(clip(A_r, ±L)) of axis k, m/s²."""
        def make() -> np.ndarray:
            a = self.run.a_ref[:, k]
            if np.isfinite(limit):
                a = np.clip(a, -limit, limit)
            return self.filter(a, tau)

        return self._ref_cache.get_or((k, tau, limit), make)

    def _raw_physical(self, k: int) -> dict[str, np.ndarray]:
        cols: dict[str, np.ndarray] = {}
        for e in CATALOG:
            cols.update(e.raw_physical(self.run, k))
        return cols

    def physical_column(self, k: int, tau: float, name: str) -> np.ndarray:
        """One column of :meth:`physical` (only that one is filtered); KeyError if absent."""
        def make() -> np.ndarray:
            return self.filter(self._raw_physical(k)[name], tau)

        return self._phys_cache.get_or((k, tau, name), make)

    def physical(self, k: int, tau: float) -> dict[str, np.ndarray]:
        """Columns of every effect that acts on the true specific force, through LPF_τ."""
        return {n: self.physical_column(k, tau, n) for n in self._raw_physical(k)}

    def columns(self, k: int, st: AxisState) -> tuple[list[str], list[np.ndarray]]:
        """Extra design columns of axis k (beyond [1, r]) for the linear extensions in ``st``.

        The columns of a linear effect depend on the axis state only through τ and L
        (:meth:`calib.effects.base.Effect.columns`): they are cached by (k, effects, τ, L).
        """
        def make() -> tuple[tuple[str, ...], tuple[np.ndarray, ...]]:
            names: list[str] = []
            cols: list[np.ndarray] = []
            for name in st.linear:
                e = effect(name)
                cols += e.columns(self, k, st)
                names += list(e.coefficients)
            for n, c in zip(names, cols, strict=True):
                if np.ptp(c) <= 1e-9 * max(1.0, float(np.max(np.abs(c)))):
                    raise UntestableError(f"column {n} is constant over the run")
            return tuple(names), tuple(cols)

        names, cols = self._col_cache.get_or((k, st.linear, st.tau, st.limit), make)
        return list(names), list(cols)

    def tilt_column(self, k: int, st: AxisState) -> np.ndarray:
        """The column of axis k shared by both axes (tilt offset: reading change per sin δ)."""
        (shared,) = SHARED
        return shared.shared_column(self, k, st)

    def memo(self, key: Hashable, make: Callable[[], object]):
        """``make()`` once per key (a few recent keys kept): arrays an effect derives from
        the run, e.g. the saturation's grid of limits and hinge columns."""
        return self._memo.get_or(key, make)

    # --- whitening -----------------------------------------------------------------------

    def _factor(self, sigma2: float, q: float) -> tuple[np.ndarray, np.ndarray, float]:
        """``Σ_Δ = σ² T + q² diag(Δt) = L D Lᵀ``: (band of the unit L for ``dtbtrs``,
        ``D^{-1/2}``, ``log det Σ_Δ = Σ log D``)."""
        def make() -> tuple[np.ndarray, np.ndarray, float]:
            m = self.run.n - 1
            d = 2.0 * sigma2 + q * q * self.run.dt_walk
            band = np.zeros((2, m))
            band[0] = 1.0
            if m > 1:
                d, e, info = lapack.dpttrf(d, np.full(m - 1, -sigma2))
                if info != 0:
                    raise np.linalg.LinAlgError(f"Σ_Δ is not positive definite (dpttrf {info})")
                band[1, :-1] = e
            return band, 1.0 / np.sqrt(d), float(np.sum(np.log(d)))

        return self._factor_cache.get_or((sigma2, q), make)

    def _weights(self, sigma2: float, q: float) -> tuple[np.ndarray, float]:
        """Uniform step: ``sqrt(λ_j / (σ²λ_j + q²Δt))`` (j = 1 … N-1) and ``log det Σ_Δ``.

        ``Σ_Δ`` is then the (N-1)² tridiagonal Toeplitz matrix with ``a = 2σ² + q²Δt`` on the
        diagonal and ``-σ²`` beside it: ``det = (r₊^N - r₋^N)/(r₊ - r₋)``, ``r± = (a ± s)/2``,
        ``s = sqrt(a² - 4σ⁴) = q·sqrt(Δt·(4σ² + q²Δt))`` (the recursion ``D_k = a D_{k-1} -
        σ⁴ D_{k-2}``), evaluated in logs with ``log1p``/``expm1``: O(1) and to rounding of
        ``Σ_j log(σ²λ_j + q²Δt)``.
        """
        def make() -> tuple[np.ndarray, float]:
            h = self._dt_uniform
            w = np.sqrt(self._lam / (sigma2 * self._lam + q * q * h))
            a = 2.0 * sigma2 + q * q * h
            s = q * np.sqrt(h * (4.0 * sigma2 + q * q * h))
            n = self.run.n
            logdet = (n * np.log(0.5 * (a + s)) - np.log(s)
                      + np.log(-np.expm1(n * np.log1p(-2.0 * s / (a + s)))))
            return w, float(logdet)

        return self._weight_cache.get_or((sigma2, q), make)

    def _logdet(self, st: AxisState) -> float:
        """``log det Σ_Δ`` of one axis."""
        if st.q == 0:  # det(σ² T) = σ^{2(N-1)} N
            return float((self.run.n - 1) * np.log(st.sigma2_eff) + np.log(self.run.n))
        if self._dt_uniform is not None:
            return self._weights(st.sigma2_eff, st.q)[1]
        return self._factor(st.sigma2_eff, st.q)[2]

    def _spectra(self, items: list[tuple[Hashable, np.ndarray]]) -> list[np.ndarray]:
        """Orthonormal DCT-II of named columns without the constant term (cached by name)."""
        out = [self._spec_cache.get(key) for key, _ in items]
        todo = [i for i, c in enumerate(out) if c is None]
        if todo:
            u = np.empty((len(todo), self.run.n))
            for j, i in enumerate(todo):
                u[j] = items[i][1]
            spec = fft.dct(u, type=2, norm="ortho", axis=-1, overwrite_x=True)
            for j, i in enumerate(todo):
                col = spec[j, 1:].copy()
                out[i] = self._spec_cache.get_or(items[i][0], lambda c=col: c)
        for key, _ in items:  # (one may have been evicted by the insertions above)
            if key in self._spec_cache:
                self._spec_cache.move_to_end(key)
        return out  # type: ignore[return-value]

    def _solve_white(self, st: AxisState, dm: np.ndarray) -> np.ndarray:
        """``D^{-1/2} L⁻¹ dm`` for differenced columns dm (N-1, c)."""
        band, s, _ = self._factor(st.sigma2_eff, st.q)
        x, info = lapack.dtbtrs(band, dm, uplo="L", diag="U")
        if info != 0:
            raise np.linalg.LinAlgError(f"dtbtrs failed (info = {info})")
        return x * s[:, None]

    def whiten(self, st: AxisState, m: np.ndarray) -> np.ndarray:
        """``L⁻¹ Δ m`` for the model's noise (σ², q) of one axis: (N, …) → (N-1, …)."""
        m = np.asarray(m, dtype=float)
        d = np.diff(m.reshape(m.shape[0], -1), axis=0)
        return self._solve_white(st, d).reshape((m.shape[0] - 1,) + m.shape[1:])

    def white(self, st: AxisState, m: np.ndarray, key: Hashable | None = None) -> np.ndarray:
        """An isometric image of :meth:`whiten` (the same inner products, so the same RSS,
        Gram matrices and score statistics), cheaper: ``(m - m̄)/σ`` (N rows) when q = 0,
        ``L⁻¹Δm`` (N-1 rows) otherwise. ``key`` names the columns for the cache."""
        if key is not None and st.q > 0:
            return self._white_cache.get_or((key, st.sigma2_eff, st.q),
                                            lambda: self.whiten(st, m))
        if st.q > 0:
            return self.whiten(st, m)
        m = np.asarray(m, dtype=float)
        return (m - m.mean(axis=0)) / np.sqrt(st.sigma2_eff)

    def _white_columns(self, st: AxisState, items: list[tuple[Hashable, np.ndarray]]
                       ) -> list[np.ndarray]:
        """``L⁻¹Δ`` of named columns (q > 0), the new ones in one solve, cached per (σ², q)."""
        sq = (st.sigma2_eff, st.q)
        out: list[np.ndarray | None] = []
        todo: list[int] = []
        for i, (key, _) in enumerate(items):
            hit = self._white_cache.get((key, *sq))
            if hit is not None:
                self._white_cache.move_to_end((key, *sq))
            else:
                todo.append(i)
            out.append(hit)
        if todo:
            dm = np.empty((self.run.n - 1, len(todo)), order="F")
            for j, i in enumerate(todo):
                dm[:, j] = np.diff(items[i][1])
            w = self._solve_white(st, dm)
            for j, i in enumerate(todo):
                col = np.ascontiguousarray(w[:, j])
                out[i] = self._white_cache.get_or((items[i][0], *sq), lambda c=col: c)
        return out  # type: ignore[return-value]

    def _axis_items(self, k: int, st: AxisState, tilt: bool
                    ) -> tuple[list[str], list[tuple[Hashable, np.ndarray]]]:
        """Names of H and the named columns ``[r, extension columns, (tilt column)]``."""
        r = self.reference(k, st.tau, st.limit)
        names, cols = self.columns(k, st)
        items: list[tuple[Hashable, np.ndarray]] = [(("r", k, st.tau, st.limit), r)]
        items += [(("col", k, n, st.tau, st.limit), c) for n, c in zip(names, cols, strict=True)]
        if tilt:
            items.append((("tilt", k, st.tau), self.tilt_column(k, st)))
        return ["scale", *names], items

    def _note(self, k: int, st: AxisState, tilt: bool) -> set:
        """Record that axis k's columns were asked for the noise (σ², q) of ``st``."""
        seen = self._seen.get_or((k, st.linear, st.tau, st.limit, tilt), set)
        seen.add((st.sigma2_eff, st.q))
        return seen

    def _use_spectra(self, k: int, st: AxisState, tilt: bool,
                     items: list[tuple[Hashable, np.ndarray]]) -> bool:
        """Whether to whiten axis k's columns in the DCT basis (module docstring): uniform
        step, and the spectra are cached, or these columns were already asked for another
        (σ², q) and none of them is whitened for this one (a profile of q or σ²; a profile
        of τ or L keeps the data column and solves only its few new columns)."""
        if self._dt_uniform is None:
            return False
        sq = (st.sigma2_eff, st.q)
        seen = self._note(k, st, tilt)
        if all(key in self._spec_cache for key, _ in items):
            return True
        return len(seen) > 1 and not any((key, *sq) in self._white_cache for key, _ in items)

    def _white_system(self, k: int, st: AxisState, tilt: bool, spectral: bool = True
                      ) -> tuple[np.ndarray, list[str]]:
        """Fortran-ordered ``[H | z | y]`` of axis k in the form of :meth:`white` (or, when
        ``spectral`` allows it, in the DCT basis), unscaled by σ when q = 0 (its factor is
        then independent of σ²), and the names of H."""
        names, items = self._axis_items(k, st, tilt)
        y = self.run.datos[:, k]
        if st.q == 0:
            self._note(k, st, tilt)  # a profile of q from here goes spectral at once
            a = np.empty((self.run.n, len(items) + 1), order="F")
            for j, (_, c) in enumerate(items):
                a[:, j] = c
            np.subtract(y, items[0][1], out=a[:, -1])
            a -= a.mean(axis=0)
            return a, names
        items = [*items, (("y", k), y)]
        if spectral and self._use_spectra(k, st, tilt, items):
            spec = self._spectra(items)
            w, _ = self._weights(st.sigma2_eff, st.q)
            a = np.empty((self.run.n - 1, len(items)), order="F")
            for j, c in enumerate(spec[:-1]):
                np.multiply(c, w, out=a[:, j])
            np.subtract(spec[-1], spec[0], out=a[:, -1])
            a[:, -1] *= w
            return a, names
        cols = self._white_columns(st, items)
        a = np.empty((self.run.n - 1, len(cols)), order="F")
        for j, c in enumerate(cols[:-1]):
            a[:, j] = c
        np.subtract(cols[-1], cols[0], out=a[:, -1])  # W(A_m - r) = W A_m - W r
        return a, names

    def _axis_factor(self, k: int, st: AxisState, tilt: bool
                     ) -> tuple[np.ndarray, list[str], float] | None:
        """R of axis k's whitened ``[H | z | y]`` (module docstring), the names of H and the
        equilibrated condition number of H alone (without tilt; exact where it may exceed
        :data:`COND_MAX`, below it possibly a bound that is too:
        :func:`calib.numerics.equilibrated_cond_within`); None when the rows cannot identify
        the columns."""
        if st.q == 0:
            key = ("c", k, st.linear, st.tau, st.limit, tilt)
        else:
            key = ("w", k, st, tilt)

        def make():
            a, names = self._white_system(k, st, tilt)
            if a.shape[0] <= a.shape[1]:
                return None
            r = _r_factor(a, overwrite=True)  # a is built here and not used again
            p = len(names)
            return r, names, (np.nan if tilt else _cond_within(r[:p, :p], COND_MAX))

        got = self._axis_cache.get_or(key, make)
        if got is None:
            return None
        r, names, cond = got
        if st.q == 0:
            r = r / np.sqrt(st.sigma2_eff)
        return r, names, cond

    def axis_parts(self, k: int, st: AxisState, tilt: bool) -> tuple[np.ndarray, list[str]]:
        """The unwhitened system of axis k: (N, 1 + p [+ 1]) columns ``[y - r, r, effect
        columns…, tilt column]`` (m/s²; the tilt column when ``tilt``) and the names of the
        p model columns (``scale`` first)."""
        r = self.reference(k, st.tau, st.limit)
        names, cols = self.columns(k, st)
        parts = [self.run.datos[:, k] - r, r, *cols]
        if tilt:
            parts.append(self.tilt_column(k, st))
        return np.column_stack(parts), ["scale", *names]

    def axis_system(self, k: int, st: AxisState, tilt: bool
                    ) -> tuple[np.ndarray, np.ndarray, list[str], float, np.ndarray | None]:
        """Whitened system of axis k: (yw, Hw, names, log det Σ_Δ, whitened tilt column)."""
        parts, names = self.axis_parts(k, st, tilt)
        w = self.whiten(st, parts)
        p = 1 + len(names)
        return (w[:, 0], w[:, 1:p], names, self._logdet(st), (w[:, p] if tilt else None))

    # --- likelihood ----------------------------------------------------------------------

    def _solve(self, hw: np.ndarray, yw: np.ndarray, names: list[str]) -> FitResult:
        fit = fit_linear(hw, yw, tuple(names), sigma2=1.0, intercept=None)
        if not np.isfinite(fit.cond) or fit.cond > COND_MAX:
            raise UntestableError(f"columns {', '.join(names)} are (nearly) collinear here "
                                  f"(condition number {fit.cond:.3g})")
        return fit

    def _full_fit(self, state: ModelState
                  ) -> tuple[FitResult, tuple, tuple[np.ndarray, np.ndarray]]:
        """The joint fit on the whitened rows ``L⁻¹Δ·`` (parameters, covariance, residuals);
        raises the named error when the design cannot identify the columns."""
        if not state.tilt:
            fits, blocks = [], []
            for k in range(2):
                yw, hw, names, _, _ = self.axis_system(k, state.axes[k], False)
                fits.append(self._solve(hw, yw, names))
                blocks.append((yw, hw, names))
            fx, fy = fits
            names = tuple([f"x.{s}" for s in blocks[0][2]] + [f"y.{s}" for s in blocks[1][2]])
            joint = FitResult(names, np.concatenate([fx.params, fy.params]),
                              sla.block_diag(fx.cov, fy.cov),
                              np.concatenate([fx.residuals, fy.residuals]), np.array(1.0),
                              "given", fx.dof + fy.dof, fx.rank + fy.rank,
                              max(fx.cond, fy.cond), fx.chi2 + fy.chi2)
            return joint, tuple(blocks), (fx.residuals, fy.residuals)
        systems = [self.axis_system(k, state.axes[k], True) for k in range(2)]
        (yx, hx, nx, _, zx), (yy, hy, ny, _, zy) = systems
        m = yx.size
        px, py = hx.shape[1], hy.shape[1]
        h = np.zeros((2 * m, px + py + 1))
        h[:m, :px], h[m:, px:px + py] = hx, hy
        h[:m, -1], h[m:, -1] = zx, zy
        names = tuple([f"x.{s}" for s in nx] + [f"y.{s}" for s in ny] + ["sin_tilt"])
        joint = self._solve(h, np.concatenate([yx, yy]), list(names))
        return (joint, tuple(s[:3] for s in systems),
                (joint.residuals[:m], joint.residuals[m:]))

    def _assemble(self, state: ModelState) -> _Fit:
        """``-2 log L``, REML term and per-axis RSS from the two axis factors."""
        got = [self._axis_factor(k, state.axes[k], state.tilt) for k in range(2)]
        if got[0] is None or got[1] is None:
            self._full_fit(state)  # raises the named error
            raise NotIdentifiableError("fewer samples than parameters")
        (rx, nx, cx_h), (ry, ny, cy_h) = got
        names = [f"x.{s}" for s in nx] + [f"y.{s}" for s in ny]
        ps = (len(nx), len(ny))
        tri = [np.abs(np.diag(r[:p, :p])) for r, p in ((rx, ps[0]), (ry, ps[1]))]
        logdet_h = float(sum(2.0 * np.sum(np.log(d)) for d in tri))
        if not state.tilt:
            rss = (float(rx[-1, -1] ** 2), float(ry[-1, -1] ** 2))
            cond = max(cx_h, cy_h)
        else:
            names.append("sin_tilt")
            (ax, bx, cx), (ay, by, cy) = ((r[p, p], r[p, p + 1], r[p + 1, p + 1])
                                          for r, p in ((rx, ps[0]), (ry, ps[1])))
            den = ax * ax + ay * ay
            s = (ax * bx + ay * by) / den if den > 0 else 0.0
            rss = (float(cx * cx + (bx - ax * s) ** 2), float(cy * cy + (by - ay * s) ** 2))
            logdet_h += float(np.log(den)) if den > 0 else -np.inf
            px, py = ps
            j = np.zeros((px + py + 2, px + py + 1))  # rows with the joint design's Gram
            j[:px, :px], j[:px, -1] = rx[:px, :px], rx[:px, px]
            j[px, -1] = ax
            j[px + 1:px + 1 + py, px:px + py], j[px + 1:px + 1 + py, -1] = ry[:py, :py], ry[:py, py]
            j[-1, -1] = ay
            cond = _equilibrated_cond(j)
        if not np.isfinite(cond) or cond > COND_MAX or not all((d > 0).all() for d in tri):
            self._full_fit(state)  # raises the named error (rank or condition)
            raise UntestableError(f"columns {', '.join(names)} are (nearly) collinear here "
                                  f"(condition number {cond:.3g})")
        nll = rss[0] + rss[1] + self._logdet(state.axes[0]) + self._logdet(state.axes[1])
        return _Fit(self, state, float(nll), logdet_h, rss, tuple(names))

    def fit(self, state: ModelState) -> _Fit:
        """Fit the linear parameters of a model at its nonlinear values; ``-2 log L``.

        ``-2 log L`` and the per-axis RSS come from the cached axis factors (module
        docstring); the parameters, covariance and whitened system (``fit``, ``blocks``,
        ``resid`` of the result) are solved on first use.
        """
        return self._fit_cache.get_or(state, lambda: self._assemble(state))

    def whitened_residual(self, k: int, state: ModelState) -> tuple[np.ndarray, np.ndarray]:
        """Axis k of the model's fit in the form of :meth:`white`: (residual with unit
        variance, design ``[H | z]``: the columns the residual is orthogonal to or shares)."""
        st = state.axes[k]
        a, _ = self._white_system(k, st, state.tilt, spectral=False)
        if st.q == 0:
            a /= np.sqrt(st.sigma2_eff)
        ncol = a.shape[1] - 1
        y = a[:, -1].copy()
        p = ncol - (1 if state.tilt else 0)
        if state.tilt:  # ŝ of the joint fit (module docstring)
            ab = []
            for j in range(2):
                r, _, _ = self._axis_factor(j, state.axes[j], True)
                pj = r.shape[1] - 2
                ab.append((r[pj, pj], r[pj, pj + 1]))
            (ax, bx), (ay, by) = ab
            y -= a[:, p] * ((ax * bx + ay * by) / (ax * ax + ay * ay))
        beta, *_ = np.linalg.lstsq(a[:, :p], y, rcond=None)
        return y - a[:, :p] @ beta, a[:, :ncol]

    def nll(self, state: ModelState, reml: bool = False) -> float:
        """``-2 log L`` of a model (restricted w.r.t. the biases; constants dropped).

        ``reml``: the restricted likelihood w.r.t. all linear parameters, ``+ log det(H_wᵀH_w)``
        (from the QR factor of the whitened design). It removes the downward bias of a
        variance component (q) whose effect the fitted columns partly absorb; it compares
        only models with the same columns (used for q, never across designs).
        """
        def make() -> float:
            f = self.fit(state)
            return f.nll + (f.logdet_h if reml else 0.0)

        return self._nll_cache.get_or((state, reml), make)

    def n_params(self, state: ModelState, k: int) -> int:
        """Parameters of axis k: bias, scale, columns, nonlinear ones, shared tilt."""
        return state.n_params(k)

    def safe_nll(self, state: ModelState, reml: bool = False) -> float:
        """:meth:`nll`, or inf when the model is not identifiable here (profile searches)."""
        try:
            return self.nll(state, reml)
        except NotIdentifiableError:
            return np.inf

    # --- tests and refinement: asked of the effect objects ----------------------------------

    def test(self, state: ModelState, name: str, axis: str) -> Trial:
        """Test extension ``name`` on ``axis`` on top of ``state`` (likelihood ratio).

        Each effect object states its reference distribution of ``LR = -2 log Λ`` under "no
        such effect": χ²(k) for the linear columns and the tilt offset (σ² known), χ̄² for the
        boundary parameters q and τ, Davies' bound for the saturation limit, the two-sided
        χ²(dof) for noise_level (modules :mod:`~calib.effects.linear`,
        :mod:`~calib.effects.tilt`, :mod:`~calib.effects.response`,
        :mod:`~calib.effects.noise`).
        """
        return effect(name).test(self, state, axis)

    def refine(self, state: ModelState, passes: int = 2) -> ModelState:
        """Coordinate descent over every nonlinear parameter and free σ² (local windows)."""
        for _ in range(passes):
            for k in range(2):
                for e in REFINED:
                    if e.present(state.axes[k]):
                        state = e.refine(self, state, k)
        return state
