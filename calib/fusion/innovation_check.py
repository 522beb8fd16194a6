"""Does the filter believe its own fixes? The innovation gate's count and the windowed NIS test
of a fused run (issue 23, "a filter that doubts its inputs").

Under a right model (the stated noises, calibration and fix σ, the right units, axes and
times) a Kalman filter's innovations are white: ``ν_j ~ N(0, S_j)``, independent from fix to
fix, so ``NIS_j = ν_jᵀ S_j⁻¹ ν_j ~ χ²(d)`` independently (Bar-Shalom, Li & Kirubarajan,
*Estimation with Applications to Tracking and Navigation*, 2001, §5.4: the normalized
innovation squared and its time-average test). Two checks follow.

Gate (one fix)
--------------
A fix with ``NIS ≥ c = χ²_d⁻¹(1 - α_g)`` is rejected and not used
(:func:`calib.fusion.kalman.gate_threshold`; a right fix is rejected with probability α_g exactly).
Default ``α_g = 0.001`` (:data:`GATE_ALPHA`, c = 13.8 for d = 2, a 3.7σ circle): the course's
60 fixes lose a right fix in 6 % of clean runs (1 - 0.999⁶⁰), while a 200 m outlier against
σ ≈ 3 m has NIS ≈ 4000. α_g = 0.01 would reject a right fix in 45 % of clean runs; the gate
is for gross errors, and the window test below catches the subtle ones.

Windowed NIS (consistency)
--------------------------
The M fixes are cut in ``W = ceil(M / K)`` consecutive windows of K or K - 1 fixes
(``numpy.array_split``; K = :data:`NIS_WINDOW` = 10 fixes, 10 s at 1 Hz: long enough to
average a fix's noise, short enough to see a drift over the course's 60 s). The statistic
of window w is the sum of its *capped* NIS::

    T_w = Σ_{j ∈ w} min(NIS_j, c)

(a rejected fix counts c: one outlier adds at most c, a run of rejections drives T_w up).
Under the right model the terms are independent, each ``min(X, c)`` with ``X ~ χ²(d)`` (a
continuous part on [0, c) and an atom ``α_g`` at c), so the law of T_w is the k-fold
convolution of that law, computed numerically (:func:`capped_sum_quantiles`: a grid of
``c/2000`` per term, FFT; no gate: ``T_w ~ χ²(dk)`` exactly). Window w fails when T_w is
outside its two-sided band ``[q(α_w/2), q(1 - α_w/2)]``: above, the fixes disagree with the
filter more than it states (wrong units, axes, times, offsets, gyro, a σ too small); below,
they agree better than it states (a σ too large).

The run is *inconsistent* when any window fails. Windows hold different fixes, and the
innovations of a right filter are independent, so the W window tests are independent and
Šidák's per-window level ``α_w = 1 - (1 - α)^(1/W)`` makes the false-alarm rate of the run
exactly α (:data:`CONSISTENCY_ALPHA` = 0.01), whatever W. Two approximations, stated: a
rejected fix makes the later innovations condition on the rejection (probability α_g per
fix, negligible at 0.001), and the extended (turning) filter's innovations are white only to
first order.

Units: NIS and its bands dimensionless (χ²), times s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import stats

from calib.fusion.kalman import gate_threshold
from calib.results import ResultMixin, readonly

GATE_ALPHA = 0.001
"""Default α of the innovation gate (module docstring: why 0.001)."""

CONSISTENCY_ALPHA = 0.01
"""Default false-alarm rate of the whole run's consistency verdict (Šidák over windows)."""

NIS_WINDOW = 10
"""Default window of the NIS test, in fixes."""

ALPHA_MIN = 1e-6
"""Smallest consistency α: tails below ~1e-9 per window are beyond the FFT law's accuracy."""

NIS_WINDOW_MAX = 1000
"""Largest window (bounded work: the law of a window's sum is an FFT of 4001·K points)."""

_BINS = 2000
"""Grid cells per term on [0, c) for the capped sum's law (error of a quantile ≲ k·c/4000)."""


