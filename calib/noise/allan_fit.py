"""The fit of the noise terms to the octave Allan variances, its intervals and the rule that
picks the model (:mod:`calib.noise.allan` reports it; ``tiltbench noise`` prints it).

**Estimator.** θ (:data:`calib.noise.allan_model.ALL_TERM_NAMES`: N²·fs, B², K²/fs, Q²·fs², σ²)
is the generalized least-squares estimate on the octave Allan variances ``s_i`` with their full
covariance ``V(θ)`` (exact for the model's processes, :mod:`calib.noise.allan_model`), iterated
so that V is evaluated at the fit (IRLS: whitened by Cholesky, solved by QR; no normal matrix is
inverted), with every θ ≥ 0 (non-negative least squares on the whitened system: a term may
not go negative to cancel another — that would let V(θ) grow with the term it hides and any
curve pass the χ² test). The terms outside the model are held at 0; the standard errors are
the unconstrained GLS ones at the fit.

**Adequacy** of a model on a range of octaves (both must hold):

=====================  ========================================================  ==========
check                  statistic and reference                                   threshold
=====================  ========================================================  ==========
the curve              GLS residual ``χ² = rᵀV⁻¹r`` on ``n_τ − p`` dof           p ≥ 0.01
the Allan minimum      the bias-instability part alone ``B²·X_iB`` under every   α = 0.01
                       point's upper χ² bound ``s_i·ν_i/χ²_{ν_i}(α)``             per point
=====================  ========================================================  ==========

(``LACK_OF_FIT_P``, ``B_BOUND_ALPHA``). The second is IEEE Std 952's reading "the flat floor
is 0.664·B" turned into a bound, ``B ≤ min σ_A/0.664`` with the *upper* χ² bound of each
point (ν_i its exact EDF): a fitted B that puts its floor above what the measured minimum allows
is refused, but B is never clipped to the noisy minimum itself.

**Model rule** (:meth:`Engine.select`): on a range of octaves, start from the three core terms
N, B, K; the ladder's larger models add the quantization term Q (slope −1: an integrated
output, or a filter that whitens the first octaves), a Gauss–Markov term (σ, T_c; T_c on the
grid of :func:`calib.noise.allan_model.gm_grid`, the one of smallest χ² with V held at the
current fit), or both. Then

1. move to the larger model whose χ² drop (V held at the current fit) exceeds
   ``χ²_Δp(1 − ADD_ALPHA/G)`` by the most (Δp the parameters added, T_c counted; G the
   octaves of the range for a new Gauss–Markov term — one independent try of T_c per
   octave — else 1; ``ADD_ALPHA`` = 0.01), fitted exactly, kept if adequate; repeat. A term
   the curve shows is modelled even when the smaller model passes, rather than absorbed
   into B or N;
2. while the current model is *not* adequate, move to any larger model that is (the widening
   rule: the largest drop first);
3. an extra term whose removal leaves an adequate model, with a χ² rise below the same
   threshold, leaves again (a term taken on the way that the final model does not need);
4. the model must be adequate. On the whole octave grid (or ``--tau-range``) first; if no
   model is adequate there, the widest contiguous range of octaves (at least
   ``max(MIN_FIT_OCTAVES, p + 2)``) on which one is, among equally wide ranges the one of
   largest p (its χ² p-value); the octaves left out are reported as the ones the model does
   not describe;
5. if none is adequate anywhere: the three core terms on the whole grid, reported as *not*
   describing the curve (``fit_ok`` false; ``noise --save`` refuses it).

**Intervals** (two-sided ``level``, per term): the set of values θ_0 that a score-type test
accepts — θ_a fixed at θ_0, the other terms of the model refitted, V evaluated *under that
hypothesis*, θ_0 kept while ``|θ̂_a(V) − θ_0|/se_a(V) ≤ z_{(1+level)/2}`` (Wilson's construction;
a Wald interval undercovers the walk: 0.82 at 0.95). A negative estimate is taken as 0 (the
interval is then [0, upper]: it only accepts more values). **Resolved**: the same test rejects
θ_a = 0 one-sided at ``alpha``; for the rate random walk also the rise rule below.

**The rise rule of K** (``K_RISE_*``): K is resolved only when, over at least
``K_RISE_STEPS`` = 2 octave steps inside the model's range whose both ends hold at least
``K_RISE_CLUSTERS`` = 8 non-overlapping clusters (n/m ≥ 8), the fitted curve rises with slope
≥ +¼ and K is its largest term. A +½ slope read from the last octave alone (n/m = 4 clusters:
an Allan variance with 2–3 degrees of freedom) is not a random walk: that is what a 107-s log
called "resolved" before. The false-call rate on white + flicker logs is at most α
(``tests/test_allan_rules.py``, Monte Carlo with a binomial band).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from calib import distributions as stats
from calib.noise.allan_model import ALL_TERM_NAMES, N_PROCESSES, AllanMoments

LACK_OF_FIT_P = 0.01
"""p below which a model is said not to describe the Allan curve (GLS residual χ²)."""
B_BOUND_ALPHA = 0.01
"""One-sided α of each octave's upper χ² bound that the bias-instability floor must stay under
(the bound at the measured minimum is IEEE Std 952's ``B ≤ min σ_A / 0.664``)."""
ADD_ALPHA = 0.01
"""A larger model of the ladder replaces an adequate one when its χ² drop is significant at
this α (Šidák-corrected for the correlation times searched): a term the curve shows is added
even when the smaller model passes, so that it does not leak into the others."""
MIN_FIT_OCTAVES = 5
"""Fewest octaves a model is read from (3 core terms + 2 dof; more with more terms: p + 2)."""
K_RISE_CLUSTERS = 8
"""Non-overlapping clusters (n/m) an octave needs to count for the rise of K: at 8 its Allan
variance has ≥ 5 degrees of freedom for a walk (Greenhall's EDF at m = n/8), at 4 only ~2."""
K_RISE_STEPS = 2
"""Octave steps of rise (slope ≥ ``K_RISE_SLOPE``, K the largest term) K needs to be resolved."""
K_RISE_SLOPE = 0.25
"""Slope of the ADEV (log–log) an octave step needs to count as rising: halfway from the flat
floor (0) to the walk's +½."""
WHITE, FLICKER, WALK, QUANT, GM = range(N_PROCESSES)
CORE = (WHITE, FLICKER, WALK)
LADDER: tuple[tuple[int, ...], ...] = (CORE, CORE + (QUANT,), CORE + (GM,), CORE + (QUANT, GM))
"""The models in the order the rule tries them (module docstring)."""
LADDER_NAMES = ("three terms", "with quantization", "with Gauss–Markov",
                "with quantization and Gauss–Markov")


@dataclass(frozen=True)
class Model:
    """Which terms (indices of :data:`ALL_TERM_NAMES`), which GM correlation time (index of
    the moments' ``gm_tc``) and which octaves ``[lo, hi)`` a fit uses."""

    active: tuple[int, ...]
    g: int | None
    lo: int
    hi: int

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(ALL_TERM_NAMES[a] for a in self.active)


@dataclass(frozen=True)
class ModelFit:
    """One model fitted: θ (5,), its covariance over the active terms, χ², the bound."""

    model: Model
    theta: np.ndarray
    cov: np.ndarray
    chi2: float
    dof: int
    p: float
    bound_ok: bool
    b_bound: float
    b_bound_index: int
    edf: np.ndarray = field(repr=False)

    @property
    def adequate(self) -> bool:
        return self.p >= LACK_OF_FIT_P and self.bound_ok


def gls(s: np.ndarray, design: np.ndarray, cov: np.ndarray
        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Batched GLS: s (n,) or (G, n), design (n, p) or (G, n, p), cov (G, n, n) →
    (θ (G, p), Cov θ (G, p, p), χ² (G,)). Whitened by Cholesky, columns equilibrated, solved
    by QR: ``R θ = Qᵀ s_w``, ``Cov θ = R⁻¹R⁻ᵀ`` (R is p×p triangular; no normal matrix)."""
    li = np.linalg.inv(np.linalg.cholesky(cov))  # L⁻¹ (G, n, n): whitens both sides
    xw = li @ design
    sw = (li @ np.broadcast_to(s, cov.shape[:2])[..., None])[..., 0]
    scale = np.linalg.norm(xw, axis=1)
    scale = np.where(scale > 0, scale, 1.0)
    q, r = np.linalg.qr(xw / scale[:, None, :])
    qs = np.einsum("gnp,gn->gp", q, sw)
    theta = np.linalg.solve(r, qs[..., None])[..., 0] / scale
    ri = np.linalg.inv(r)
    cov_theta = ri @ np.swapaxes(ri, 1, 2) / (scale[:, :, None] * scale[:, None, :])
    res = sw - np.einsum("gnp,gp->gn", xw, theta)
    return theta, cov_theta, np.einsum("gn,gn->g", res, res)


def nnls_gls(s: np.ndarray, design: np.ndarray, cov: np.ndarray
             ) -> tuple[np.ndarray, None, np.ndarray]:
    """GLS with θ ≥ 0 (``scipy.optimize.nnls`` on the whitened, equilibrated system), one
    batch element at a time: (θ (G, p), None, χ² (G,)). A term cannot go negative to cancel
    another: the V(θ) of an IRLS step is then never inflated by a large term that a negative
    one hides in the mean, which would let any curve "pass" the χ² test."""
    from scipy.optimize import nnls

    li = np.linalg.inv(np.linalg.cholesky(cov))
    xw = li @ design
    sw = (li @ np.broadcast_to(s, cov.shape[:2])[..., None])[..., 0]
    theta = np.empty((cov.shape[0], xw.shape[-1]))
    chi2 = np.empty(cov.shape[0])
    for g in range(cov.shape[0]):
        scale = np.linalg.norm(xw[g], axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        sol, rnorm = nnls(xw[g] / scale, sw[g])
        theta[g] = sol / scale
        chi2[g] = rnorm ** 2
    return theta, None, chi2


class Engine:
    """The octave Allan variances ``s`` of one axis with the moments of its record: fits,
    score tests and the model rule (module docstring)."""

    def __init__(self, s: np.ndarray, mom: AllanMoments, floor: float,
                 nonnegative: bool = True):
        self.s = np.asarray(s, dtype=float)
        self.mom = mom
        self.floor = float(floor)
        self.k = self.s.size
        self.nonnegative = nonnegative

    # -------------------------------------------------------------- pieces
    def arrays(self, model: Model) -> tuple[np.ndarray, np.ndarray]:
        """(design (k_f, 5), tensor (k_f, k_f, 5, 5)) on the model's octaves."""
        design, tensor = self.mom.full(model.g)
        sl = slice(model.lo, model.hi)
        return design[sl], tensor[sl, sl]

    def valid(self, theta: np.ndarray) -> np.ndarray:
        t = np.maximum(theta, 0.0)
        t[..., WHITE] = np.maximum(t[..., WHITE], self.floor)
        return t

    def cov_of(self, tensor: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """V (G, k, k) at each θ (G, 5) (clipped: :meth:`valid`): ``V_ij = θᵀ T_ij θ`` as one
        matrix product of the outer products θθᵀ with the flattened tensor."""
        th = self.valid(np.atleast_2d(theta))
        k, p = tensor.shape[0], tensor.shape[-1]
        outer = (th[:, :, None] * th[:, None, :]).reshape(th.shape[0], p * p)
        return (outer @ tensor.reshape(k * k, p * p).T).reshape(th.shape[0], k, k)

    def _start(self, s: np.ndarray, design: np.ndarray, active: tuple[int, ...]) -> np.ndarray:
        """A first θ: least squares in relative terms (weights 1/s), negative entries at 0."""
        x = design[:, list(active)] / s[:, None]
        sol = np.linalg.lstsq(x / np.linalg.norm(x, axis=0), np.ones_like(s), rcond=None)[0]
        theta = np.zeros(N_PROCESSES)
        theta[list(active)] = sol / np.linalg.norm(x, axis=0)
        return self.valid(theta)

    def fit(self, model: Model, start: np.ndarray | None = None, iterations: int = 6
            ) -> ModelFit:
        """IRLS on the model's octaves (module docstring)."""
        design, tensor = self.arrays(model)
        s = self.s[model.lo:model.hi]
        act = list(model.active)
        theta = self._start(s, design, model.active) if start is None else self.valid(start)
        solve = nnls_gls if self.nonnegative else gls
        for _ in range(iterations):
            v = self.cov_of(tensor, theta)
            est, _, chi2 = solve(s, design[:, act], v)
            theta = np.zeros(N_PROCESSES)
            theta[act] = est[0]
        v = self.cov_of(tensor, theta)
        est, _, chi2 = solve(s, design[:, act], v)
        theta = np.zeros(N_PROCESSES)
        theta[act] = est[0]
        cov = gls(s, design[:, act], v)[1]  # the unconstrained GLS covariance: the se
        return self._finish(model, theta, cov[0], float(chi2[0]), design, tensor)

    def _finish(self, model, theta, cov, chi2, design, tensor) -> ModelFit:
        dof = (model.hi - model.lo) - len(model.active)
        s = self.s[model.lo:model.hi]
        th = self.valid(theta)
        var = np.einsum("a,iiab,b->i", th, tensor, th)
        nu = 2.0 * (design @ th) ** 2 / var
        upper = s * nu / stats.chi2.ppf(B_BOUND_ALPHA, nu)
        flick = design[:, FLICKER]
        allowed = upper / flick  # the largest B² each point allows
        i = int(np.argmin(allowed))
        bound_ok = bool(max(theta[FLICKER], 0.0) <= allowed[i])
        return ModelFit(model=model, theta=theta, cov=cov, chi2=chi2, dof=dof,
                        p=float(stats.chi2.sf(chi2, dof)) if dof > 0 else float("nan"),
                        bound_ok=bound_ok, b_bound=float(allowed[i]),
                        b_bound_index=model.lo + i, edf=nu)

    # -------------------------------------------------------------- the rule
    def select(self) -> tuple[ModelFit, bool, list[ModelFit]]:
        """(the chosen fit, whether it is adequate, every fit tried) by the model rule of the
        module docstring."""
        tried: list[ModelFit] = []
        k = self.k
        for width in range(k, MIN_FIT_OCTAVES - 1, -1):
            found: list[ModelFit] = []
            for lo in range(0, k - width + 1):
                hit = self._ladder(lo, lo + width, tried)
                if hit is not None:
                    found.append(hit)
            if found:
                best = max(found, key=lambda f: (f.p, -len(f.model.active)))
                return best, True, tried
        base = next(f for f in tried if f.model == Model(CORE, None, 0, k))
        return base, False, tried

    def _ladder(self, lo: int, hi: int, tried: list[ModelFit]) -> ModelFit | None:
        """The model of octaves [lo, hi) by the rule (module docstring, steps 1, 4 and 5), or
        None when no model of the ladder is adequate there."""
        if hi - lo < MIN_FIT_OCTAVES:
            return None
        current = self.fit(Model(CORE, None, lo, hi))
        tried.append(current)
        while True:
            cands = []
            for active in LADDER:
                if (not set(current.model.active) < set(active)
                        or hi - lo < max(MIN_FIT_OCTAVES, len(active) + 2)):
                    continue
                chi2, g = self._proxy(current, active)
                limit = self._threshold(current.model.active, active, hi - lo)
                cands.append((current.chi2 - chi2 - limit, active, g))
            cands.sort(key=lambda c: -c[0])
            moved = False
            for margin, active, g in cands:
                # a significant drop; or, while the current model is not adequate, any
                # larger model that is (the largest drop first): the widening rule
                if margin <= 0 and current.adequate:
                    break
                new = self.fit(Model(active, g, lo, hi))
                tried.append(new)
                if new.adequate or (margin > 0 and not current.adequate):
                    current, moved = new, True
                    break
            if not moved:
                break
        if not current.adequate:
            return None
        return self.prune(current, tried)

    @staticmethod
    def _threshold(small: tuple[int, ...], large: tuple[int, ...], octaves: int) -> float:
        """``χ²_Δp(1 − ADD_ALPHA/G)`` between the models ``small`` ⊂ ``large`` on ``octaves``
        octaves (steps 4, 5): Δp the parameters added (T_c counted), G the octaves for a new
        Gauss–Markov term (its T_c is searched on a fine grid, but a GM bump spans about two
        octaves, so neighbouring candidates are nearly one model: one independent try per
        octave, Šidák), else 1."""
        new_gm = GM in large and GM not in small
        searched = octaves if new_gm else 1
        added = len(large) - len(small) + (1 if new_gm else 0)
        return float(stats.chi2.isf(ADD_ALPHA / searched, added))

    def prune(self, fit: ModelFit, tried: list[ModelFit]) -> ModelFit:
        """Step 5 of the rule: an extra term (quantization, Gauss–Markov) leaves the model when
        the model without it is adequate and the term's χ² drop is not significant (the
        threshold of :meth:`_threshold`, V held at the larger fit): a term taken on the way
        that the final model no longer needs leaves it."""
        current = fit
        changed = True
        while changed:
            changed = False
            for extra in (QUANT, GM):
                if extra not in current.model.active:
                    continue
                active = tuple(a for a in current.model.active if a != extra)
                m = current.model
                g = None if extra == GM else m.g
                design, _ = self.arrays(Model(active, g, m.lo, m.hi))
                _, tensor_c = self.arrays(m)
                v = self.cov_of(tensor_c, current.theta)
                chi2 = float(gls(self.s[m.lo:m.hi], design[:, list(active)], v)[2][0])
                if chi2 - current.chi2 > self._threshold(active, m.active, m.hi - m.lo):
                    continue
                smaller = self.fit(Model(active, g, m.lo, m.hi))
                tried.append(smaller)
                if smaller.adequate:
                    current, changed = smaller, True
                    break
        return current

    def _proxy(self, current: ModelFit, active: tuple[int, ...]) -> tuple[float, int | None]:
        """χ² of the model ``active`` with V held at ``current`` (and, for a new
        Gauss–Markov term, the T_c of smallest χ²): (χ², GM index)."""
        lo, hi = current.model.lo, current.model.hi
        s = self.s[lo:hi]
        _, tensor_c = self.arrays(current.model)
        v = self.cov_of(tensor_c, current.theta)
        act = list(active)
        if GM in active and current.model.g is None:
            base, _ = self.arrays(Model(current.model.active, None, lo, hi))
            count = self.mom.gm_tc.size
            design = np.zeros((count, hi - lo, N_PROCESSES))
            design[:, :, :4] = base[:, :4]
            design[:, :, GM] = self.mom.gm_design[:, lo:hi]
            # one V for every candidate: whiten once, then one batched QR (χ² = |s_w|² −
            # |Qᵀs_w|², the residual of the whitened least squares)
            li = np.linalg.inv(np.linalg.cholesky(v[0]))
            xw = li @ design[:, :, act]
            sw = li @ s
            q = np.linalg.qr(xw / np.linalg.norm(xw, axis=1, keepdims=True))[0]
            chi2 = sw @ sw - np.sum(np.einsum("gkp,k->gp", q, sw) ** 2, axis=1)
            g = int(np.argmin(chi2))
            return float(chi2[g]), g
        design, _ = self.arrays(Model(active, current.model.g, lo, hi))
        return float(gls(s, design[:, act], v)[2][0]), current.model.g

    # -------------------------------------------------------------- intervals
    def score_z(self, fit: ModelFit, which: np.ndarray, values: np.ndarray,
                clip: bool = False, iterations: int = 2) -> np.ndarray:
        """z(θ_0) = (θ̂_a(V) − θ_0)/se_a(V), V under the hypothesis θ_a = θ_0 with the model's
        other terms refitted, for each (a, θ_0) pair of ``which``/``values`` at once (module
        docstring). ``clip``: θ̂_a(V) taken as max(θ̂_a(V), 0) (for the interval)."""
        model = fit.model
        design, tensor = self.arrays(model)
        s = self.s[model.lo:model.hi]
        act = list(model.active)
        h = which.size
        rows = np.arange(h)
        theta = np.tile(fit.theta, (h, 1))
        theta[rows, which] = values
        free = np.array([[b for b in act if b != a] for a in which], dtype=int)
        xf = design[:, free].transpose(1, 0, 2)  # (H, k, p - 1)
        for _ in range(iterations):
            v = self.cov_of(tensor, theta)
            sub = s[None, :] - design[:, which].T * values[:, None]
            est = gls(sub, xf, v)[0]
            theta[rows[:, None], free] = est
        v = self.cov_of(tensor, theta)
        est, cov, _ = gls(s, design[:, act], v)
        pos = np.array([act.index(a) for a in which])
        top = est[rows, pos]
        if clip:
            top = np.maximum(top, 0.0)
        return (top - values) / np.sqrt(cov[rows, pos, pos])

    def intervals(self, fit: ModelFit, level: float, caps: np.ndarray | None = None
                  ) -> dict[int, tuple[float, float, float]]:
        """Per active term a: (lo, hi, z_0) in θ units — the score interval at ``level`` and
        the statistic of θ_a = 0 (module docstring). All terms and both ends are searched
        together: one batched GLS per step.

        ``caps`` (5,), θ units: the largest value a term may take (the physical range of its
        unit, :mod:`calib.noise.sensor_profile`). A term read from few degrees of freedom may
        not be bounded at all at a high level (far up, V grows with θ_0 as fast as the
        distance to it: z tends to a constant above −z): its upper end is then the cap."""
        act = np.array(fit.model.active)
        z_two = float(stats.norm.ppf(0.5 + level / 2.0))
        zero = np.where(act == WHITE, self.floor, 0.0)
        z0 = self.score_z(fit, act, zero)
        est = np.maximum(fit.theta[act], zero)
        se = np.sqrt(np.maximum(np.diag(fit.cov), 0.0))
        cap = np.full(act.size, np.inf) if caps is None else np.maximum(caps[act], est)
        # upper end: z(θ_0) falls below −z; expand the bracket until it does (or the cap)
        lo_hi = est.copy()
        hi_hi = np.minimum(est + 4.0 * se + self.floor + 1e-300, cap)
        for _ in range(80):
            z = self.score_z(fit, act, hi_hi, clip=True)
            grow = (z >= -z_two) & (hi_hi < cap)
            if not grow.any():
                break
            lo_hi = np.where(grow, hi_hi, lo_hi)
            hi_hi = np.where(grow, np.minimum(hi_hi * 2.0 + 1e-300, cap), hi_hi)
        need_lo = z0 > z_two
        brackets = [(lo_hi, hi_hi, -z_two, np.ones(act.size, bool)),
                    (zero.copy(), np.maximum(est, zero), z_two, need_lo)]
        ends = self._refine(fit, act, brackets)
        out = {}
        for k, a in enumerate(act):
            lo = float(ends[1][k]) if need_lo[k] else float(zero[k])
            out[int(a)] = (lo, float(ends[0][k]), float(z0[k]))
        return out

    def _refine(self, fit: ModelFit, act: np.ndarray, brackets, points: int = 9,
                rounds: int = 2) -> list[np.ndarray]:
        """θ_0 where z(θ_0) = target inside each bracket (z decreasing in θ_0): a grid of
        ``points`` per bracket, narrowed ``rounds`` times to the two grid points around the
        crossing (8^-rounds of the bracket), then the crossing interpolated linearly in z
        between them — far finer than the interval's own sampling error (the bracket is
        about 4 standard errors wide); every bracket in one batch."""
        grids = [np.linspace(lo, hi, points, axis=1) for lo, hi, _, _ in brackets]
        result = [np.array(g[:, 0]) for g in grids]
        for _ in range(rounds):
            which = np.concatenate([np.repeat(act, points) for _ in brackets])
            values = np.concatenate([g.ravel() for g in grids])
            z = self.score_z(fit, which, values, clip=True)
            z = z.reshape(len(brackets), act.size, points)
            for b, (_, _, target, use) in enumerate(brackets):
                g = grids[b]
                above = z[b] >= target
                last = np.where(above.any(axis=1), points - 1 - np.argmax(above[:, ::-1],
                                                                           axis=1), -1)
                for t in range(act.size):
                    if not use[t]:
                        continue
                    k = int(last[t])
                    if k < 0:
                        result[b][t] = g[t, 0]
                        g[t] = g[t, 0]
                    elif k == points - 1:
                        result[b][t] = g[t, -1]
                        g[t] = g[t, -1]
                    else:
                        z0, z1 = z[b, t, k], z[b, t, k + 1]
                        w = 0.5 if not z0 > z1 else (z0 - target) / (z0 - z1)
                        result[b][t] = g[t, k] + w * (g[t, k + 1] - g[t, k])
                        g[t] = np.linspace(g[t, k], g[t, k + 1], points)
        return result


def rise_steps(fit: ModelFit, design: np.ndarray, ms: tuple[int, ...], n: int) -> int:
    """Octave steps of the model's range where the fitted curve rises with slope ≥ +¼, K is
    its largest term at both ends and both ends hold ≥ ``K_RISE_CLUSTERS`` clusters (module
    docstring: the rise rule of K)."""
    th = np.maximum(fit.theta, 0.0)
    parts = design * th
    mu = parts.sum(axis=1)
    count = 0
    for i in range(fit.model.lo, fit.model.hi - 1):
        j = i + 1
        if n // ms[j] < K_RISE_CLUSTERS:
            continue
        slope = 0.5 * math.log(mu[j] / mu[i]) / math.log(ms[j] / ms[i])
        top = all(int(np.argmax(parts[x])) == WALK for x in (i, j))
        count += slope >= K_RISE_SLOPE and top
    return count


__all__ = ["ADD_ALPHA", "B_BOUND_ALPHA", "CORE", "FLICKER", "GM", "K_RISE_CLUSTERS", "K_RISE_SLOPE",
           "K_RISE_STEPS", "LACK_OF_FIT_P", "LADDER", "LADDER_NAMES", "MIN_FIT_OCTAVES", "nnls_gls",
           "QUANT", "WALK", "WHITE", "Engine", "Model", "ModelFit", "gls", "rise_steps"]
