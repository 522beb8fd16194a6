"""Step-like changes of the bias: one step, a staircase, two-level switching — in words.

A bias that jumps (a loose connector, a supply that switches, a relay, random telegraph
noise of a bistable defect) is not a random walk and not 1/f noise: it is piecewise
constant. This module finds the steps of a path and says what they look like: the battery's
``step`` check (:mod:`calib.gap.adequacy`) finds them at a family level for its words
(:func:`find_steps`, below), the walk review (:mod:`calib.gap.walk`) at the charge its
comparison with the walk makes (:func:`optimal_steps`, the exact optimum).

Change points (binary segmentation, known noise)
------------------------------------------------
The path ``e_k = b_k + v_k`` (m/s²; v white with the model's variance σ²) is split where a
step of the level explains most: on a segment ``[a, b)`` with sums ``S_i = Σ_{a≤j<i} e_j``
the split at i gains

    LR(i) = (S_i − (i − a)/(b − a)·S_b)² / (σ²·(i − a)(b − i)/(b − a))

in ``-2 log L`` (the likelihood ratio of two levels against one, σ² known), exactly χ²(1) at
a fixed i without a step. The best split of the segment with the largest gain is kept while
that gain exceeds :func:`step_threshold` — the χ²(1) quantile at ``STEP_ALPHA / N``
(Bonferroni over the N places) — up to :data:`MAX_STEPS` steps. Sample times are not needed
(places are reported in s with timing, in samples without).

The shape in words (:func:`describe`)
-------------------------------------
Levels ``μ_0 … μ_K`` of the K + 1 segments (means), steps ``d_j = μ_j − μ_{j−1}``:

* K = 1 — "a step of +0.5 m/s² (1 σ) at t = 17.1 s";
* two levels — the steps alternate in sign and every level lies within
  :data:`TWO_LEVEL_SPREAD` of the gap between the two groups of levels (split at the largest
  gap of the sorted levels) or within 3 standard errors of its group's mean: "the bias
  switches between two levels 0.3 m/s² (0.6 σ) apart: 9 switches, 47 % of the time at the
  upper level, dwelling 4.1 s on average (random telegraph noise …)";
* a staircase — every step has the same sign: "a staircase of 3 steps of about +0.5 m/s²
  each (+1.5 m/s² in all) at t = 12 s, 22 s, 32 s";
* otherwise — "K steps of the bias: +0.3 m/s² at t = …, −0.5 m/s² at …".

Why by hand: no numpy/scipy routine segments a mean with known variance; the recursion is a
few lines (Scott & Knott 1974; Killick & Eckley's ``changepoint`` R package does the same).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtri

STEP_ALPHA = 0.01
"""Family level of the change-point search: a split is kept when its χ²(1) gain passes
``STEP_ALPHA / N`` (Bonferroni over the N places). On white noise of N = 4001 the threshold
is LR ≈ 22.3; a step of size d between two stretches of n₁, n₂ samples gains
``d²/σ²·n₁n₂/(n₁ + n₂)`` (0.5 σ over 200 samples each side: 25)."""

MAX_STEPS = 24
"""Most steps looked for (a longer telegraph record is described by its first 24)."""

MIN_SEGMENT = 5
"""Fewest samples on each side of a split."""

MIN_SWITCHES = 3
"""Fewest alternating steps called two-level switching (two steps are a pulse)."""

TWO_LEVEL_SPREAD = 0.25
"""Two-level switching: every segment level within this fraction of the gap between the two
groups of levels (or within 3 standard errors of its group's mean, for short segments)."""


def _scales(n: int) -> list[int]:
    """Lengths of the seeded intervals: n, n/2, n/4, … down to ``4·MIN_SEGMENT``."""
    out, length = [], n
    while length >= 4 * MIN_SEGMENT:
        out.append(int(length))
        length //= 2
    return out or [n]


def step_threshold(n: int) -> float:
    """χ²(1) quantile at ``STEP_ALPHA / (n·J)``, J the number of interval lengths searched:
    the smallest gain of a kept step (Bonferroni over the places and the lengths)."""
    z = float(-ndtri(0.5 * STEP_ALPHA / (max(n, 1) * len(_scales(max(n, 1))))))
    return z * z


@dataclass(frozen=True)
class StepFit:
    """The steps found on a path.

    places : (K,) index of the first sample after each step (sorted).
    levels : (K + 1,) mean of each segment, m/s².  sizes : (K,) the steps ``μ_j − μ_{j−1}``.
    lr : total gain in ``-2 log L`` (σ² known) of the K steps over one level.
    sigma : the noise std the path was segmented with, m/s².
    """

    places: np.ndarray
    levels: np.ndarray
    sizes: np.ndarray
    lr: float
    sigma: float
    n: int = 0

    @property
    def count(self) -> int:
        return int(self.places.size)

    @property
    def lengths(self) -> np.ndarray:
        """(K + 1,) samples in each segment."""
        return np.diff(np.concatenate([[0], self.places, [self.n]]))

    def columns(self, n: int) -> np.ndarray:
        """(n, K) step columns ``[k ≥ place_j]`` (zero width when K = 0)."""
        k = np.arange(n)[:, None]
        return (k >= self.places[None, :]).astype(float)


def _seed_splits(cs: np.ndarray, sigma2: float) -> tuple[np.ndarray, ...]:
    """Best split of every seeded interval: (start, stop, place, gain) arrays.

    Intervals of each length L of :func:`_scales`, starting every L/2 (the last flush with
    the end), so every step has an interval around it that holds no other step of a longer
    spacing; all intervals of one length are scanned at once."""
    n = cs.size - 1
    starts, stops, places, gains = [], [], [], []
    for length in _scales(n):
        a = np.unique(np.r_[np.arange(0, n - length + 1, max(length // 2, 1)), n - length])
        i = np.arange(MIN_SEGMENT, length - MIN_SEGMENT + 1)
        frac = i / length
        total = cs[a + length] - cs[a]
        dev = (cs[a[:, None] + i[None, :]] - cs[a][:, None]) - frac[None, :] * total[:, None]
        lr = dev * dev / (sigma2 * i * (length - i) / length)[None, :]
        j = np.argmax(lr, axis=1)
        starts.append(a)
        stops.append(a + length)
        places.append(a + i[j])
        gains.append(lr[np.arange(a.size), j])
    return tuple(np.concatenate(x) for x in (starts, stops, places, gains))


def _segment_gains(cs: np.ndarray, bounds: np.ndarray, sigma2: float) -> np.ndarray:
    """Gain of each inner boundary against merging its two neighbouring segments."""
    a, b, c = bounds[:-2], bounds[1:-1], bounds[2:]
    m1, m2 = (cs[b] - cs[a]) / (b - a), (cs[c] - cs[b]) / (c - b)
    return (m1 - m2) ** 2 * ((b - a) * (c - b) / (c - a)) / sigma2


def find_steps(e: np.ndarray, sigma2: float, max_steps: int = MAX_STEPS) -> StepFit:
    """Steps of the level of ``e`` (m/s²), noise variance σ² ((m/s²)²).

    Seeded binary segmentation with the narrowest-over-threshold choice (Kovács et al.,
    *Biometrika* 2023; Baranowski, Chen & Fryzlewicz, *JRSS-B* 2019): the best split of every
    seeded interval (:func:`_seed_splits`); while some interval's gain exceeds
    :func:`step_threshold`, the **narrowest** such interval gives a step and every interval
    that holds it is dropped (a wide interval around several alternating steps sees their
    average, a narrow one sees one step: so two-level switching is found where plain binary
    segmentation is not). Then steps whose gain against merging their two neighbouring
    segments falls below the threshold are removed, weakest first."""
    e = np.asarray(e, dtype=float)
    n = e.size
    sigma2 = float(sigma2)
    cs = np.concatenate([[0.0], np.cumsum(e)])
    empty = StepFit(np.zeros(0, dtype=int), np.array([e.mean()]) if n else np.zeros(1),
                    np.zeros(0), 0.0, float(np.sqrt(sigma2)), n)
    if n < 4 * MIN_SEGMENT:
        return empty
    thr = step_threshold(n)
    lo, hi, place, gain = _seed_splits(cs, sigma2)
    keep = gain > thr
    lo, hi, place, gain = lo[keep], hi[keep], place[keep], gain[keep]
    chosen: list[int] = []
    while lo.size and len(chosen) < 4 * max_steps:
        j = int(np.lexsort((-gain, hi - lo))[0])  # narrowest, then strongest
        p = int(place[j])
        chosen.append(p)
        out = (lo < p) & (hi > p)
        lo, hi, place, gain = lo[~out], hi[~out], place[~out], gain[~out]
    bounds = np.array(sorted({0, n, *chosen}))
    while bounds.size > 2:
        g = _segment_gains(cs, bounds, sigma2)
        worst = int(np.argmin(g))
        if g[worst] > thr and bounds.size - 2 <= max_steps:
            break
        bounds = np.delete(bounds, worst + 1)
    levels = np.diff(cs[bounds]) / np.diff(bounds)
    resid0 = float(np.sum((e - e.mean()) ** 2))
    seg = np.repeat(levels, np.diff(bounds))
    lr = (resid0 - float(np.sum((e - seg) ** 2))) / sigma2
    return StepFit(bounds[1:-1].astype(int), levels, np.diff(levels), float(lr),
                   float(np.sqrt(sigma2)), n)


MAX_DP_POINTS = 6000
"""Most points of :func:`optimal_steps`' exact search (its cost grows as the square of the
points on a path without steps); a longer path is searched on block means."""


def optimal_steps(e: np.ndarray, sigma2: float, penalty: float) -> StepFit:
    """The steps of the level of ``e`` (m/s²; noise variance σ², (m/s²)²) that maximise the
    penalised gain ``LR_K − penalty·K`` exactly.

    ``LR_K`` is the χ² gain (σ² known) of K steps over one level, ``Σ(e − ē)²/σ² −
    Σ(e − μ_seg)²/σ²``. Optimal partitioning (Jackson et al., *IEEE SPL* 2005) with PELT's
    pruning (Killick, Fearnhead & Eckley, *JASA* 2012):

        F(t) = min_s [F(s) − (S_t − S_s)²/((t − s)·σ²)] + penalty,   F(0) = −penalty,

    S the cumulative sums, segments of at least :data:`MIN_SEGMENT` samples; an s whose
    ``F(s) + C(s, t)`` exceeds F(t) can never start the last segment again and is dropped.
    Where binary segmentation (:func:`find_steps`) stops at a Bonferroni threshold and places
    each step greedily (two close steps merge into one, a missed step leaves a ramp), this
    is the segmentation a penalised comparison with another model asks for: the walk review
    charges each step its size and place (``penalty = 2·(1 + ln N)``,
    :func:`calib.gap.walk.step_charge`). A path of more than :data:`MAX_DP_POINTS` samples is
    searched on block means (places at block edges).

    Why by hand: neither numpy nor scipy segments a mean; the recursion is a dozen lines.
    """
    e = np.asarray(e, dtype=float)
    n = e.size
    sigma2 = float(sigma2)
    if n < 2 * MIN_SEGMENT:
        return StepFit(np.zeros(0, dtype=int), np.array([e.mean()]) if n else np.zeros(1),
                       np.zeros(0), 0.0, float(np.sqrt(sigma2)), n)
    m = max(1, -(-n // MAX_DP_POINTS))
    edges = np.r_[np.arange(0, n, m), n]  # sample index of each point's start, and n
    csum = np.concatenate([[0.0], np.cumsum(e)])
    cs = csum[edges]  # S at the point edges
    cw = edges.astype(float)  # samples before each edge
    npts = edges.size - 1
    seg = max(1, -(-MIN_SEGMENT // m))  # fewest points a segment holds
    f = np.full(npts + 1, np.inf)
    f[0] = -penalty
    last = np.zeros(npts + 1, dtype=int)
    cand = np.zeros(0, dtype=int)
    for t in range(seg, npts + 1):
        if t - seg == 0 or t - seg >= seg:
            cand = np.append(cand, t - seg)
        d = cs[t] - cs[cand]
        cost = f[cand] - d * d / ((cw[t] - cw[cand]) * sigma2)
        j = int(np.argmin(cost))
        f[t] = cost[j] + penalty
        last[t] = cand[j]
        cand = cand[cost <= f[t]]  # PELT: the others never win again
    bounds = [npts]
    while bounds[-1] > 0:
        bounds.append(int(last[bounds[-1]]))
    bounds = edges[np.array(bounds[::-1])]
    levels = np.diff(csum[bounds]) / np.diff(bounds)
    fitted = np.repeat(levels, np.diff(bounds))
    lr = (float(np.sum((e - e.mean()) ** 2)) - float(np.sum((e - fitted) ** 2))) / sigma2
    return StepFit(bounds[1:-1].astype(int), levels, np.diff(levels), float(lr),
                   float(np.sqrt(sigma2)), n)


def _where(tcol: np.ndarray, time_unit: str, i: int) -> str:
    return f"t = {tcol[i]:.4g} s" if time_unit == "s" else f"sample {i}"


def _at(tcol: np.ndarray, time_unit: str, i: int) -> str:
    return f"{tcol[i]:.4g} s" if time_unit == "s" else f"{i}"


def _two_level(fit: StepFit, lengths: np.ndarray) -> tuple[float, float, np.ndarray] | None:
    """(low level, high level, which segments are high) when the levels form two groups."""
    if fit.count < 2 or np.any(np.sign(fit.sizes[1:]) == np.sign(fit.sizes[:-1])):
        return None
    order = np.sort(fit.levels)
    cut = int(np.argmax(np.diff(order)))
    split = 0.5 * (order[cut] + order[cut + 1])
    high = fit.levels > split
    if high.all() or not high.any():
        return None
    lo, hi = float(fit.levels[~high].mean()), float(fit.levels[high].mean())
    gap = hi - lo
    se = 3.0 * fit.sigma / np.sqrt(lengths)
    dev = np.abs(fit.levels - np.where(high, hi, lo))
    if np.any(dev > np.maximum(TWO_LEVEL_SPREAD * gap, se)):
        return None
    return lo, hi, high


def two_level(fit: StepFit) -> bool:
    """Whether the steps switch between two levels (module docstring): at least
    :data:`MIN_SWITCHES` steps alternating in sign, every level near its group's."""
    return fit.count >= MIN_SWITCHES and _two_level(fit, fit.lengths) is not None


MIN_STAIRCASE = 3
"""Fewest steps of one sign that :func:`walk_unlike` counts as a staircase."""


def walk_unlike(fit: StepFit) -> bool:
    """Whether the steps have a shape a random walk has no reason to make: at least
    :data:`MIN_STAIRCASE` steps all of one sign (a staircase), or two-level switching
    (:func:`two_level`). A walk's path cut into steps mostly gives one or two, or steps of both
    signs that do not return to two levels (the validation set's true walks, 8–20 σ: the four
    that came near their steps had 1, 2, and 3 of mixed signs twice)."""
    return (fit.count >= MIN_STAIRCASE and _one_sign(fit.sizes)) or two_level(fit)


def _one_sign(sizes: np.ndarray) -> bool:
    """Every step of the same sign (a staircase, in :func:`describe`'s words)."""
    return bool(np.all(np.sign(sizes) == np.sign(sizes[0])))


def describe(fit: StepFit, tcol: np.ndarray, time_unit: str, axis: str) -> str:
    """The steps in words (module docstring); "" when there is none."""
    k = fit.count
    if k == 0:
        return ""
    s = fit.sigma
    n = fit.n
    if k == 1:
        d = float(fit.sizes[0])
        return (f"a step of {d:+.3g} m/s² ({d / s:+.2g} σ) in the bias on {axis} at "
                f"{_where(tcol, time_unit, int(fit.places[0]))}")
    edges = np.concatenate([[0], fit.places, [n]])
    two = _two_level(fit, fit.lengths) if k >= MIN_SWITCHES else None
    if two is not None:
        lo, hi, high = two
        span = np.diff(np.concatenate([tcol, [tcol[-1] + (tcol[-1] - tcol[0]) / max(n - 1, 1)]]))
        dwell = np.array([float(np.sum(span[a:b])) for a, b in zip(edges[:-1], edges[1:],
                                                                   strict=True)])
        share = float(np.sum(dwell[high]) / np.sum(dwell))
        unit = "s" if time_unit == "s" else "samples"
        gap = hi - lo
        return (f"the bias on {axis} switches between two levels {gap:.3g} m/s² "
                f"({gap / s:.2g} σ) apart: {k} switches, {100 * share:.0f} % of the time at "
                f"the upper level, dwelling {float(np.mean(dwell)):.3g} {unit} on average "
                f"(first at {_where(tcol, time_unit, int(fit.places[0]))}) — random "
                "telegraph noise: a bistable contact, defect or supply, not a drift")
    places = ", ".join(_at(tcol, time_unit, int(i)) for i in fit.places[:8]) + (
        ", …" if k > 8 else "")
    if _one_sign(fit.sizes):
        total = float(np.sum(fit.sizes))
        return (f"a staircase of {k} steps of about {total / k:+.3g} m/s² each "
                f"({total:+.3g} m/s², {total / s:+.2g} σ in all) in the bias on {axis} at "
                + ("t = " if time_unit == "s" else "samples ") + places)
    parts = ", ".join(f"{float(d):+.3g} m/s² at {_where(tcol, time_unit, int(i))}"
                      for d, i in zip(fit.sizes[:8], fit.places[:8], strict=True))
    return f"{k} steps of the bias on {axis}: {parts}" + (", …" if k > 8 else "")