@lru_cache(maxsize=256)
def capped_sum_quantiles(d: int, cap: float, k: int, tail: float) -> tuple[float, float]:
    """``(q(tail), q(1 - tail))`` of ``T = Σ_{i=1..k} min(X_i, cap)``, ``X_i ~ χ²(d)`` iid.

    ``cap = inf``: the χ²(dk) quantiles (scipy). Otherwise the law of one term on a half-cell
    grid (the mass of cell ``[jδ, (j+1)δ)`` at its centre, the atom ``P(X ≥ cap)`` at cap,
    ``δ = cap / 2000``), its k-th power by FFT, the quantiles by linear interpolation of the
    cumulative sum (module docstring).
    """
    if not (d >= 1 and k >= 1 and 0.0 < tail < 0.5):
        raise ValueError(f"need d ≥ 1, k ≥ 1 and 0 < tail < 0.5, got {d}, {k}, {tail}")
    if math.isinf(cap):
        return float(stats.chi2.ppf(tail, d * k)), float(stats.chi2.isf(tail, d * k))
    if cap <= 0:  # every fix rejected whatever it is: T = k·cap surely
        return k * cap, k * cap
    edges = np.linspace(0.0, cap, _BINS + 1)
    one = np.zeros(2 * _BINS + 1)  # index i ↔ value i·δ/2
    one[1:2 * _BINS:2] = np.diff(stats.chi2.cdf(edges, d))
    one[-1] = stats.chi2.sf(cap, d)
    n = k * 2 * _BINS + 1
    size = 1 << (n - 1).bit_length()
    pmf = np.fft.irfft(np.fft.rfft(one, size) ** k, size)[:n]
    cdf = np.cumsum(np.clip(pmf, 0.0, None))
    cdf /= cdf[-1]
    x = np.arange(n) * (0.5 * cap / _BINS)
    return (float(np.interp(tail, cdf, x)), float(np.interp(1.0 - tail, cdf, x)))


def window_slices(m: int, window: int) -> list[slice]:
    """The ``ceil(m / window)`` consecutive windows of ``window`` or ``window - 1`` fixes."""
    if not 1 <= window <= NIS_WINDOW_MAX:
        raise ValueError(f"the NIS window must be 1 to {NIS_WINDOW_MAX} fixes, got {window}")
    if m == 0:
        return []
    idx = np.array_split(np.arange(m), math.ceil(m / window))
    return [slice(int(i[0]), int(i[-1]) + 1) for i in idx]


def windowed_nis(nis: np.ndarray, *, d: int, gate_alpha: float, window: int = NIS_WINDOW,
                 alpha: float = CONSISTENCY_ALPHA) -> dict:
    """The window test of ``nis`` (M,) or (R, M) (module docstring).

    Returns ``slices`` (W), ``stat`` (…, W) the capped sums, ``lo``/``hi`` (W,) the bands,
    ``n`` (W,) fixes per window, ``failing`` (…, W) bool, ``consistent`` (…,) bool,
    ``per_window_alpha`` α_w and ``cap`` c.
    """
    if not ALPHA_MIN <= alpha < 1.0:
        raise ValueError(f"the consistency alpha must be in [{ALPHA_MIN:g}, 1), got {alpha!r}")
    nis = np.asarray(nis, dtype=float)
    cap = gate_threshold(gate_alpha, d)
    slices = window_slices(nis.shape[-1], window)
    W = len(slices)
    a_w = -math.expm1(math.log1p(-alpha) / W) if W else alpha  # 1 - (1 - α)^(1/W), exact
    capped = np.minimum(nis, cap)
    stat = np.stack([capped[..., s].sum(axis=-1) for s in slices], axis=-1) if W else \
        np.zeros((*nis.shape[:-1], 0))
    n = np.array([s.stop - s.start for s in slices], dtype=int)
    bands = [capped_sum_quantiles(int(d), float(cap), int(k), a_w / 2) for k in n]
    lo = np.array([b[0] for b in bands]) if W else np.zeros(0)
    hi = np.array([b[1] for b in bands]) if W else np.zeros(0)
    failing = (stat < lo) | (stat > hi)
    return {"slices": slices, "stat": stat, "lo": lo, "hi": hi, "n": n, "failing": failing,
            "consistent": ~np.any(failing, axis=-1), "per_window_alpha": a_w, "cap": cap}


