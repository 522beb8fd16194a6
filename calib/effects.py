"""Model extensions of the discrepancy workflow: one per effect of ``docs/effects.md``.

The nominal model of axis a ∈ {x, y} (course; IEEE Std 1293 K0 = bias, K1 = 1 + scale) is
``A_m = bias + (1 + scale)·A_r + v``, v ~ N(0, σ²) white. Every effect of the catalog is an
*extension* of it with its own parameters, in the catalog's units and sign conventions
(``A_rx = -g sin θ``, ``A_ry = -g cos θ``; ``a_p`` = the other axis' reference; ω = dθ/dt,
α = d²θ/dt²)::

    A_m = bias + (1 + s)·[ LPF_τ(clip(A_r, ±L) + δ·sgn·A_p + lever) + k2·r² + k_ip·r·A_p ]
          + rate·(t - t0) + b_walk(t) + v,        then rounded to multiples of lsb

with ``r = LPF_τ(clip(A_r, ±L))``, sgn = +1 (x: ``-g sin(θ+δ) ≈ A_rx + δ A_ry``) or -1 (y:
``-g cos(θ+δ) ≈ A_ry - δ A_rx``), and the lever-arm projection derived from the table geometry
(hinge along +y, site at (pos_x, 0, pos_z) in the table frame, sensitive axis +x for the x
sensor and -z for the y sensor; acceleration of the site ``α ŷ×p - ω² p``)::

    x:  -ω²·pos_x + α·pos_z            y:  +ω²·pos_z + α·pos_x

Which parameter enters how (so each is estimated the right way):

================== ============================ ===============================================
effect              parameter (units)            extension
================== ============================ ===============================================
misalignment        δ (rad)                      column sgn·A_p; exact: ``δ = atan2(c, 1 + s')``
tilt_offset         δ (rad), both axes           one shared column ``sgn·(1 + ŝ_a)·A_p``: sin δ
nonlinearity_k2     k2 (1/(m/s²))                column r², ``k2 = c/(1 + s)``
cross_axis          k_ip (1/(m/s²))              column r·A_p, ``k_ip = c/(1 + s)``
bias_drift          rate (m/s² per s or sample)  column t - t0 (or index k), additive: rate = c
lever_arm           pos_x, pos_z (m)             columns ω², α; divided by (1 + s), signs above
lowpass_lag         τ (s)                        r = LPF_τ(A_r): 1-D profile likelihood in τ
saturation          limit L (m/s²)               r = clip(A_r, ±L): 1-D profile in L
bias_random_walk    q (m/s²/√s or /√sample)      exact Gaussian likelihood (see below), ML in q
noise_level         σ² ((m/s²)²)                 σ² free (profile), χ² interval
quantization        lsb (m/s²)                   lattice of the readings; adds lsb²/12 to σ²
gravity_mismatch    g (m/s²)                     none: absorbed by the scale factors
================== ============================ ===============================================

Likelihood (one code path for every model)
------------------------------------------
The readings are differenced, ``Δy_k = y_k - y_{k-1}``; this removes the bias (an exact
reparametrisation: it is the likelihood restricted with respect to the bias) and makes the
random-walk model banded: ``Δy = ΔH β + q√Δt_k w_k + v_k - v_{k-1}`` has the tridiagonal
covariance ``Σ_Δ = σ² T + q² diag(Δt)`` (T: 2 on the diagonal, -1 beside it). With its banded
Cholesky factor ``Σ_Δ = L Lᵀ`` (``scipy.linalg.cholesky_banded``, O(N)) the model is whitened,
``L⁻¹Δy ≈ L⁻¹ΔH β``, solved by :func:`calib.ls.fit_linear` (QR / lstsq, never a normal matrix)
and ``-2 log L = RSS + log det Σ_Δ`` (+ a constant common to all models). With q = 0 this is
exactly ordinary least squares with an intercept. This is the exact Gaussian likelihood of
the local-level (random-walk bias) model that a Kalman filter with a diffuse initial level
computes (the filter itself gives the innovations and the smoothed bias in :mod:`calib.gap`),
at O(N) per evaluation without a Python loop. q is estimated by restricted ML (REML, see
:meth:`Extensions.nll`). Nested models are compared by the likelihood ratio
``LR = Δ(-2 log L)``.

The low-pass is the one of the bench (``bench.effects.lowpass``): exact for an input linear
between samples, ``y_k = u_k - τc_k + e^{-h/τ}(y_{k-1} - u_{k-1} + τc_k)``, ``c_k = (u_k -
u_{k-1})/h``, starting at rest (``y_0 = u_0``); it acts on the signal (response stage) and the
white noise of the reading stays white.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy import linalg as sla
from scipy import optimize, stats

from calib.conventions import AXES, EFFECT_NAMES, NEEDS_TIMING, PER_SAMPLE_UNITS, reference_accel
from calib.diagnostics import (
    LN2,
    angular_rates,
    chi2_two_sided_logp,
    flat_top_score,
    hinge_columns,
    hinge_levels,
)
from calib.filters import lowpass
from calib.ls import FitResult, NotIdentifiableError, fit_linear

LINEAR_COLUMNS: dict[str, tuple[str, ...]] = {
    "misalignment": ("c_mis",),
    "nonlinearity_k2": ("c_k2",),
    "cross_axis": ("c_cross",),
    "bias_drift": ("c_drift",),
    "lever_arm": ("c_w2", "c_alpha"),
}
"""Effects that are extra design-matrix columns on top of [1, A_r], and their coefficients."""

PHYSICAL_COLUMNS = ("misalignment", "lever_arm")
"""Columns that act on the true specific force, so they pass through the sensor's low-pass."""

