"""Held poses found in a continuous log: the static-segment detector.

A board turned by hand, a phone laid on its sides, a tilt table stepped through positions:
the log alternates held poses and motion. This module labels each sample with its pose
(0, 1, …) or -1 while moving.

Statistic
---------
For each sample i a centred window of ``w`` samples (truncated at the ends) gives

    V_i = s²_x,i + s²_y,i                      (m/s²)²

the sum of the two tilt-plane axes' sample variances in the window. Not the variance of the
norm ``|a|``: turning a board in the tilt plane keeps ``|a| = g`` and changes only the axes,
so a slow rotation would read as static. With a gyro (rate ω about the tilt axis, rad/s), also

    W_i = mean over the window of (ω - median(ω))²        (rad/s)²

(the log-wide median is the bias while mostly held: a constant turning rate has no variance
but a large W). A 3-axis log is watched on every axis (``more_acc``: V sums the three
variances, ν = 3(w − 1); a gyro of m axes sums its m mean squares, ν = m·w): a turn about a
tilt-plane axis moves the normal axis first, and the pose ±n must not merge with ∓n because
x and y read alike on both. A sample is *static* when ``V_i ≤ τ_V`` (and ``W_i ≤ τ_W``): its
whole window is quiet, so the samples within half a window of any motion are excluded.

Thresholds from the data's own quiet level (two stages)
-------------------------------------------------------
For white noise of equal variance σ² on both axes, ``V = σ² χ²_ν/(w-1)`` with ``ν = 2(w-1)``.

1. Candidates. The quiet level ``q`` is the 10th percentile of V over the log
   (:data:`QUIET_QUANTILE`: at least 10 % of the log must be held still), an estimate of
   ``σ² χ²_ν(0.10)/(w-1)`` for the quietest pose. Candidate holds are where

       V ≤ τ = LOOSE · MARGIN · q · χ²_ν(0.999) / χ²_ν(0.10)

   — the 99.9 % point of a static window, times :data:`MARGIN` = 2, times :data:`LOOSE` = 10
   because poses differ in noise (measured on a real YEI 3-Space log: a hand-held pose 4×
   noisier in variance than one resting on a table), while motion is orders of magnitude
   louder.
2. Each candidate against its own noise: with ``q_k`` the median of V over the candidate,
   an estimate of ``σ_k² χ²_ν(0.5)/(w-1)``, its samples are static where

       V ≤ τ_k = min(τ, MARGIN · q_k · χ²_ν(0.999) / χ²_ν(0.5))

   so the edges of a hold are trimmed at that pose's own 99.9 % point (× 2), not at the
   loudest pose's: samples at the start of a slow turn do not bias the pose's mean.

``q`` and ``q_k`` are floored at the quantization variance ``Σ_k Δ_k²/12`` (Δ_k the smallest
step between distinct readings of axis k), so a coarse sensor whose quiet windows are
constant does not get a zero threshold. The gyro's statistic goes through the same two
stages with ``ν = w`` (a mean of w squares). Both thresholds of each pose are in its
:class:`Segment`.

A log still throughout
----------------------
Before the holds are cut, the whole log goes through the static check of ``tiltbench noise``
(:func:`calib.logs.static_log.check_static`: no window mean more than 0.3 m/s² from another —
a tilt of ≈ 1.75° —, no window variance 9× the median one, no scatter beyond the
sample-to-sample noise, every gyro axis under 0.05 rad/s; windows of at least ten correlation
times).
A log that passes is **one** held pose, all of it (``still``). The two stages above assume
readings independent within a window; an export that is low-pass filtered or decimated holds
stretches of smoothed or repeated values far quieter than its noise (a real Galaxy S5 export:
windows 10⁴× below the median), and its 10th percentile then splits one still log into
thousands of "holds". Poses closer than 1.75° in one log are not a calibration design either
way (its poses must spread around the turn).

Segments
--------
Runs of static samples shorter than ``min_hold`` become moving. Two runs separated by less
than ``min_hold`` whose means differ by less than :data:`MERGE_STDS` per-sample standard
deviations on both axes are one pose (a bump while holding); the samples of the bump stay -1.
Defaults: window 0.5 s and min hold 1 s with sample times; 25 and 100 samples without.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calib.input_rules import DataError
from calib.logs.static_log import MAX_RATE, WINDOW_SHIFT, check_static
from calib.results import ResultMixin, readonly

QUIET_QUANTILE = 0.10
"""Quantile of the window statistic taken as the quiet level (≥ 10 % of the log held)."""
STATIC_QUANTILE = 0.999
"""A static window exceeds the threshold with about this complement probability (before
the margin)."""
MARGIN = 2.0
"""Factor on the threshold for noise that differs between poses."""
LOOSE = 10.0
"""A held pose may be this much noisier (variance) than the quietest tenth of the log — a
board held by hand beside one resting on a table — and still be a candidate hold."""
MERGE_STDS = 3.0
"""Runs closer than ``min_hold`` whose means differ by less than this many per-sample stds
on both axes are the same pose."""

FEW_HOLDS = 4
"""Fewer detected holds than this (a multi-position calibration's least) get the hint to try a
shorter window and minimum hold; with more, the detector found holds and what is missing is
something else (poses in the tilt plane, orientations)."""
DEFAULT_WINDOW_S, DEFAULT_HOLD_S = 0.5, 1.0
"""Window and minimum hold, s, when the log has sample times."""
DEFAULT_WINDOW_N, DEFAULT_HOLD_N = 25, 100
"""Window and minimum hold, samples, when it has none."""


@dataclass(frozen=True, eq=False)
class Segment(ResultMixin):
    """One held pose.

    Attributes
    ----------
    start, stop : sample indices, ``[start, stop)``; the pose's samples are those labelled
        with it inside (a merged bump stays -1).
    n : number of samples labelled with the pose.
    t_start, t_stop : times of the first and last labelled sample, s (None without times).
    mean, std : (2,) per-axis mean and sample std of the labelled samples, m/s².
    """

    start: int
    stop: int
    n: int
    t_start: float | None
    t_stop: float | None
    mean: np.ndarray
    std: np.ndarray
    threshold: float = float("nan")
    gyro_threshold: float | None = None

    _TITLE = "Held pose"
    _UNITS = {"mean": "m/s²", "std": "m/s²", "t_start": "s", "t_stop": "s",
              "threshold": "(m/s²)²", "gyro_threshold": "(rad/s)²"}

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean", readonly(self.mean))
        object.__setattr__(self, "std", readonly(self.std))

    def summary(self) -> str:
        when = ("" if self.t_start is None else
                f" t {self.t_start:.3f}–{self.t_stop:.3f} s")
        return (f"samples {self.start}–{self.stop - 1}{when} (n = {self.n}): mean "
                f"[{self.mean[0]:+.5f}, {self.mean[1]:+.5f}] m/s², std "
                f"[{self.std[0]:.3g}, {self.std[1]:.3g}] m/s², threshold "
                f"{self.threshold:.3g} (m/s²)²")

    def to_dict(self) -> dict:
        return {"start": self.start, "stop": self.stop, "n": self.n,
                "t_start": self.t_start, "t_stop": self.t_stop,
                "mean": self.mean.tolist(), "std": self.std.tolist(),
                "threshold": self.threshold, "gyro_threshold": self.gyro_threshold}

    @classmethod
    def from_dict(cls, d: dict) -> Segment:
        return cls(**{k: d[k] for k in ("start", "stop", "n", "t_start", "t_stop", "mean",
                                         "std", "threshold", "gyro_threshold")})


@dataclass(frozen=True, eq=False)
class PoseDetection(ResultMixin):
    """Held poses of a log and the thresholds that found them (module docstring).

    Attributes
    ----------
    segments : the poses in time order.
    labels : (N,) int, pose index per sample, -1 while moving.
    window, min_samples : window and minimum hold, samples.
    quiet_level, threshold : q and τ_V, (m/s²)².
    gyro_quiet_level, gyro_threshold : the same for the gyro, (rad/s)², or None.
    axes_watched : acceleration axes whose variances V sums (2: the tilt plane; 3 with the
        normal axis of a 3-axis log).
    still : the whole log passed the static check: one hold, every sample (module docstring).
    """

    segments: tuple[Segment, ...]
    labels: np.ndarray
    window: int
    min_samples: int
    quiet_level: float
    threshold: float
    gyro_quiet_level: float | None = None
    gyro_threshold: float | None = None
    axes_watched: int = 2
    still: bool = False

    _TITLE = "Held poses"
    _UNITS = {"quiet_level": "(m/s²)²", "threshold": "(m/s²)²",
              "gyro_quiet_level": "(rad/s)²", "gyro_threshold": "(rad/s)²",
              "window": "samples", "min_samples": "samples"}

    def __post_init__(self) -> None:
        object.__setattr__(self, "segments", tuple(self.segments))
        object.__setattr__(self, "labels", readonly(self.labels, int))

    @property
    def count(self) -> int:
        return len(self.segments)

    def thresholds_line(self) -> str:
        """One line: the window, the minimum hold and the thresholds with how they came."""
        if self.still:
            return ("the whole log is still (the static check of `tiltbench noise`: window "
                    f"means within {WINDOW_SHIFT:g} m/s² of each other, no scatter beyond the "
                    f"sample-to-sample noise, every gyro axis under {MAX_RATE:g} rad/s): one "
                    "hold, every sample")
        watched = "var_x + var_y" + (" + var_n" if self.axes_watched == 3 else "") if (
            self.axes_watched <= 3) else f"the variances of {self.axes_watched} axes"
        line = (f"candidate holds where {watched} over {self.window} samples ≤ "
                f"{self.threshold:.3g} (m/s²)² (= {LOOSE:g} × {MARGIN:g} × the static 99.9 % "
                f"point from the quiet level {self.quiet_level:.3g} (m/s²)², the 10th "
                "percentile)")
        if self.gyro_threshold is not None:
            line += (f" and the gyro's mean square ≤ {self.gyro_threshold:.3g} (rad/s)² "
                     f"(quiet level {self.gyro_quiet_level:.3g})")
        return line + (f"; each hold then against {MARGIN:g} × the 99.9 % point from its own "
                       f"median (below); holds shorter than {self.min_samples} samples "
                       "ignored")

    def few_poses_hint(self, rate: float | None = None) -> str:
        """What to try when the detector found too few holds: its window and minimum hold, and
        shorter ones (a hand-held or high-rate log: tremor and taps fill long windows, and a
        hand rarely holds still for a full second). ``rate``: Hz, to say them in seconds."""
        if rate:
            w, h = f"{self.window / rate:.3g} s", f"{self.min_samples / rate:.3g} s"
            try_ = "--static-window 0.1 --min-hold 0.5 (seconds)"
        else:
            w, h = f"{self.window} samples", f"{self.min_samples} samples"
            try_ = "--static-window 10 --min-hold 50 (samples: the log has no times)"
        found = (f"the pose detector found {self.count} hold(s) with a window of {w} and a "
                 f"minimum hold of {h}")
        if self.still:  # shorter windows cannot find poses the sensor never took
            return ("the whole log is still (the static check of `tiltbench noise`): one hold; "
                    "record the sensor held in several orientations")
        if self.count >= FEW_HOLDS:  # holds were found: what is missing is not detection
            return found
        return f"{found}; on a hand-held or high-rate log shorter ones find more: try {try_}"

    def summary(self) -> str:
        held = int(np.sum(self.labels >= 0))
        lines = [f"{self.count} held pose(s) found; {held} of {self.labels.size} samples held",
                 self.thresholds_line()]
        lines += [f"  pose {k}: {s.summary()}" for k, s in enumerate(self.segments)]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-able; ``labels`` run-length encoded as ``[label, count]`` pairs."""
        lab = self.labels
        starts = np.r_[0, np.flatnonzero(lab[1:] != lab[:-1]) + 1] if lab.size else []
        stops = np.r_[starts[1:], lab.size] if lab.size else []
        runs = [[int(lab[a]), int(b - a)] for a, b in zip(starts, stops, strict=True)]
        return {"segments": [s.to_dict() for s in self.segments], "labels_rle": runs,
                "window": self.window, "min_samples": self.min_samples,
                "quiet_level": self.quiet_level, "threshold": self.threshold,
                "gyro_quiet_level": self.gyro_quiet_level,
                "gyro_threshold": self.gyro_threshold, "axes_watched": self.axes_watched,
                "still": self.still,
                "units": dict(self._UNITS, **{"segments.mean": "m/s²", "segments.std": "m/s²",
                                             "segments.t_start": "s",
                                             "segments.t_stop": "s",
                                             "segments.start": "sample index",
                                             "segments.stop": "sample index",
                                             "segments.n": "samples",
                                             "segments.threshold": "(m/s²)²",
                                             "segments.gyro_threshold": "(rad/s)²",
                                             "labels_rle": "pose label, samples",
                                             "axes_watched": "count"})}

    @classmethod
    def from_dict(cls, d: dict) -> PoseDetection:
        labels = np.concatenate([np.full(c, v, dtype=int) for v, c in d["labels_rle"]]
                                ) if d["labels_rle"] else np.zeros(0, dtype=int)
        return cls(segments=tuple(Segment.from_dict(s) for s in d["segments"]),
                   labels=labels, window=d["window"], min_samples=d["min_samples"],
                   quiet_level=d["quiet_level"], threshold=d["threshold"],
                   gyro_quiet_level=d.get("gyro_quiet_level"),
                   gyro_threshold=d.get("gyro_threshold"),
                   axes_watched=int(d.get("axes_watched", 2)),
                   still=bool(d.get("still", False)))


def _window_sums(s: np.ndarray, n: int, w: int
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sums over the centred window of ``w`` samples (truncated at the ends) of the data whose
    cumulative sums (with a leading 0) are ``s`` (N + 1): ``(sums, edge, edge_count)`` — every
    window holds ``w`` samples except those at the indices ``edge`` (the first and last half
    windows), which hold ``edge_count``. The interior is one difference of two views of ``s``:
    no index or count arrays the length of the log."""
    h = w // 2
    out = np.empty(n)
    inner = n - w + 1
    if inner > 0:
        np.subtract(s[w:], s[:inner], out=out[h:h + inner])
    edge = np.concatenate([np.arange(min(h, n)), np.arange(max(h + max(inner, 0), h), n)])
    edge = edge[(edge >= 0) & (edge < n)]
    lo, hi = np.maximum(0, edge - h), np.minimum(n, edge + (w - h))
    out[edge] = s[hi] - s[lo]
    return out, edge, (hi - lo).astype(float)


def window_variance(x: np.ndarray, w: int) -> np.ndarray:
    """Sample variance (ddof 1) of ``x`` in a centred window of ``w`` samples per sample,
    truncated at the ends; O(N) by cumulative sums of the centred data (centring keeps the
    difference of sums accurate: the values are O(g) while the variances may be 10⁻⁸). A few
    arrays the length of the log at a time: a long log's detection must not need ten.

    Per window of c samples: ``(Σx² − (Σx)²/c) / (c − 1)``."""
    x = np.array(x, dtype=float)
    x -= np.mean(x)
    n = x.size
    s = np.zeros(n + 1)
    np.cumsum(x, out=s[1:])
    s1, edge, cnt = _window_sums(s, n, w)
    np.square(x, out=x)
    np.cumsum(x, out=s[1:])
    del x
    var, _, _ = _window_sums(s, n, w)
    del s
    e1, e2 = s1[edge], var[edge]  # the truncated windows, done apart with their own counts
    np.square(s1, out=s1)
    s1 /= w
    var -= s1
    del s1
    var /= max(w - 1.0, 1.0)
    var[edge] = (e2 - e1 * e1 / cnt) / np.maximum(cnt - 1.0, 1.0)
    np.maximum(var, 0.0, out=var)
    return var


def _window_mean(x: np.ndarray, w: int) -> np.ndarray:
    n = x.size
    s = np.zeros(n + 1)
    np.cumsum(x, out=s[1:])
    total, edge, cnt = _window_sums(s, n, w)
    e = total[edge]
    total /= w
    total[edge] = e / cnt
    return total


_PREFIX = 1 << 14
"""Samples of each column whose quantization step bounds the column's (:class:`_QuantFloor`)."""
_BLOCK = 1 << 20
"""Samples per block where a long log's column is walked in pieces (bounded temporaries)."""


def _quant_step(x: np.ndarray) -> float:
    """The smallest step between distinct values of ``x`` (0 when all are equal): one sorted
    copy, its differences taken in blocks (``np.unique`` + ``np.diff`` would hold three
    arrays the length of a long log)."""
    s = np.sort(x)
    best = np.inf
    for a in range(0, s.size - 1, _BLOCK):
        d = np.diff(s[a:a + _BLOCK + 1])
        d = d[d > 0]
        if d.size:
            best = min(best, float(d.min()))
    return best if np.isfinite(best) else 0.0


def _range_stats(x: np.ndarray, ranges: list[tuple[int, int]]
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Mean and sample std (ddof 1) per column of the rows of ``x`` in ``ranges`` ([a, b)),
    two passes over slices in blocks: no copy of the rows (a 24-hour hold is one range)."""
    blocks = [(a0, min(a0 + _BLOCK, b)) for a, b in ranges for a0 in range(a, b, _BLOCK)]
    count = sum(b - a for a, b in ranges)
    mean = sum(x[a:b].sum(0) for a, b in blocks) / count
    ss = sum(np.square(x[a:b] - mean).sum(0) for a, b in blocks)
    return mean, np.sqrt(ss / (count - 1)) if count > 1 else np.full(x.shape[1], np.nan)


def _ratio(nu: float, level: float) -> float:
    """``χ²_ν(0.999) / χ²_ν(level)``: from a quantile of static windows to their 99.9 %
    point (``scipy.special.chdtri``, the inverse upper tail: scipy.stats takes ≈ 0.4 s to
    import and a long log's import needs nothing else of it)."""
    from scipy.special import chdtri

    return float(chdtri(nu, 1.0 - STATIC_QUANTILE) / chdtri(nu, 1.0 - level))


class _QuantFloor:
    """The quantization variance ``Σ_k Δ_k²/12`` of some columns (Δ_k: :func:`_quant_step`),
    taken exactly only where it can matter: the steps of each column's first
    :data:`_PREFIX` samples are at least the column's (their distinct values are a subset), so
    their sum bounds the floor from above; :meth:`max_with` sorts the whole columns only when a
    value falls below that bound. A long log's detection then needs no sort of its columns."""

    def __init__(self, cols: list[np.ndarray], least: float = 0.0):
        self.cols, self.least = cols, least
        steps = [_quant_step(c[:_PREFIX]) for c in cols]
        # one value in the prefix says nothing about the column's step: no bound
        self.bound = (np.inf if any(d == 0.0 and c.size > _PREFIX for d, c in zip(steps, cols,
                                                                                  strict=True))
                      else max(sum(d * d / 12.0 for d in steps), least))
        self._exact: float | None = None

    def exact(self) -> float:
        if self._exact is None:
            self._exact = max(sum(_quant_step(c) ** 2 / 12.0 for c in self.cols), self.least)
        return self._exact

    def max_with(self, x: float) -> float:
        """``max(x, floor)``, exactly."""
        return x if x >= self.bound else max(x, self.exact())


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``[start, stop)`` of each run of True."""
    m = np.concatenate(([False], mask, [False]))
    edges = np.flatnonzero(m[1:] != m[:-1])
    return list(zip(edges[0::2].tolist(), edges[1::2].tolist(), strict=True))


def _still_throughout(acc: np.ndarray, rate: float, gyro: np.ndarray | None,
                      extra: list[np.ndarray], hold: int) -> bool:
    """Whether the whole log passes :func:`calib.logs.static_log.check_static` (module
    docstring: A log still throughout): its windows of one minimum hold at least, every gyro
    axis checked. A log shorter than two holds is left to the two stages. ``rate``: Hz, or 1
    for a log without times (``hold`` then in samples)."""
    n = acc.shape[0]
    if n < 2 * hold:
        return False
    rates = None if gyro is None else np.asarray(gyro, dtype=float).reshape(n, -1)
    # the tilt-plane axes with every gyro axis, then each other axis: views of the log, no
    # copy of a long one
    try:
        check_static(acc, rate, "log", window=hold / rate, gyro=rates)
        for col in extra:
            check_static(col, rate, "log", window=hold / rate)
    except DataError:
        return False
    return True


def detect_poses(acc: np.ndarray, t: np.ndarray | None = None, gyro: np.ndarray | None = None,
                 *, window: float | None = None, min_hold: float | None = None,
                 more_acc: np.ndarray | None = None) -> PoseDetection:
    """Find the held poses of a log (module docstring).

    Parameters
    ----------
    acc : (N, 2) m/s², the tilt-plane readings (the segments' means and stds are of these).
    t : (N,) s, increasing, or None.
    gyro : (N,) rad/s about the tilt axis, or (N, m) every gyro axis of the log, or None.
        With m axes the gyro statistic sums them: ``W_i`` over the axes, ν = m·w.
    more_acc : (N,) or (N, j) m/s², the log's other acceleration axes (a 3-axis log's
        normal axis), watched too: ``V_i`` then sums the variances of all k = 2 + j axes,
        ν = k(w − 1), and two runs merge only when they agree on every axis. Without it, a
        tumble about the tilt-plane x axis that starts by moving z alone reads as held.
    window, min_hold : s when ``t`` is given (defaults 0.5 and 1), samples when not (25 and
        100).

    Returns
    -------
    PoseDetection : segments, per-sample labels (-1 moving), thresholds.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> th = np.repeat([0.0, 1.0, 2.0], 400)
    >>> acc = np.c_[-9.8 * np.sin(th), -9.8 * np.cos(th)] + 0.01 * rng.standard_normal((1200, 2))
    >>> detect_poses(acc).count
    3
    """
    acc = np.asarray(acc, dtype=float)
    n = acc.shape[0]
    if t is not None:
        dt = float(np.median(np.diff(t))) if n > 1 else 1.0
        w = int(round((DEFAULT_WINDOW_S if window is None else window) / dt))
        hold = int(round((DEFAULT_HOLD_S if min_hold is None else min_hold) / dt))
        rate = 1.0 / dt
    else:
        w = int(DEFAULT_WINDOW_N if window is None else window)
        hold = int(DEFAULT_HOLD_N if min_hold is None else min_hold)
        rate = 1.0  # samples: windows and holds count them
    w = max(w, 5)
    hold = max(hold, w)
    # the watched axes as a list of columns (views): no (N, k) copy of a long log
    extra = [] if more_acc is None else list(np.asarray(more_acc, dtype=float).reshape(n, -1).T)
    watch = [acc[:, 0], acc[:, 1], *extra]
    k_acc = len(watch)
    nu_v = k_acc * (w - 1.0)
    v = window_variance(watch[0], w)
    for col in watch[1:]:  # summed in place: one accumulator, not a new array per axis
        v += window_variance(col, w)
    floor = _QuantFloor(watch)
    q = max(floor.max_with(float(np.quantile(v, QUIET_QUANTILE))), 1e-18)
    thr = LOOSE * MARGIN * q * _ratio(nu_v, QUIET_QUANTILE)
    coarse = v <= thr
    gq = gthr = wsq = None
    gfloor = None
    if gyro is not None:
        g = np.asarray(gyro, dtype=float).reshape(n, -1)
        nu_w = float(w * g.shape[1])
        wsq = sum(_window_mean((g[:, j] - np.median(g[:, j])) ** 2, w)
                  for j in range(g.shape[1]))
        gfloor = _QuantFloor([g[:, j] for j in range(g.shape[1])], least=1e-24)
        gq = gfloor.max_with(float(np.quantile(wsq, QUIET_QUANTILE)))
        gthr = LOOSE * MARGIN * gq * _ratio(nu_w, QUIET_QUANTILE)
        coarse &= wsq <= gthr
    if _still_throughout(acc, rate, gyro, extra, hold):
        labels = np.zeros(n, dtype=int)
        labels.setflags(write=False)
        mean, std = _range_stats(acc, [(0, n)])
        one = Segment(start=0, stop=n, n=n, t_start=None if t is None else float(t[0]),
                      t_stop=None if t is None else float(t[-1]), mean=mean, std=std,
                      threshold=thr, gyro_threshold=gthr)
        return PoseDetection(segments=(one,), labels=labels, window=w, min_samples=hold,
                             quiet_level=q, threshold=thr, gyro_quiet_level=gq,
                             gyro_threshold=gthr, axes_watched=k_acc, still=True)
    # stage 2: each candidate hold against its own noise (median of its windows)
    runs, own = [], []
    for a, b in _runs(coarse):
        if b - a < hold:
            continue
        tau = min(thr, MARGIN * floor.max_with(float(np.median(v[a:b]))) * _ratio(nu_v, 0.5))
        quiet = v[a:b] <= tau
        gtau = None
        if wsq is not None:
            gtau = min(gthr, MARGIN * gfloor.max_with(float(np.median(wsq[a:b])))
                       * _ratio(nu_w, 0.5))
            quiet &= wsq[a:b] <= gtau
        for x, y in _runs(quiet):
            if y - x >= hold:
                runs.append((a + x, a + y))
                own.append((tau, gtau))
    groups: list[list[tuple[int, int]]] = []
    taus: list[tuple[float, float | None]] = []
    for (a, b), tau in zip(runs, own, strict=True):
        if groups and a - groups[-1][-1][1] < hold:
            prev = np.concatenate([np.column_stack([c[x:y] for c in watch])
                                   for x, y in groups[-1]])
            here = np.column_stack([c[a:b] for c in watch])
            limit = MERGE_STDS * np.maximum(prev.std(0, ddof=1), here.std(0, ddof=1))
            if np.all(np.abs(prev.mean(0) - here.mean(0)) <= limit):
                groups[-1].append((a, b))
                continue
        groups.append([(a, b)])
        taus.append(tau)
    labels = np.full(n, -1, dtype=int)
    segments = []
    for k, grp in enumerate(groups):
        for a, b in grp:
            labels[a:b] = k
        mean, std = _range_stats(acc, grp)  # the group's runs are disjoint and in order
        first, last = grp[0][0], grp[-1][1] - 1
        segments.append(Segment(
            start=int(grp[0][0]), stop=int(grp[-1][1]), n=sum(b - a for a, b in grp),
            t_start=None if t is None else float(t[first]),
            t_stop=None if t is None else float(t[last]),
            mean=mean, std=std, threshold=taus[k][0], gyro_threshold=taus[k][1]))
    labels.setflags(write=False)  # the record shares it (calib.results.readonly)
    return PoseDetection(segments=tuple(segments), labels=labels, window=w, min_samples=hold,
                         quiet_level=q, threshold=thr, gyro_quiet_level=gq,
                         gyro_threshold=gthr, axes_watched=k_acc)


__all__ = ["DEFAULT_HOLD_N", "DEFAULT_HOLD_S", "DEFAULT_WINDOW_N", "DEFAULT_WINDOW_S",
           "LOOSE", "MARGIN", "MERGE_STDS", "PoseDetection", "QUIET_QUANTILE", "STATIC_QUANTILE",
           "Segment", "detect_poses", "window_variance"]
