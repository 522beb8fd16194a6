"""Twin closure: does a simulated twin of the fitted profile have the Allan deviation of the
log it was fitted to? (``tiltbench noise LOG --twin``.)

The log's octave Allan variances ``s_i`` and the twin's ``t_i`` (the profile simulated for the
log's length and rate by the bench's generator, :func:`bench.sensor_twin.simulate_axis`, and
averaged in the same blocks) are two independent curves. One joint test compares them over
every octave of the grid, inside the model's τ range and outside it:

    u_i = log s_i − log t_i − [b(ν_i) − b(ν'_i)],   b(ν) = ψ(ν/2) − log(ν/2)

(``E log(χ²_ν/ν) = b(ν)``, ψ the digamma function; ν_i, ν'_i the exact EDF of each point for
the log's fitted model and for the twin's, :func:`calib.noise.allan_model.edf`), and

    T = uᵀ Σ_u⁻¹ u  ~  χ²_k  under "the twin is the sensor",   reject when p < α (family α).

**Both curves' variances and the correlation between octaves.** ``Var log s_i = ψ'(ν_i/2)``
(trigamma: exact for a scaled χ²_ν, where the delta method's 2/ν is 40 % low at ν = 2) and the
correlations of the octaves are those of the exact covariance ``V(θ)`` of the Allan variances
(:mod:`calib.noise.allan_model`): ``Σ = D R D``. The twin's parameters were fitted to this very
log, which pulls the log's curve towards the model: to first order
``log s − log μ(θ̂) = (I − H) e`` with the GLS hat of the model in relative units
``H = diag(1/μ) X_kept G_kept diag(μ_f) S_f``, ``G = Cov(θ̂) X_fᵀ V_ff⁻¹`` (only the terms the
twin keeps: an unresolved term is left out of the profile, so its estimate does not move the
twin), so

    Σ_u = (I − H) Σ (I − H)ᵀ + Σ'      (Σ' the twin's own, at its θ)

Leaving H out would make the test conservative (its size about half of α on 12 octaves).

**Inside the model's τ range.** When the model describes only part of the grid (a narrower τ
range chosen by the fit's rule, :mod:`calib.noise.allan_fit`), the twin cannot follow the log
outside it (a decimation filter, a feature no term has): the same statistic is also computed
on the octaves of the model's range alone — ``u_r`` and the sub-block ``Σ_u,rr`` of the same
covariance, ``T_r ~ χ²_{k_r}`` under the same hypothesis — and reported beside the joint test
(``model_range``), which stays the verdict; the summary says when every octave where they part
lies outside the model's range.

**A shaped log** (an export's low-pass filter, :mod:`calib.noise.shaping`). The twin filters
with the filter read from this log, so the two curves also differ by that estimate's error:
at short τ, where the filter shapes the curve, the octaves move nearly as one and a 1 %
error in the filter's passband is many of their joint standard deviations. Its covariance,
``Σ_f`` of the log white Allan variance over re-estimates of the filter
(:func:`calib.noise.shaping.shaping_spread`: a seeded parametric bootstrap), weighted by each
octave's white share ``w_i = θ_w·X_iw / μ_i``, is added: ``Σ_u + diag(w) Σ_f diag(w)``.

**Where they part.** Per octave ``z_i = u_i / √Σ_u,ii``; octaves with ``|z_i|`` above the
Šidák bound of the family, ``Φ⁻¹(1 − (1 − (1 − α)^{1/k})/2)``, are named (the twin's ADEV
against the log's, and which is higher); when the joint test rejects but no single octave
crosses that bound, the octave of largest |z| is named.

**Logs with gaps.** A log characterized from segments (:mod:`calib.noise.allan`: Logs with
gaps) is compared with a twin of the same segment lengths: each segment simulated as its own
record (the model's independent records), averaged in the same blocks, its Allan variance
pooled the same way (:func:`calib.noise.allan.pooled_adev`), and the moments those of the
pooled estimator (:func:`calib.noise.allan_model.record_moments`).

Size and power are measured in ``tests/test_twin_closure.py`` on logs made by a generator
written apart from the bench (``validation/noise_independent``): rejection of a true twin at
≈ α (binomial band), of a twin 1.5× noisier in nearly every log.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special, stats

from calib.input_rules import DataError
from calib.noise.allan import overlapping_adev, pooled_adev
from calib.noise.allan_fit import LADDER, Engine, Model
from calib.noise.allan_model import ALL_TERM_NAMES, edf, record_moments, supported_octaves
from calib.results import ResultMixin, readonly

CLOSURE_ALPHA = 0.05
"""Family α of the twin-closure test: the probability that a true twin is rejected."""


@dataclass(frozen=True, eq=False)
class Closure(ResultMixin):
    """The twin-closure test of one axis (module docstring).

    axis : the axis name.
    taus (k,) s; adev, twin_adev (k,) in the reading's unit; z (k,) per-octave standardized
    differences (positive: the log above the twin); statistic T, dof k, p; alpha; reject;
    parted : indices of the octaves named as where the twin and the log part.
    range_octaves : (lo, hi) the model's octaves (``taus[lo:hi]``); range_statistic,
    range_p : the same test on them alone (module docstring: Inside the model's τ range).
    """

    axis: str
    taus: np.ndarray
    adev: np.ndarray
    twin_adev: np.ndarray
    z: np.ndarray
    statistic: float
    dof: int
    p: float
    alpha: float
    reject: bool
    parted: tuple[int, ...]
    range_octaves: tuple[int, int] = (0, 0)
    range_statistic: float = float("nan")
    range_p: float = float("nan")

    _TITLE = "Twin closure"
    _UNITS = "τ s; ADEV in the reading unit"

    def __post_init__(self) -> None:
        for name in ("taus", "adev", "twin_adev", "z"):
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "parted", tuple(int(i) for i in self.parted))
        object.__setattr__(self, "range_octaves", tuple(int(i) for i in self.range_octaves))

    @property
    def partial_range(self) -> bool:
        """The model describes only part of the grid's octaves."""
        lo, hi = self.range_octaves
        return hi > lo and (lo > 0 or hi < self.taus.size)

    @property
    def range_reject(self) -> bool:
        """The test on the model's octaves alone rejects at α."""
        return bool(self.range_p < self.alpha)

    def summary(self) -> str:
        head = (f"twin closure, axis {self.axis}: T = {self.statistic:.1f} on {self.dof} "
                f"octaves, p = {self.p:.2g} at family α = {self.alpha:g}: ")
        if not self.reject:
            return head + "the twin's Allan deviation matches the log's (not rejected)"
        parts = []
        for i in self.parted:
            side = "above" if self.z[i] < 0 else "below"
            parts.append(f"τ = {self.taus[i]:.3g} s (twin {self.twin_adev[i]:.3g} {side} the "
                         f"log's {self.adev[i]:.3g}, z = {self.z[i]:+.1f})")
        out = head + "REJECTED — the twin parts from the log at " + "; ".join(parts)
        if self.partial_range:
            lo, hi = self.range_octaves
            inside = [i for i in self.parted if lo <= i < hi]
            where = ("every one outside" if not inside else "some inside")
            out += (f" — {where} the model's τ range {self.taus[lo]:.3g}–"
                    f"{self.taus[hi - 1]:.3g} s (the profile does not describe the others); "
                    f"on that range alone T = {self.range_statistic:.1f} on {hi - lo} octaves, "
                    f"p = {self.range_p:.2g}: "
                    + ("rejected" if self.range_reject else "not rejected"))
        return out

    def to_dict(self) -> dict:
        return {"axis": self.axis, "taus": self.taus.tolist(), "adev": self.adev.tolist(),
                "twin_adev": self.twin_adev.tolist(), "z": self.z.tolist(),
                "statistic": float(self.statistic), "dof": int(self.dof), "p": float(self.p),
                "alpha": float(self.alpha), "reject": bool(self.reject),
                "parted": list(self.parted),
                "model_range": {"octaves": list(self.range_octaves),
                                "statistic": float(self.range_statistic),
                                "dof": int(self.range_octaves[1] - self.range_octaves[0]),
                                "p": float(self.range_p), "reject": self.range_reject}}

    @classmethod
    def from_dict(cls, d: dict) -> Closure:
        return cls(axis=d["axis"], taus=d["taus"], adev=d["adev"], twin_adev=d["twin_adev"],
                   z=d["z"], statistic=float(d["statistic"]), dof=int(d["dof"]),
                   p=float(d["p"]), alpha=float(d["alpha"]), reject=bool(d["reject"]),
                   parted=tuple(d["parted"]),
                   range_octaves=tuple(d["model_range"]["octaves"]),
                   range_statistic=float(d["model_range"]["statistic"]),
                   range_p=float(d["model_range"]["p"]))


def _model_of(fit) -> tuple[Model, np.ndarray]:
    """The fit's :class:`Model` (terms, GM grid index, octaves) and the θ the twin keeps (the
    resolved terms; white always)."""
    names = [t.name for t in fit.terms]
    active = tuple(sorted(ALL_TERM_NAMES.index(n) for n in names))
    active = next(a for a in LADDER if set(a) == set(active))
    g = None
    mom = record_moments(fit.fit_lengths, fit.ms, fit.shaping)
    gm = fit.term("gauss_markov")
    if gm is not None:
        rate = fit.ms[0] / fit.taus[0]
        g = int(np.argmin(np.abs(mom.gm_tc - gm.correlation_time * rate)))
    keep = np.zeros(len(ALL_TERM_NAMES), bool)
    for t in fit.terms:
        keep[ALL_TERM_NAMES.index(t.name)] = t.resolved or t.name == "white_noise_density"
    theta_twin = np.where(keep, np.maximum(np.asarray(fit.theta, float), 0.0), 0.0)
    return Model(active, g, fit.octaves[0], fit.octaves[1]), theta_twin


def closure_test(fit, twin_adev: np.ndarray, alpha: float = CLOSURE_ALPHA) -> Closure:
    """The joint test of the module docstring.

    Parameters
    ----------
    fit : the log's :class:`calib.noise.allan.AxisNoise`.
    twin_adev : (k,) the twin's overlapping ADEV at the same τ (same block means), reading unit.
    alpha : family α.
    """
    model, theta_twin = _model_of(fit)
    mom = record_moments(fit.fit_lengths, fit.ms, fit.shaping)
    design, tensor = mom.full(model.g)
    s = np.asarray(fit.adev, float) ** 2
    t = np.asarray(twin_adev, float) ** 2
    k = s.size
    theta = np.asarray(fit.theta, float)
    floor = 1e-12 * s[0] / design[0, 0]
    engine = Engine(s, mom, floor)
    th = engine.valid(theta)
    tht = engine.valid(theta_twin)
    mu = design @ th
    v = np.einsum("a,ijab,b->ij", th, tensor, th)
    v_t = np.einsum("a,ijab,b->ij", tht, tensor, tht)
    nu, nu_t = edf(design, tensor, th), edf(design, tensor, tht)

    def log_cov(cov, nus):
        sd = np.sqrt(np.diag(cov))
        corr = cov / np.outer(sd, sd)
        d = np.sqrt(special.polygamma(1, nus / 2.0))
        return corr * np.outer(d, d)

    sig, sig_t = log_cov(v, nu), log_cov(v_t, nu_t)
    # a shaped log: the spread of its filter's estimate (relative; module docstring)
    spread = np.zeros((k, k))
    if fit.export_filter is not None:
        from calib.noise.shaping import shaping_spread

        spread = shaping_spread(fit.export_filter, fit.n, fit.ms, fit.block)
    white = design[:, 0] * th[0]  # the white noise's part of each octave
    # the GLS hat of the kept terms, in relative units (module docstring)
    lo, hi = model.lo, model.hi
    act = list(model.active)
    xf = design[lo:hi][:, act]
    vff = v[lo:hi, lo:hi]
    cov_theta = np.asarray(fit.cov, float)
    # (Cov θ) Xᵀ V⁻¹ as a solve (V symmetric): ((V⁻¹ X)(Cov θ))ᵀ, no inverted matrix
    gain = (np.linalg.solve(vff, xf) @ cov_theta.T).T  # (p, k_f)
    kept = [i for i, a in enumerate(act) if theta_twin[a] > 0 or a == 0]
    h = np.zeros((k, k))
    h[:, lo:hi] = (design[:, [act[i] for i in kept]] @ gain[kept]) * mu[lo:hi][None, :]
    h /= mu[:, None]
    a = np.eye(k) - h
    share = white / mu  # the filter read from this log (module docstring: A shaped log)
    cov_u = a @ sig @ a.T + sig_t + share[:, None] * spread * share[None, :]

    def bias(x):
        return special.digamma(x / 2.0) - np.log(x / 2.0)

    u = np.log(s) - np.log(t) - (bias(nu) - bias(nu_t))
    stat = float(u @ np.linalg.solve(cov_u, u))
    p = float(stats.chi2.sf(stat, k))
    z = u / np.sqrt(np.diag(cov_u))
    reject = p < alpha
    crit = stats.norm.ppf(1.0 - (1.0 - (1.0 - alpha) ** (1.0 / k)) / 2.0)
    parted = tuple(int(i) for i in np.nonzero(np.abs(z) > crit)[0])
    if reject and not parted:
        parted = (int(np.argmax(np.abs(z))),)
    r = slice(lo, hi)  # the model's octaves alone: the sub-block of the same covariance
    stat_r = float(u[r] @ np.linalg.solve(cov_u[r, r], u[r]))
    return Closure(axis=fit.axis, taus=fit.taus, adev=fit.adev, twin_adev=twin_adev, z=z,
                   statistic=stat, dof=k, p=p, alpha=alpha, reject=bool(reject),
                   parted=parted if reject else (), range_octaves=(lo, hi),
                   range_statistic=stat_r, range_p=float(stats.chi2.sf(stat_r, hi - lo)))


def twin_adev(fit, y, rate: float) -> np.ndarray:
    """(k,) the overlapping ADEV of a twin's readings on the log's grid: the same block means
    and octaves. ``y``: (N,) at ``rate`` Hz, as many as the log's (one record, N/n_fit samples
    per block), or a list of arrays, one per segment of a log with gaps (the log's segment
    lengths, in order: block means per segment, the Allan variance pooled over the segments
    that hold the first octave, as :func:`calib.noise.allan.fit_axis_noise` did)."""
    if isinstance(y, (list, tuple)):
        block = max(1, int(round(rate * float(fit.taus[0]) / fit.ms[0])))
        pieces = [np.asarray(p, dtype=float) for p in y]
        pieces = [p if block == 1 else p[:p.size // block * block].reshape(-1, block).mean(axis=1)
                  for p in pieces]
        used = [p for p in pieces if supported_octaves(p.size, fit.ms)]
        if tuple(p.size for p in used) != fit.fit_lengths:
            raise DataError(f"axis {fit.axis}: the twin's segments hold "
                            f"{[p.size for p in used]} samples after block means, the log's "
                            f"{list(fit.fit_lengths)}: simulate the twin with the log's "
                            "segment lengths")
        return pooled_adev(used, rate / block, fit.ms)[1]
    y = np.asarray(y, dtype=float)
    block = max(1, y.size // fit.n_fit)
    yb = y if block == 1 else y[:fit.n_fit * block].reshape(-1, block).mean(axis=1)
    return overlapping_adev(yb, rate / block, fit.ms)[1]


__all__ = ["CLOSURE_ALPHA", "Closure", "closure_test", "twin_adev"]