SIGN_P: tuple[float, float] = (1.0, -1.0)
"""Sign of the other axis' reference in a rotation by +δ: x: A_rx + δA_ry; y: A_ry - δA_rx."""

COND_MAX = 1e10
"""An extension whose whitened design has a larger (equilibrated) condition number is not
testable in this experiment (its columns are collinear with the model's)."""

def _logdet_gram(h: np.ndarray) -> float:
    """``log det(HᵀH)`` from the QR factor of H (``2 Σ log|R_ii|``), no normal matrix."""
    if h.size == 0:
        return 0.0
    r = np.linalg.qr(h, mode="r")
    return float(2.0 * np.sum(np.log(np.abs(np.diag(r)))))


class UntestableError(NotIdentifiableError):
    """The extension cannot be tested in this experiment (collinear, or no data for it)."""


# ---------------------------------------------------------------------------- the run

@dataclass(frozen=True, eq=False)
class RunData:
    """A measured calibration run prepared for the extensions (read-only arrays).

    tita : (N,) rad.  datos : (N, 2) m/s².  a_ref : (N, 2) ``[-g sin θ, -g cos θ]``.
    sigma2 : (2,) stated noise variances, (m/s²)².  g : m/s².
    t : (N,) sample times, s (the file's ``t`` or ``k/rate``), or None.
    tcol : (N,) ``t - t0`` (s) or the sample index k.  time_unit : "s" or "sample".
    dt_walk : (N-1,) Δt of the random walk (s, or 1 per sample).
    omega, alpha : (N,) dθ/dt (rad/s), d²θ/dt² (rad/s²) when timed, else None.
    h_uniform : the sampling period when ``t`` is uniform, else None.
    """

    tita: np.ndarray
    datos: np.ndarray
    a_ref: np.ndarray
    sigma2: np.ndarray
    g: float
    t: np.ndarray | None
    tcol: np.ndarray
    time_unit: str
    dt_walk: np.ndarray
    omega: np.ndarray | None
    alpha: np.ndarray | None
    h_uniform: float | None

    @property
    def n(self) -> int:
        return int(self.tita.shape[0])

    @property
    def timed(self) -> bool:
        return self.t is not None

    @classmethod
    def build(cls, tita, datos, noise_var, g: float, t=None, rate: float | None = None
              ) -> RunData:
        """Prepare a run. ``t`` (s) wins over ``rate`` (Hz, samples in time order)."""
        tita = np.asarray(tita, dtype=float)
        datos = np.asarray(datos, dtype=float)
        n = tita.shape[0]
        if datos.shape != (n, 2):
            raise ValueError(f"datos must be ({n}, 2), got {datos.shape}")
        s2 = np.asarray(noise_var, dtype=float)
        if s2.shape == (2, 2):
            s2 = np.diag(s2)
        if s2.shape != (2,) or np.any(~np.isfinite(s2)) or np.any(s2 <= 0):
            raise ValueError(f"noise_var must be two positive variances, got {noise_var!r}")
        if t is None and rate is not None:
            if not (np.isfinite(rate) and rate > 0):
                raise ValueError(f"rate must be a positive sample rate (Hz), got {rate}")
            t = np.arange(n, dtype=float) / float(rate)
        omega = alpha = None
        h_uniform = None
        if t is not None:
            t = np.asarray(t, dtype=float)
            if t.shape != (n,) or np.any(np.diff(t) <= 0):
                raise ValueError("t must be (N,) and strictly increasing")
            tcol = t - t[0]
            dt = np.diff(t)
            if np.max(np.abs(dt - dt.mean())) <= 1e-9 * dt.mean():
                h_uniform = float(dt.mean())
            omega, alpha = angular_rates(tita, t)
            unit = "s"
        else:
            tcol = np.arange(n, dtype=float)
            dt = np.ones(n - 1)
            unit = "sample"
        arrays = dict(tita=tita, datos=datos, a_ref=reference_accel(tita, g), sigma2=s2,
                      t=t, tcol=tcol, dt_walk=dt, omega=omega, alpha=alpha)
        for v in arrays.values():
            if v is not None:
                v.setflags(write=False)
        return cls(g=float(g), time_unit=unit, h_uniform=h_uniform, **arrays)


