"""The likelihood of any model of the catalog on one run (:class:`Extensions`).

Generic: the effects in a model are read from its :class:`~calib.effects.state.ModelState`
and every effect-specific step (design columns, tests, profiles, refinement) is asked of the
registered effect objects (:mod:`calib.effects.catalog`). Equations: package docstring.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import linalg as sla

from calib.effects.base import Trial, UntestableError
from calib.effects.catalog import CATALOG, REFINED, SHARED, effect
from calib.effects.run import RunData
from calib.effects.state import AxisState, ModelState
from calib.filters import lowpass
from calib.ls import FitResult, NotIdentifiableError, fit_linear

COND_MAX = 1e10
"""An extension whose whitened design has a larger (equilibrated) condition number is not
testable in this experiment (its columns are collinear with the model's)."""


def _logdet_gram(h: np.ndarray) -> float:
    """``log det(HᵀH)`` from the QR factor of H (``2 Σ log|R_ii|``), no normal matrix."""
    if h.size == 0:
        return 0.0
    r = np.linalg.qr(h, mode="r")
    return float(2.0 * np.sum(np.log(np.abs(np.diag(r)))))


@dataclass
class _Fit:
    nll: float
    logdet_h: float
    rss: tuple[float, float]
    fit: FitResult
    names: tuple[str, ...]
    blocks: tuple  # per axis (yw, Hw, names) of the whitened system
    resid: tuple[np.ndarray, np.ndarray]


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
        self.gains = np.asarray(gains, dtype=float)
        self._nll_cache: dict = {}
        self._chol_cache: dict = {}
        self._ref_cache: dict = {}
        self._col_cache: dict = {}
        self._axis_cache: dict = {}

    # --- columns -------------------------------------------------------------------------

    def filter(self, u: np.ndarray, tau: float) -> np.ndarray:
        """The sensor's low-pass ``LPF_τ`` along the run (identity for τ = 0)."""
        if tau <= 0:
            return u
        return lowpass(u, self.run.t, tau, self.run.h_uniform)

    def reference(self, k: int, tau: float = 0.0, limit: float = float("inf")) -> np.ndarray:
        """r = LPF_τ(clip(A_r, ±L)) of axis k, m/s²."""
        key = (k, tau, limit)
        if key not in self._ref_cache:
            if len(self._ref_cache) > 256:
                self._ref_cache.clear()
            a = self.run.a_ref[:, k]
            if np.isfinite(limit):
                a = np.clip(a, -limit, limit)
            self._ref_cache[key] = self.filter(a, tau)
        return self._ref_cache[key]

    def physical(self, k: int, tau: float) -> dict[str, np.ndarray]:
        """Columns of every effect that acts on the true specific force, through LPF_τ."""
        key = (k, tau)
        if key not in self._col_cache:
            if len(self._col_cache) > 64:
                self._col_cache.clear()
            cols: dict[str, np.ndarray] = {}
            for e in CATALOG:
                cols.update(e.raw_physical(self.run, k))
            m = self.filter(np.column_stack(list(cols.values())), tau)
            self._col_cache[key] = dict(zip(cols, m.T, strict=True))
        return self._col_cache[key]

    def columns(self, k: int, st: AxisState) -> tuple[list[str], list[np.ndarray]]:
        """Extra design columns of axis k (beyond [1, r]) for the linear extensions in ``st``."""
        names: list[str] = []
        cols: list[np.ndarray] = []
        for name in st.linear:
            e = effect(name)
            cols += e.columns(self, k, st)
            names += list(e.coefficients)
        for n, c in zip(names, cols, strict=True):
            if np.ptp(c) <= 1e-9 * max(1.0, float(np.max(np.abs(c)))):
                raise UntestableError(f"column {n} is constant over the run")
        return names, cols

    def tilt_column(self, k: int, st: AxisState) -> np.ndarray:
        """The column of axis k shared by both axes (tilt offset: reading change per sin δ)."""
        (shared,) = SHARED
        return shared.shared_column(self, k, st)

    # --- whitening -----------------------------------------------------------------------

    def _chol(self, sigma2: float, q: float) -> tuple[np.ndarray, float]:
        key = (sigma2, q)
        if key not in self._chol_cache:
            if len(self._chol_cache) > 128:
                self._chol_cache.clear()
            m = self.run.n - 1
            ab = np.empty((2, m))
            ab[0] = 2.0 * sigma2 + q * q * self.run.dt_walk
            ab[1, :-1] = -sigma2
            ab[1, -1] = 0.0
            c = sla.cholesky_banded(ab, lower=True, check_finite=False)
            self._chol_cache[key] = (c, float(2.0 * np.sum(np.log(c[0]))))
        return self._chol_cache[key]

    def whiten(self, st: AxisState, m: np.ndarray) -> np.ndarray:
        """``L⁻¹ Δ m`` for the model's noise (σ², q) of one axis: (N, …) → (N-1, …)."""
        c, _ = self._chol(st.sigma2_eff, st.q)
        return sla.solve_banded((1, 0), c, np.diff(m, axis=0), check_finite=False)

    def axis_system(self, k: int, st: AxisState, tilt: bool
                    ) -> tuple[np.ndarray, np.ndarray, list[str], float, np.ndarray | None]:
        """Whitened system of axis k: (yw, Hw, names, log det Σ_Δ, whitened tilt column)."""
        r = self.reference(k, st.tau, st.limit)
        names, cols = self.columns(k, st)
        parts = [self.run.datos[:, k] - r, r, *cols]
        if tilt:
            parts.append(self.tilt_column(k, st))
        w = self.whiten(st, np.column_stack(parts))
        _, logdet = self._chol(st.sigma2_eff, st.q)
        p = 2 + len(cols)
        return w[:, 0], w[:, 1:p], ["scale", *names], logdet, (w[:, p] if tilt else None)

    # --- likelihood ----------------------------------------------------------------------

    def _solve(self, hw: np.ndarray, yw: np.ndarray, names: list[str]) -> FitResult:
        fit = fit_linear(hw, yw, tuple(names), sigma2=1.0, intercept=None)
        if not np.isfinite(fit.cond) or fit.cond > COND_MAX:
            raise UntestableError(f"columns {', '.join(names)} are (nearly) collinear here "
                                  f"(condition number {fit.cond:.3g})")
        return fit

    def _axis_fit(self, k: int, st: AxisState) -> tuple[FitResult, tuple, float]:
        key = (k, st)
        if key not in self._axis_cache:
            if len(self._axis_cache) > 512:
                self._axis_cache.clear()
            yw, hw, names, logdet, _ = self.axis_system(k, st, False)
            self._axis_cache[key] = (self._solve(hw, yw, names), (yw, hw, names), logdet)
        return self._axis_cache[key]

    def fit(self, state: ModelState) -> _Fit:
        """Fit the linear parameters of a model at its nonlinear values; ``-2 log L``."""
        if not state.tilt:
            (fx, bx, lx), (fy, by, ly) = (self._axis_fit(k, state.axes[k]) for k in range(2))
            names = tuple([f"x.{s}" for s in bx[2]] + [f"y.{s}" for s in by[2]])
            joint = FitResult(names, np.concatenate([fx.params, fy.params]),
                              sla.block_diag(fx.cov, fy.cov),
                              np.concatenate([fx.residuals, fy.residuals]), np.array(1.0),
                              "given", fx.dof + fy.dof, fx.rank + fy.rank,
                              max(fx.cond, fy.cond), fx.chi2 + fy.chi2)
            ldh = _logdet_gram(bx[1]) + _logdet_gram(by[1])
            return _Fit(joint.chi2 + lx + ly, ldh, (fx.chi2, fy.chi2), joint, names, (bx, by),
                        (fx.residuals, fy.residuals))
        blocks = [self.axis_system(k, state.axes[k], True) for k in range(2)]
        logdet = blocks[0][3] + blocks[1][3]
        (yx, hx, nx, _, zx), (yy, hy, ny, _, zy) = blocks
        m = yx.size
        px, py = hx.shape[1], hy.shape[1]
        h = np.zeros((2 * m, px + py + 1))
        h[:m, :px], h[m:, px:px + py] = hx, hy
        h[:m, -1], h[m:, -1] = zx, zy
        names = tuple([f"x.{s}" for s in nx] + [f"y.{s}" for s in ny] + ["sin_tilt"])
        joint = self._solve(h, np.concatenate([yx, yy]), list(names))
        resid = (joint.residuals[:m], joint.residuals[m:])
        rss = (float(resid[0] @ resid[0]), float(resid[1] @ resid[1]))
        return _Fit(joint.chi2 + logdet, _logdet_gram(h), rss, joint, names,
                    tuple(b[:3] for b in blocks), resid)

    def nll(self, state: ModelState, reml: bool = False) -> float:
        """``-2 log L`` of a model (restricted w.r.t. the biases; constants dropped).

        ``reml``: the restricted likelihood w.r.t. all linear parameters, ``+ log det(H_wᵀH_w)``
        (from the QR factor of the whitened design). It removes the downward bias of a
        variance component (q) whose effect the fitted columns partly absorb; it compares
        only models with the same columns (used for q, never across designs).
        """
        key = (state, reml)
        if key not in self._nll_cache:
            if len(self._nll_cache) > 4096:
                self._nll_cache.clear()
            f = self.fit(state)
            self._nll_cache[key] = f.nll + (f.logdet_h if reml else 0.0)
        return self._nll_cache[key]

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
