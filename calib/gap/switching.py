"""Two-level switching of the bias (random telegraph noise) on a path, by its likelihood.

A bias that flips between two levels at random times (a bistable contact, defect or supply)
is faint when its levels are a fraction of σ apart: the change-point search of
:mod:`calib.gap.steps` finds a switch only where it alone passes the Bonferroni threshold, so a
faint telegraph is found as one or two steps, or none, and a random walk follows it better.
This module scores the switching as a whole instead: the likelihood of a two-state hidden
Markov level, every switching history integrated out (no place is searched, so nothing is
charged for places), which the walk review (:func:`calib.gap.walk.switching_drift`) sets
against the random walk's on the same path.

Model (the path ``e_k``, m/s², with white noise of known variance σ²)
--------------------------------------------------------------------
    e_k = μ_{s_k} + v_k,   v_k ~ N(0, σ²),   s_k ∈ {0, 1} a Markov chain:
    P(s_k = 1 | s_{k−1} = 0) = p₀₁,  P(s_k = 0 | s_{k−1} = 1) = p₁₀ (per sample),
    s_0 from the chain's stationary law (p₁₀, p₀₁)/(p₀₁ + p₁₀).

Four parameters (μ₀, μ₁, p₀₁, p₁₀) against one (the mean) of white noise: three charged.
``-2 log L = −2 log(π B₁ Π_{k≥2} P B_k 1)`` with ``B_k = diag(exp(−(e_k − μ_j)²/2σ²))``
(Rabiner, *Proc. IEEE* 77, 1989, eq. 19–21) up to the terms every model of the path shares,
so ``LR = Σ(e − ē)²/σ² − (−2 log L)`` is the gain over one level.

How it is computed
------------------
The forward recursion is a product of N 2 × 2 matrices ``M_k = P B_k``; it is evaluated as a
tree of batched products (pairs multiplied at once, each product rescaled by its largest entry
and the scale kept in logs), log₂ N numpy steps instead of an N-step Python loop. The
parameters are found by Nelder–Mead (scipy) from the better of two starts (the two levels of
a smoothed path at two widths). The switching history shown in words is the Viterbi path (Rabiner
eq. 30–35).

A path longer than :data:`MAX_POINTS` is first averaged in blocks of m samples (noise σ²/m):
the switches then fall on block edges; :func:`calib.gap.walk.switching_drift` averages the
walk's path the same way.

Why by hand: scipy has no hidden Markov model; hmmlearn would be a compiled dependency for a
two-state chain whose likelihood is a dozen lines, and it re-estimates the noise variance,
which is known here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from calib.gap.steps import StepFit

MAX_POINTS = 8000
"""Longest path fitted sample by sample; a longer one is averaged in blocks to at most this."""

SWITCH_CHARGE = 3.0
"""Parameters charged to two-level switching beyond one level: a second level and the two
switching rates (its places are integrated out, not searched)."""

_STARTS = (100, 25)
"""Smoothing windows of the starts, as fractions 1/w of the path (two levels of each)."""

_P_MIN = 1e-9
"""Smallest switching probability per point a start uses (a chain that never switches)."""


def block_means(e: np.ndarray, m: int) -> np.ndarray:
    """Means of consecutive blocks of ``m`` samples (the last, shorter block dropped when
    m > 1 and it is incomplete)."""
    e = np.asarray(e, dtype=float)
    if m <= 1:
        return e
    nb = e.size // m
    return e[:nb * m].reshape(nb, m).mean(axis=1)


def block_size(n: int) -> int:
    """Samples per point so that at most :data:`MAX_POINTS` points remain."""
    return max(1, -(-n // MAX_POINTS))


def two_level_m2ll(e: np.ndarray, sigma2: float, mu: tuple[float, float],
                   p01: float, p10: float) -> float:
    """``-2 log L`` of the two-level Markov model (module docstring; levels ``mu`` m/s²,
    switch probabilities per point 0 < p₀₁, p₁₀ < 1), without the terms shared by every model
    of the path (``N log 2πσ²``): white noise about one level μ gives ``Σ(e − μ)²/σ²`` on the
    same scale."""
    e = np.asarray(e, dtype=float)
    d = np.empty((e.size, 2))
    d[:, 0] = (e - mu[0]) ** 2
    d[:, 1] = (e - mu[1]) ** 2
    d *= 0.5 / sigma2
    dmin = d.min(axis=1)
    b = np.exp(dmin[:, None] - d)  # B_k / exp(−dmin_k): entries in (0, 1], one of them 1
    log_scale = -float(dmin.sum())
    trans = np.array([[1.0 - p01, p01], [p10, 1.0 - p10]])
    v = np.array([p10, p01]) / (p01 + p10) * b[0]
    mats = trans[None, :, :] * b[1:, None, :]  # M_k = P B_k
    while mats.shape[0] > 1:
        if mats.shape[0] % 2:  # fold the odd one into the row vector
            v = v @ mats[0]
            mats = mats[1:]
        mats = np.matmul(mats[0::2], mats[1::2])
        s = mats.max(axis=(1, 2))
        mats /= s[:, None, None]
        log_scale += float(np.log(s).sum())
    if mats.shape[0]:
        v = v @ mats[0]
    return -2.0 * (float(np.log(v.sum())) + log_scale)


def viterbi(e: np.ndarray, sigma2: float, mu: tuple[float, float], p01: float, p10: float
            ) -> np.ndarray:
    """The most probable state path (0/1 per point) of the two-level model."""
    e = np.asarray(e, dtype=float)
    n = e.size
    ll = np.column_stack([-(e - mu[0]) ** 2, -(e - mu[1]) ** 2]) * (0.5 / sigma2)
    lt = np.log(np.array([[1.0 - p01, p01], [p10, 1.0 - p10]]))
    delta = np.log(np.array([p10, p01]) / (p01 + p10)) + ll[0]
    back = np.zeros((n, 2), dtype=np.int8)
    t00, t01, t10, t11 = (float(x) for x in lt.ravel())
    d0, d1 = float(delta[0]), float(delta[1])
    l0, l1 = ll[:, 0].tolist(), ll[:, 1].tolist()
    for k in range(1, n):  # two states: plain floats beat numpy's per-call cost here
        a, b = d0 + t00, d1 + t10
        c, d = d0 + t01, d1 + t11
        back[k, 0], back[k, 1] = (a < b), (c < d)
        d0, d1 = max(a, b) + l0[k], max(c, d) + l1[k]
    states = np.empty(n, dtype=np.int8)
    states[-1] = int(d1 > d0)
    for k in range(n - 1, 0, -1):
        states[k - 1] = back[k, states[k]]
    return states


@dataclass(frozen=True)
class SwitchingFit:
    """Two-level switching fitted to a path.

    levels : (μ₀, μ₁), m/s², μ₀ < μ₁.  rates : (p₀₁, p₁₀) per sample.  lr : gain in
    ``-2 log L`` over one level.  states : (N,) 0/1 per sample (Viterbi, block-resolved).
    block : samples per point of the fit.  sigma : the noise std, m/s².
    """

    levels: tuple[float, float]
    rates: tuple[float, float]
    lr: float
    states: np.ndarray
    block: int
    sigma: float

    @property
    def switches(self) -> int:
        return int(np.count_nonzero(np.diff(self.states)))

    def step_fit(self) -> StepFit:
        """The decoded path as steps (:class:`calib.gap.steps.StepFit`): a step at every
        switch, each segment at its state's level."""
        n = self.states.size
        places = np.flatnonzero(np.diff(self.states)) + 1
        seg_state = self.states[np.r_[0, places]].astype(int)
        levels = np.asarray(self.levels)[seg_state]
        return StepFit(places.astype(int), levels, np.diff(levels), float(self.lr),
                       float(self.sigma), n)