# ----------------------------------------------------------------------- model states

@dataclass(frozen=True)
class AxisState:
    """The model of one axis: which extensions, and the values of the nonlinear ones.

    linear : effects present as design columns (:data:`LINEAR_COLUMNS`).
    tau : low-pass time constant, s (0: none).  q : random-walk intensity (0: none), m/s²
        per √(time unit).  limit : saturation limit, m/s² (inf: none).
    sigma2 : white-noise variance in use, (m/s²)² (the stated one unless ``noise_free``).
    noise_free : ``noise_level`` is in the model (σ² estimated).
    lsb : quantization step, m/s² (0: none); adds lsb²/12 to the noise variance.
    """

    linear: tuple[str, ...] = ()
    tau: float = 0.0
    q: float = 0.0
    limit: float = float("inf")
    sigma2: float = 1.0
    noise_free: bool = False
    lsb: float = 0.0

    @property
    def sigma2_eff(self) -> float:
        """Variance of the reading's white error: σ² + lsb²/12 (Sheppard), (m/s²)²."""
        return self.sigma2 + self.lsb**2 / 12.0

    def effects(self) -> tuple[str, ...]:
        """Catalog names of the extensions present (catalog order)."""
        present = set(self.linear)
        present |= {name for name, on in (("lowpass_lag", self.tau > 0),
                                          ("bias_random_walk", self.q > 0),
                                          ("saturation", np.isfinite(self.limit)),
                                          ("noise_level", self.noise_free),
                                          ("quantization", self.lsb > 0)) if on}
        return tuple(n for n in EFFECT_NAMES if n in present)

    @property
    def n_nonlinear(self) -> int:
        return int(self.tau > 0) + int(self.q > 0) + int(np.isfinite(self.limit))

    def has(self, name: str) -> bool:
        return name in self.effects()

    def add(self, name: str, value: float | None = None) -> AxisState:
        if name in LINEAR_COLUMNS:
            order = [n for n in EFFECT_NAMES if n in set(self.linear) | {name}]
            return replace(self, linear=tuple(order))
        if name == "lowpass_lag":
            return replace(self, tau=float(value))
        if name == "bias_random_walk":
            return replace(self, q=float(value))
        if name == "saturation":
            return replace(self, limit=float(value))
        if name == "noise_level":
            return replace(self, sigma2=float(value), noise_free=True)
        raise ValueError(f"{name} is not a per-axis extension")

    def remove(self, name: str, stated_sigma2: float) -> AxisState:
        if name in LINEAR_COLUMNS:
            return replace(self, linear=tuple(n for n in self.linear if n != name))
        return {"lowpass_lag": lambda: replace(self, tau=0.0),
                "bias_random_walk": lambda: replace(self, q=0.0),
                "saturation": lambda: replace(self, limit=float("inf")),
                "noise_level": lambda: replace(self, sigma2=stated_sigma2, noise_free=False),
                "quantization": lambda: replace(self, lsb=0.0)}[name]()


@dataclass(frozen=True)
class ModelState:
    """The model of the run: both axes and the shared tilt offset (a column with sin δ)."""

    axes: tuple[AxisState, AxisState]
    tilt: bool = False

    def axis(self, k: int) -> AxisState:
        return self.axes[k]

    def with_axis(self, k: int, st: AxisState) -> ModelState:
        axes = list(self.axes)
        axes[k] = st
        return replace(self, axes=(axes[0], axes[1]))

    def effects(self) -> list[tuple[str, str]]:
        """(name, axis) of every extension in the model, catalog order."""
        out = [("tilt_offset", "both")] if self.tilt else []
        for k, a in enumerate(AXES):
            out += [(n, a) for n in self.axes[k].effects()]
        rank = {n: i for i, n in enumerate(EFFECT_NAMES)}
        return sorted(out, key=lambda e: (rank[e[0]], e[1]))