@dataclass(frozen=True, eq=False, kw_only=True)
class Consistency(ResultMixin):
    """The verdict on one fused run (module docstring).

    Attributes
    ----------
    consistent : no window out of its band.
    alpha : the run's false-alarm rate.  per_window_alpha : Šidák's α_w.
    window : K, fixes per window.  d : dimension of a fix.
    gate_alpha : α_g.  gate : c = χ²_d⁻¹(1 - α_g) (inf: no gate).
    fixes : M.  rejected : indices (into the fixes the filter saw) of the rejected ones.
    t_start, t_end : (W,) each window's first and last fix time, s.
    n : (W,) fixes per window.  stat : (W,) capped NIS sums.  lo, hi : (W,) the bands.
    failing : (W,) bool.  mean_nis : mean NIS of the used fixes (expected d).
    """

    _TITLE = "Filter consistency"
    _UNITS = "times s; NIS, its sums and bands dimensionless (χ²)"

    consistent: bool
    alpha: float
    per_window_alpha: float
    window: int
    d: int
    gate_alpha: float
    gate: float
    fixes: int
    rejected: np.ndarray
    t_start: np.ndarray
    t_end: np.ndarray
    n: np.ndarray
    stat: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    failing: np.ndarray
    mean_nis: float

    def __post_init__(self) -> None:
        for name in ("t_start", "t_end", "stat", "lo", "hi"):
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "rejected", readonly(self.rejected, int))
        object.__setattr__(self, "n", readonly(self.n, int))
        object.__setattr__(self, "failing", readonly(self.failing, bool))
        object.__setattr__(self, "consistent", bool(self.consistent))

    @classmethod
    def of(cls, fusion, t_gps=None, *, alpha: float = CONSISTENCY_ALPHA,
           window: int = NIS_WINDOW) -> Consistency:
        """The verdict on a single-run :class:`calib.fusion.linear.FusionResult` (its NIS, its
        gate's α, its fix times)."""
        nis = np.asarray(fusion.nis(), dtype=float)
        if nis.ndim != 1:
            raise ValueError("Consistency.of takes a single run (no run axis)")
        d = int(fusion.innovations.shape[-1])
        w = windowed_nis(nis, d=d, gate_alpha=fusion.gate_alpha, window=window, alpha=alpha)
        t = np.asarray(fusion.t_gps if t_gps is None else t_gps, dtype=float)
        used = np.asarray(fusion.fix_used, dtype=bool)
        return cls(consistent=bool(w["consistent"]), alpha=float(alpha),
                   per_window_alpha=float(w["per_window_alpha"]), window=int(window), d=d,
                   gate_alpha=float(fusion.gate_alpha), gate=float(w["cap"]),
                   fixes=int(nis.shape[0]), rejected=np.flatnonzero(~used),
                   t_start=[t[s.start] for s in w["slices"]],
                   t_end=[t[s.stop - 1] for s in w["slices"]], n=w["n"], stat=w["stat"],
                   lo=w["lo"], hi=w["hi"], failing=w["failing"],
                   mean_nis=float(np.mean(nis[used])) if used.any() else float("nan"))

    @property
    def failing_windows(self) -> list[dict]:
        """The windows out of their band: first/last fix time (s), statistic, band."""
        return [{"t_start": float(self.t_start[i]), "t_end": float(self.t_end[i]),
                 "fixes": int(self.n[i]), "nis_sum": float(self.stat[i]),
                 "band": [float(self.lo[i]), float(self.hi[i])],
                 "side": "high" if self.stat[i] > self.hi[i] else "low"}
                for i in np.flatnonzero(self.failing)]

    def verdict(self) -> str:
        """One line: consistent, or inconsistent and where (the gate's count is in the
        fusion summary)."""
        if self.consistent:
            return (f"consistent: windowed NIS inside its band in all {self.n.size} windows of "
                    f"≤ {self.window} fixes (false-alarm rate {self.alpha:g})")
        f = self.failing_windows
        where = ", ".join(f"{w['t_start']:g}–{w['t_end']:g} s {w['side']}" for w in f[:3])
        more = f" +{len(f) - 3} more" if len(f) > 3 else ""
        return (f"INCONSISTENT: fixes vs the filter's stated σ out of band in "
                f"{len(f)} of {self.n.size} NIS windows ({where}{more})")

    def summary(self) -> str:
        return self.verdict()

    def to_dict(self) -> dict:
        return {"consistent": self.consistent, "verdict": self.verdict(),
                "alpha": self.alpha, "per_window_alpha": self.per_window_alpha,
                "window": self.window, "d": self.d, "gate_alpha": self.gate_alpha,
                "gate": self.gate if math.isfinite(self.gate) else None,
                "fixes": self.fixes, "rejected": self.rejected.tolist(),
                "t_start": self.t_start.tolist(), "t_end": self.t_end.tolist(),
                "n": self.n.tolist(), "stat": self.stat.tolist(), "lo": self.lo.tolist(),
                "hi": self.hi.tolist(), "failing": self.failing.tolist(),
                "failing_windows": self.failing_windows,
                "mean_nis": self.mean_nis if math.isfinite(self.mean_nis) else None,
                "units": {"t_start": "s", "t_end": "s", "failing_windows.t_start": "s",
                          "failing_windows.t_end": "s", "stat": "1 (χ²)", "lo": "1 (χ²)",
                          "hi": "1 (χ²)", "gate": "1 (χ²)", "mean_nis": "1 (χ²)",
                          "alpha": "1", "per_window_alpha": "1", "gate_alpha": "1",
                          "window": "fixes", "fixes": "count", "rejected": "fix index",
                          "n": "count"}}

    @classmethod
    def from_dict(cls, d: dict) -> Consistency:
        """Rebuild from :meth:`to_dict` (exact)."""
        kw = {k: d[k] for k in ("consistent", "alpha", "per_window_alpha", "window", "d",
                                "gate_alpha", "fixes", "rejected", "t_start", "t_end", "n",
                                "stat", "lo", "hi", "failing")}
        return cls(**kw, gate=float("inf") if d["gate"] is None else float(d["gate"]),
                   mean_nis=float("nan") if d["mean_nis"] is None else float(d["mean_nis"]))


__all__ = ["ALPHA_MIN", "CONSISTENCY_ALPHA", "Consistency", "GATE_ALPHA", "NIS_WINDOW",
           "NIS_WINDOW_MAX", "capped_sum_quantiles", "window_slices", "windowed_nis"]