def _starts(e: np.ndarray) -> list[np.ndarray]:
    """Starting points (μ₀, μ₁, logit p₀₁, logit p₁₀): the lower and upper fifths of the path
    smoothed over N/w points, and its crossings of their mid-level as the switch rate."""
    out = []
    n = e.size
    for w in _STARTS:
        width = max(3, n // w)
        sm = np.convolve(e, np.ones(width) / width, mode="valid")
        lo, hi = np.percentile(sm, [20.0, 80.0])
        if not hi > lo:
            continue
        cross = np.count_nonzero(np.diff(sm > 0.5 * (lo + hi)))
        p = float(np.clip((cross + 1) / n, _P_MIN, 0.25))
        out.append(np.array([lo, hi, np.log(p / (1 - p)), np.log(p / (1 - p))]))
    return out


def fit_switching(e: np.ndarray, sigma2: float) -> SwitchingFit | None:
    """ML two-level switching of path ``e`` (m/s²; noise variance σ², (m/s²)²), or None when the
    path is too short or flat (module docstring)."""
    e = np.asarray(e, dtype=float)
    n = e.size
    if n < 40 or not np.all(np.isfinite(e)):
        return None
    m = block_size(n)
    eb = block_means(e, m)
    s2 = float(sigma2) / m
    white = float(np.sum((eb - eb.mean()) ** 2) / s2)

    def m2ll(x: np.ndarray) -> float:
        p01, p10 = 1.0 / (1.0 + np.exp(-x[2])), 1.0 / (1.0 + np.exp(-x[3]))
        val = two_level_m2ll(eb, s2, (float(x[0]), float(x[1])), p01, p10)
        return val if np.isfinite(val) else np.inf

    starts = _starts(eb)
    if not starts:
        return None
    # from the better start only: on 40 walks and telegraphs the second start's optimum was
    # the same to 0.01 in LR, at 2.5 times the cost
    best = optimize.minimize(m2ll, min(starts, key=m2ll), method="Nelder-Mead",
                             options={"xatol": 1e-3, "fatol": 1e-2, "maxiter": 1500})
    if not np.isfinite(best.fun):
        return None
    mu0, mu1 = float(best.x[0]), float(best.x[1])
    p01, p10 = (float(1.0 / (1.0 + np.exp(-v))) for v in best.x[2:])
    if mu0 > mu1:  # name the lower level 0
        mu0, mu1, p01, p10 = mu1, mu0, p10, p01
    states = np.repeat(viterbi(eb, s2, (mu0, mu1), p01, p10), m)
    if states.size < n:  # the incomplete last block keeps the last state
        states = np.r_[states, np.full(n - states.size, states[-1] if states.size else 0)]
    return SwitchingFit((mu0, mu1), (p01 / m, p10 / m), max(white - float(best.fun), 0.0),
                        states.astype(np.int8), m, float(np.sqrt(sigma2)))