# ------------------------------------------------------------------------ trial results

@dataclass(frozen=True)
class Trial:
    """One extension tested on top of a model.

    name, axis : the effect.  state : the extended model (its parameter at the ML value).
    lr : likelihood-ratio statistic ``-2 log Λ`` (≥ 0).  logp : log p-value under the
    reference distribution in ``reference``.  nll : ``-2 log L`` of the extended model.
    """

    name: str
    axis: str
    state: ModelState
    lr: float
    logp: float
    nll: float
    reference: str

    @property
    def p_value(self) -> float:
        return float(np.exp(self.logp))


@dataclass
class _Fit:
    nll: float
    logdet_h: float
    rss: tuple[float, float]
    fit: FitResult
    names: tuple[str, ...]
    blocks: tuple  # per axis (yw, Hw, names) of the whitened system
    resid: tuple[np.ndarray, np.ndarray]


# ------------------------------------------------------------------------ the engine

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

    def _filter(self, u: np.ndarray, tau: float) -> np.ndarray:
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
            self._ref_cache[key] = self._filter(a, tau)
        return self._ref_cache[key]

    def _physical(self, k: int, tau: float) -> dict[str, np.ndarray]:
        key = (k, tau)
        if key not in self._col_cache:
            if len(self._col_cache) > 64:
                self._col_cache.clear()
            run = self.run
            cols = {"mis": SIGN_P[k] * run.a_ref[:, 1 - k]}
            if run.omega is not None:
                cols["w2"] = run.omega**2
                cols["alpha"] = run.alpha
            m = np.column_stack(list(cols.values()))
            m = self._filter(m, tau)
            self._col_cache[key] = dict(zip(cols, m.T, strict=True))
        return self._col_cache[key]

    def columns(self, k: int, st: AxisState) -> tuple[list[str], list[np.ndarray]]:
        """Extra design columns of axis k (beyond [1, r]) for the linear extensions in ``st``."""
        names: list[str] = []
        cols: list[np.ndarray] = []
        r = self.reference(k, st.tau, st.limit)
        phys = self._physical(k, st.tau)
        a_p = self.run.a_ref[:, 1 - k]
        for e in st.linear:
            if e == "misalignment":
                cols.append(phys["mis"])
            elif e == "nonlinearity_k2":
                cols.append(r * r)
            elif e == "cross_axis":
                cols.append(r * a_p)
            elif e == "bias_drift":
                cols.append(self.run.tcol)
            elif e == "lever_arm":
                if "w2" not in phys:
                    raise UntestableError("lever_arm needs sample times")
                cols += [phys["w2"], phys["alpha"]]
            names += list(LINEAR_COLUMNS[e])
        for n, c in zip(names, cols, strict=True):
            if np.ptp(c) <= 1e-9 * max(1.0, float(np.max(np.abs(c)))):
                raise UntestableError(f"column {n} is constant over the run")
        return names, cols

    def tilt_column(self, k: int, st: AxisState) -> np.ndarray:
        """``sgn·(1 + ŝ_k)·LPF_τ(A_p)``: the reading change per unit sin δ of a tilt offset."""
        return self.gains[k] * self._physical(k, st.tau)["mis"]

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
        st = state.axes[k]
        ncols = sum(len(LINEAR_COLUMNS[e]) for e in st.linear)
        return 2 + ncols + st.n_nonlinear + int(state.tilt) + int(st.noise_free)

    # --- 1-D profile optimisation ----------------------------------------------------------

    @staticmethod
    def _minimise(f: Callable[[float], float], grid: np.ndarray) -> tuple[float, float]:
        """Minimise f over a sorted grid, then Brent between the best point's neighbours."""
        vals = np.array([f(x) for x in grid])
        i = int(np.nanargmin(vals))
        lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
        best_x, best_f = float(grid[i]), float(vals[i])
        if hi > lo:
            res = optimize.minimize_scalar(f, bounds=(lo, hi), method="bounded",
                                           options={"xatol": 1e-4 * (hi - lo) + 1e-12})
            if res.fun < best_f:
                best_x, best_f = float(res.x), float(res.fun)
        return best_x, best_f

    def _safe(self, state: ModelState, reml: bool = False) -> float:
        try:
            return self.nll(state, reml)
        except NotIdentifiableError:
            return np.inf

    def profile_q(self, state: ModelState, k: int, window: float | None = None
                  ) -> tuple[float, float]:
        """REML of the random-walk intensity q of axis k (others fixed): (q, REML -2 log L)."""
        st = state.axes[k]
        s2 = st.sigma2_eff
        dtm = float(np.median(self.run.dt_walk))
        n = self.run.n

        def f(lk: float) -> float:
            q = float(np.sqrt(np.exp(lk) * s2 / dtm))
            return self._safe(state.with_axis(k, replace(st, q=q)), reml=True)

        if window is None:
            grid = np.linspace(np.log(0.01 / n**2), 0.0, 18)
        else:
            c = np.log(st.q**2 * dtm / s2)
            grid = np.linspace(c - window, c + window, 7)
        lk, val = self._minimise(f, grid)
        return float(np.sqrt(np.exp(lk) * s2 / dtm)), val

    def profile_tau(self, state: ModelState, k: int, window: float | None = None
                    ) -> tuple[float, float]:
        """ML of the low-pass time constant τ (s) of axis k (others fixed): (τ, nll)."""
        st = state.axes[k]
        h = float(np.median(np.diff(self.run.t)))
        dur = float(self.run.t[-1] - self.run.t[0])

        def f(lt: float) -> float:
            return self._safe(state.with_axis(k, replace(st, tau=float(np.exp(lt)))))

        if window is None:
            grid = np.linspace(np.log(0.01 * h), np.log(max(0.25 * dur, 2 * h)), 24)
        else:
            c = np.log(st.tau)
            grid = np.linspace(c - window, c + window, 7)
        lt, val = self._minimise(f, grid)
        return float(np.exp(lt)), val

    def profile_limit(self, state: ModelState, k: int, window: float | None = None
                      ) -> tuple[float, float]:
        """ML of the saturation limit L (m/s²) of axis k (others fixed): (L, nll)."""
        st = state.axes[k]

        def f(lim: float) -> float:
            return self._safe(state.with_axis(k, replace(st, limit=float(lim))))

        if window is None:
            grid = np.sort(hinge_levels(self.run.a_ref[:, k]))
        else:
            grid = st.limit * np.linspace(1 - window, 1 + window, 7)
        if grid.size == 0:
            return float("inf"), self.nll(state)
        lim, val = self._minimise(f, grid)
        return lim, val

    def profile_sigma2(self, state: ModelState, k: int) -> tuple[float, float]:
        """ML of the white-noise variance σ² of axis k (others fixed): (σ², nll)."""
        st = state.axes[k]
        fit = self.fit(state)
        m = self.run.n - 1
        guess = max(fit.rss[k] * st.sigma2_eff / m - st.lsb**2 / 12.0, 1e-12 * st.sigma2_eff)
        if st.q == 0:  # RSS ∝ 1/σ²_eff exactly: closed form
            return guess, self._safe(state.with_axis(k, replace(st, sigma2=guess)))

        def f(ls: float) -> float:
            return self._safe(state.with_axis(k, replace(st, sigma2=float(np.exp(ls)))))

        ls, val = self._minimise(f, np.log(guess) + np.linspace(-0.7, 0.7, 7))
        return float(np.exp(ls)), val

    # --- tests of one extension --------------------------------------------------------------

    def test(self, state: ModelState, name: str, axis: str) -> Trial:
        """Test extension ``name`` on ``axis`` on top of ``state`` (likelihood ratio).

        Reference distributions of ``LR = -2 log Λ`` under "no such effect":

        * linear columns (misalignment, K2, cross-axis, drift, lever arm), tilt offset: σ²
          known, so ``LR = Δχ² ~ χ²(k)`` exactly (k = number of columns).
        * bias_random_walk (q ≥ 0) and lowpass_lag (τ ≥ 0): parameter on the boundary,
          ``LR ~ ½χ²₀ + ½χ²₁`` (χ̄²; for a random-walk variance the true point mass at 0 is
          larger than ½, so this p-value is conservative).
        * saturation: L exists only under the alternative: Davies' bound on the sup of the
          one-sided score process over the grid of limits (:func:`davies_logp`).
        * noise_level: ``RSS/σ²_stated ~ χ²(dof)`` exactly, two-sided.
        """
        if name == "tilt_offset":
            new = replace(state, tilt=True)
            nll1 = self.nll(new)
            lr = max(self.nll(state) - nll1, 0.0)
            return Trial(name, "both", new, lr, float(stats.chi2.logsf(lr, 1)), nll1,
                         "chi2(1)")
        k = AXES.index(axis)
        st = state.axes[k]
        nll0 = self.nll(state)
        if name in LINEAR_COLUMNS:
            new = state.with_axis(k, st.add(name))
            nll1 = self.nll(new)
            lr = max(nll0 - nll1, 0.0)
            df = len(LINEAR_COLUMNS[name])
            return Trial(name, axis, new, lr, float(stats.chi2.logsf(lr, df)), nll1,
                         f"chi2({df})")
        if name in ("bias_random_walk", "lowpass_lag"):
            if name == "lowpass_lag" and not self.run.timed:
                raise UntestableError("lowpass_lag needs sample times")
            rw = name == "bias_random_walk"
            prof = self.profile_q if rw else self.profile_tau
            val, nll1 = prof(state, k)
            lr = (self.nll(state, reml=True) if rw else nll0) - nll1
            if not np.isfinite(nll1) or lr <= 0:
                return Trial(name, axis, state, 0.0, 0.0, nll0, "chibar2(0:1)")
            new = state.with_axis(k, st.add(name, val))
            return Trial(name, axis, new, lr, float(-LN2 + stats.chi2.logsf(lr, 1)),
                         self.nll(new), "chibar2(0:1)")
        if name == "saturation":
            logp = self.saturation_score(state, k)
            lim, nll1 = self.profile_limit(state, k)
            lr = max(nll0 - nll1, 0.0)
            new = state.with_axis(k, st.add(name, lim)) if np.isfinite(lim) else state
            return Trial(name, axis, new, lr, logp, min(nll1, nll0), "davies")
        if name == "noise_level":
            fit = self.fit(state)
            dof = self.run.n - 1 - (self.n_params(state, k) - 1)
            logp = chi2_two_sided_logp(fit.rss[k], dof)
            s2, nll1 = self.profile_sigma2(state, k)
            new = state.with_axis(k, st.add(name, s2))
            return Trial(name, axis, new, max(nll0 - nll1, 0.0), logp, nll1, f"chi2({dof})")
        raise ValueError(f"unknown extension {name!r}")

    def saturation_score(self, state: ModelState, k: int) -> float:
        """log p of the flat-top score test (clip at ±L, L unknown) on axis k."""
        st = state.axes[k]
        levels = hinge_levels(self.run.a_ref[:, k])
        if levels.size == 0:
            raise UntestableError("no range of |A_r| to clip")
        fit = self.fit(state)
        yw, hw, _ = fit.blocks[k]
        design = hw
        if state.tilt:
            design = np.column_stack([hw, self.whiten(st, self.tilt_column(k, st))])
        a = self.run.a_ref[:, k]
        hinges = self._filter(hinge_columns(a, levels), st.tau)
        _, logp = flat_top_score(fit.resid[k], design, self.whiten(st, hinges))
        return logp

    # --- refinement of all nonlinear parameters ------------------------------------------------

    def refine(self, state: ModelState, passes: int = 2) -> ModelState:
        """Coordinate descent over every nonlinear parameter and free σ² (local windows)."""
        for _ in range(passes):
            for k in range(2):
                st = state.axes[k]
                if st.tau > 0:
                    tau, _ = self.profile_tau(state, k, window=0.5)
                    state = state.with_axis(k, replace(state.axes[k], tau=tau))
                if np.isfinite(st.limit):
                    lim, _ = self.profile_limit(state, k, window=0.05)
                    state = state.with_axis(k, replace(state.axes[k], limit=lim))
                if st.q > 0:
                    q, _ = self.profile_q(state, k, window=1.0)
                    state = state.with_axis(k, replace(state.axes[k], q=q))
                if st.noise_free:
                    s2, _ = self.profile_sigma2(state, k)
                    state = state.with_axis(k, replace(state.axes[k], sigma2=s2))
        return state


__all__ = [
    "EFFECT_NAMES", "NEEDS_TIMING", "PER_SAMPLE_UNITS", "LINEAR_COLUMNS", "SIGN_P",
    "AxisState", "ModelState", "RunData", "Trial", "Extensions", "UntestableError", "lowpass",
]
