"""The checks of a static log before its noise is characterized (``tiltbench noise``): its
sample rate, even spacing and the segments between its gaps (:func:`log_segments`,
:func:`sample_rate_of`), that every axis reads something and the table did not move
(:func:`check_static`), and the quantization step of its readings (:func:`quantization_step`).

**Gaps and segments.** A gap is what the reader calls one (:data:`calib.logs.reader.GAP_FACTOR`:
a step longer than 5 median steps — one rule, one constant, here and in every reader). A gap is
never filled: :func:`log_segments` splits the log into the stretches between its gaps, each
evenly sampled at the log's one rate (its median step within :data:`SEGMENT_STEP_TOLERANCE`
of the log's), and the noise characterization pools their Allan variances as independent
records (:mod:`calib.noise.allan`). Inside a segment every step is a step (≤ 5 median steps,
as for the reader): a step that spans two or more sample times (a dropped reading) is counted
(``missing``) and said in a note, the readings on either side taken as consecutive.
:func:`sample_rate_of` is the one-record form: the same rule, refused at the first gap.

The static check (:func:`check_static`) refuses, each in one line naming the file, the axis
and the fix:

=====================  ==========================================================  ==========
rule                   refused when                                                threshold
=====================  ==========================================================  ==========
stuck axis             all readings of an axis within ``STUCK_SPAN·max(1, |y|)``    1e-9
                       of each other (a dead, stuck or saturated axis; its
                       "noise" is float rounding and its fit gives N ≈ 1e-28)
window shift           a window mean more than ``shift`` m/s² above the lowest     0.3 m/s²
                       window mean (a tilt of ≈ 1.75° at 0.3 m/s²), or above the
                       noise floor of the window means where that is larger
window variance        a window variance above ``var_ratio`` × the median          9
                       window's (handling, a burst of vibration); windows of
                       at least ``WINDOW_CORR`` correlation times
gyro                   with a gyro, a window mean rate above ``max_rate``          0.05 rad/s
not still              the scatter the sample-to-sample noise does not explain,    0.3 m/s²
                       ``e² = var(y) − var(Δy)/2``, above ``MAX_EXCESS_STD²`` +
                       ``EXCESS_Z·σ_d²/√n`` (σ_d² = var(Δy)/2)
=====================  ==========================================================  ==========

**Why the last rule.** The window tests compare windows with each other: a sensor shaken or
carried through the whole log (every window alike) passes them, and vibration faster than a
window averages out of the window means. For white noise ``var(Δy)/2 = var(y)``, so ``e²`` is
zero up to its sampling error (``e²`` is then the lag-1 autocovariance, std ``σ²/√n``); motion
slower than the sample rate adds to ``var(y)`` far more than to ``var(Δy)`` (a sine of
frequency f adds A²/2 to the first and A²·sin²(πf/fs) to the second). Isolated spikes add
equally to both and do not count. Drift counts, as the window shift does.

**A filtered log.** A window of w white readings has a variance ``σ²·χ²_{w−1}/(w−1)``: its
ratio to the median window's stays below 2 at w = 100, and 9 is a burst. A log low-pass
filtered below its Nyquist frequency (a digital filter, a decimated export) holds few
independent readings per window: a 10 Hz phone export with a correlation time of about a
second has about two per 1-s window, and its quiet windows reach 14× the median by chance.
The window tests therefore lay windows of at least :data:`WINDOW_CORR` correlation times
(:func:`correlation_time`: the first lag where an axis' autocorrelation falls below 1/e, the
longest over the axes, read on up to :data:`CORR_SAMPLES` readings), about ten independent
readings each; a white log's correlation time is one sample and its window stays ``window``.
The noise characterization itself: :mod:`calib.noise.allan`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from calib.input_rules import DataError
from calib.logs.table import GAP_FACTOR
from calib.numerics import lagged_sums

WINDOW_CORR = 10.0
"""Shortest window of the window tests in correlation times (module docstring: A filtered
log)."""

CORR_SAMPLES = 1 << 17
"""Readings (from the start) the correlation time is read on."""

STUCK_SPAN = 1e-9
"""An axis is stuck when all its readings lie within ``STUCK_SPAN·max(1 m/s², max|y|)`` of each
other: float64 rounding and unit conversions (g, counts → m/s²) move a constant reading by a
few ulps (≈ 1e-15 relative); the finest quantizer of a logged accelerometer (a 24-bit
converter over ±2 g: 2.3e-6 m/s² ≈ 2.4e-7 g) is 200× above this span."""
WINDOW_SHIFT = 0.3
"""Largest shift of a window mean above the lowest one, m/s² (a tilt of ≈ 1.75° at 1 g)."""
MAX_RATE = 0.05
"""Largest window mean gyro rate, rad/s (≈ 3°/s)."""
_BLOCK_ROWS = 1 << 20
"""Rows handled at a time where a long log is walked in pieces (bounded temporaries)."""
MAX_EXCESS_STD = 0.3
"""Largest scatter not explained by sample-to-sample noise, m/s² (std): the same 0.3 m/s² as
the window shift (``--static-shift``: a tilt of ≈ 1.75°); a held sensor's drift over a log
(bias instability, random walk) stays far below it (0.02 m/s² for 5e-4 m/s²/√s over an
hour), a hand-held or shaken one is above it."""
EXCESS_Z = 6.0
"""The sampling error of ``e²`` allowed on top, in its standard deviations ``σ_d²/√n``: six
of them are exceeded by chance with probability ≈ 1e-9, so a noisy short log of white noise
is never refused (64 samples of σ = 0.8 m/s² allow e = 0.75 m/s²)."""
SEGMENT_STEP_TOLERANCE = 0.25
"""A segment's median step may differ from the log's by this fraction: a logger that changed
its rate changed it by a factor (50 → 100 Hz), while time-stamp rounding moves a median far
less (7 or 8 ms stamps of a 128 Hz log: 12.5 %). Segments at different rates are refused: the
octave m would mean a different τ in each."""


LATTICE_PREFIX = 1 << 14
"""Samples of a long log looked at first by :func:`quantization_step`: more than half of them
distinct means readings off any lattice (a log in counts repeats its few values at once)."""


def quantization_step(y: np.ndarray, rel_tol: float = 1e-3) -> float | None:
    """The lattice step of the readings (m/s²), or None when they are not on a lattice.

    The readings are on a lattice when they take few distinct values (at most half the
    samples) and every distinct value is ``u_0 + k·Δ`` (k integer, to ``rel_tol``·Δ), Δ the
    smallest gap between sorted distinct values (gaps below 1e-9 of the range are float
    noise of one value and merged). A long log whose first :data:`LATTICE_PREFIX` samples are
    already mostly distinct values is not on a lattice: its whole sort is skipped."""
    y = np.asarray(y, dtype=float)
    if y.size > 2 * LATTICE_PREFIX:
        head = np.sort(y[:LATTICE_PREFIX])
        if np.count_nonzero(head[1:] != head[:-1]) + 1 > LATTICE_PREFIX // 2:
            return None
    u = np.sort(y)
    distinct = u[1:] != u[:-1]
    count = int(np.count_nonzero(distinct)) + 1
    if count < 2 or count > y.size // 2:  # continuous readings end here, after one sort
        return None
    u = np.concatenate([u[:1], u[1:][distinct]])
    span = float(u[-1] - u[0])
    gaps = np.diff(u)
    gaps = gaps[gaps > 1e-9 * span]
    if gaps.size == 0:
        return None
    step = float(gaps.min())
    k = (u - u[0]) / step
    if np.max(np.abs(k - np.rint(k))) > rel_tol:
        return None
    return step


@dataclass(frozen=True)
class LogSegments:
    """The stretches of a log between its gaps (module docstring; :func:`log_segments`).

    rate : the common sample rate, Hz (``--rate`` if given, else the mean rate inside the
        segments, ``Σ(n_s − 1)/Σ(t_last − t_first)`` to 12 digits).
    bounds : ((start, stop), …) row indices of each segment, stop exclusive, in order.
    gaps : ((row, t, length), …) each gap: the row before it, its time s, its length s.
    step : the log's median step, s (None when the log has no sample times).
    missing : sample times inside the segments without a reading (a step spanning k sample
        times counts k − 1; steps ≤ :data:`calib.logs.reader.GAP_FACTOR` median steps).
    """

    rate: float
    bounds: tuple[tuple[int, int], ...]
    gaps: tuple[tuple[int, float, float], ...] = ()
    step: float | None = None
    missing: int = 0

    @property
    def count(self) -> int:
        return len(self.bounds)

    @property
    def lengths(self) -> tuple[int, ...]:
        return tuple(b - a for a, b in self.bounds)

    def line(self, where: str) -> str | None:
        """The one-line note of a split log (None for one segment): how many segments and
        gaps, the first gap, and how they are used."""
        if self.count < 2:
            return None
        _, t0, length = self.gaps[0]
        return (f"{where}: {self.count} segments between {len(self.gaps)} gap(s) (the first "
                f"{length:.4g} s after t = {t0:.6g} s); the Allan variance pooled over them, "
                "segments as independent records")

    def missing_note(self) -> str | None:
        """The note of readings missing inside the segments (None when none are)."""
        if not self.missing:
            return None
        return (f"{self.missing} sample time(s) inside the segments have no reading (steps of 2 "
                f"to {GAP_FACTOR:g} median steps, not gaps by the reader's rule): the readings "
                "on either side are taken as consecutive")


def log_segments(t: np.ndarray | None, rate: float | None, where: str) -> LogSegments:
    """Split a log at its gaps (module docstring): the segments, the common rate, the gaps.

    Parameters
    ----------
    t : (N,) sample times, s, strictly increasing (as the reader leaves them), or None.
    rate : the stated rate, Hz (``--rate``), or None (then from ``t``).
    where : the file, for the messages.

    Raises
    ------
    DataError : no times and no rate; times that do not increase; a segment at another rate
        (its median step off the log's by more than :data:`SEGMENT_STEP_TOLERANCE`).
    """
    if t is None:
        if rate is None:
            raise DataError(f"{where}: the log has no sample times; give its rate with --rate HZ")
        return LogSegments(rate=float(rate), bounds=())
    t = np.asarray(t, dtype=float)
    dt = np.diff(t)
    med = float(np.median(dt)) if dt.size else float("nan")
    if not med > 0:
        raise DataError(f"{where}: sample times do not increase")
    cut = np.flatnonzero(dt > GAP_FACTOR * med)  # the reader's rule (calib.logs.reader)
    starts = np.concatenate([[0], cut + 1])
    stops = np.concatenate([cut + 1, [t.size]])
    bounds = tuple((int(a), int(b)) for a, b in zip(starts, stops, strict=True))
    gaps = tuple((int(k), float(t[k]), float(dt[k])) for k in cut)
    # steps of 1.5 to GAP_FACTOR median steps: readings missing inside a segment (the few
    # long steps only are looked at: no temporaries the length of the log)
    long = np.flatnonzero(dt >= 1.5 * med)
    long = long[dt[long] <= GAP_FACTOR * med]
    missing = int(np.sum(np.rint(dt[long] / med) - 1.0))
    for k, (a, b) in enumerate(bounds if len(bounds) > 1 else ()):  # one: its step is med
        if b - a < 3:
            continue  # a step or none: contributes nothing (too short for one octave)
        own = float(np.median(dt[a:b - 1]))
        if abs(own - med) > SEGMENT_STEP_TOLERANCE * med:
            raise DataError(
                f"{where}: segment {k + 1} of {len(bounds)} (t = {t[a]:.6g} to {t[b - 1]:.6g} s) "
                f"is sampled every {own:.4g} s, the log every {med:.4g} s (median steps): the "
                "Allan variance pools segments of one rate only; cut the log where the rate "
                "changes and characterize each part")
    if rate is None:
        spans = float(sum(t[b - 1] - t[a] for a, b in bounds))
        steps = sum(b - a - 1 for a, b in bounds)
        # the mean rate inside the segments, to 12 digits (time stamps in float carry ~1e-13
        # noise); one segment: (N − 1)/(t_N − t_1)
        rate = float(f"{steps / spans:.12g}")
    return LogSegments(rate=float(rate), bounds=bounds, gaps=gaps, step=med, missing=missing)


def sample_rate_of(t: np.ndarray | None, rate: float | None, where: str) -> float:
    """The log's sample rate (Hz): ``rate`` if given, else 1 / mean step of ``t``. Refuses a
    log with gaps (the reader's rule, :data:`calib.logs.reader.GAP_FACTOR`): the Allan
    deviation of one record needs even spacing — :func:`log_segments` splits such a log
    instead (``tiltbench noise`` does)."""
    split = log_segments(t, rate, where)
    if split.gaps:
        k, t0, length = split.gaps[0]
        raise DataError(f"{where}: gap of {length:.4g} s after t = {t0:.6g} s (median step "
                        f"{split.step:.4g} s; {len(split.gaps)} gap(s), steps > "
                        f"{GAP_FACTOR:g} median steps); the Allan deviation of one record "
                        "needs evenly spaced samples: split the log at its gaps "
                        "(`tiltbench noise` does) or cut it at the gap")
    return split.rate


def stuck_axis(y: np.ndarray) -> float | None:
    """The constant value (m/s²) of a stuck axis (module docstring, :data:`STUCK_SPAN`), or
    None when its readings change."""
    y = np.asarray(y, dtype=float)
    if y.size == 0:
        return None
    hi, lo = float(np.max(y)), float(np.min(y))
    span, top = hi - lo, max(abs(hi), abs(lo))
    return float(np.median(y)) if span <= STUCK_SPAN * max(1.0, top) else None


def excess_scatter(y: np.ndarray, bounds: tuple[tuple[int, int], ...] | None = None
                   ) -> tuple[float, float]:
    """(e², allowed e²) of one axis, (m/s²)²: the variance the sample-to-sample noise does not
    explain, ``var(y) − var(Δy)/2``, and its limit ``MAX_EXCESS_STD² + EXCESS_Z·σ_d²/√n``
    (module docstring). ``bounds``: the segments of a log with gaps ((start, stop) rows): the
    differences Δy then stay inside the segments (none across a gap), var(y) is over all of
    their readings."""
    y = np.asarray(y, dtype=float)
    spans = ((0, y.size),) if bounds is None else tuple(bounds)
    n = sum(b - a for a, b in spans)
    n_d = sum(max(b - a - 1, 0) for a, b in spans)
    if n < 3 or n_d < 2:
        return 0.0, MAX_EXCESS_STD ** 2
    # two passes over pieces (no copy, no difference array the length of a long log)
    mean = sum(float(np.sum(y[a:b])) for a, b in spans) / n
    mean_d = sum(float(y[b - 1] - y[a]) for a, b in spans if b - a > 1) / n_d
    ss = ss_d = 0.0
    for a, b in spans:
        for c in range(a, b, _BLOCK_ROWS):
            piece = y[c:min(c + _BLOCK_ROWS + 1, b)]  # one row more: the step to the next
            ss += float(np.sum(np.square(piece[:_BLOCK_ROWS] - mean)))
            ss_d += float(np.sum(np.square(np.diff(piece) - mean_d)))
    white = ss_d / (n_d - 1) / 2.0
    excess = ss / (n - 1) - white
    return excess, MAX_EXCESS_STD ** 2 + EXCESS_Z * white / np.sqrt(n)


def check_static(acc: np.ndarray, rate: float, where: str, *, window: float = 1.0,
                 shift: float = WINDOW_SHIFT, var_ratio: float = 9.0,
                 gyro: np.ndarray | None = None, max_rate: float = MAX_RATE,
                 axes: tuple[str, ...] | None = None,
                 segments: tuple[tuple[int, int], ...] | None = None,
                 t: np.ndarray | None = None) -> dict[str, Any]:
    """Refuse a static log that cannot be characterized (module docstring's table: a stuck
    axis, a window shift or variance, a gyro rate above ``max_rate`` rad/s ≈ 3°/s, scatter
    that is not noise); return the check's numbers for the report.

    Parameters
    ----------
    acc : (N, k) readings, m/s².
    rate : sample rate, Hz.
    where : the file, for the messages.
    window : window of the window tests, s.
    shift : largest window-mean shift, m/s².
    var_ratio : largest window variance over the median window's.
    gyro : (N,) rate about the tilt axis, or (N, m) rates of m axes (each axis' window means
        checked), rad/s, or None.
    max_rate : largest window mean gyro rate, rad/s.
    axes : the name of each column for the messages (default x, y, …).
    segments : ((start, stop), …) rows of the stretches between the log's gaps
        (:func:`log_segments`), or None (one record). No window and no difference straddles a
        gap: the windows are laid from each segment's start (a segment's tail shorter than a
        window is left out), and all windows of all segments are compared with each other —
        the log must still be one held pose (a pose changed during a gap is refused like one
        changed within a segment).
    t : (N,) sample times, s: the messages then give a window's time in the log's clock
        (across a gap the row count no longer tells it); without it, rows / ``rate``.

    Returns
    -------
    dict : window s, thresholds, the largest window shift m/s² and variance ratio, per axis
        the excess scatter ``excess_std`` and its limit ``excess_limit`` (m/s², std).

    Raises
    ------
    DataError : one line naming ``where``, the axis and the fix.
    """
    acc = np.asarray(acc, dtype=float)
    if acc.ndim == 1:
        acc = acc[:, None]
    names = tuple(axes) if axes is not None else tuple(
        "xyz"[k] if k < 3 else str(k) for k in range(acc.shape[1]))
    for k in range(acc.shape[1]):
        value = stuck_axis(acc[:, k])
        if value is not None:
            raise DataError(
                f"{where}: axis {names[k]} reads {value:.6g} m/s² in every sample (all "
                f"{acc.shape[0]} readings within {STUCK_SPAN:g} of each other, relative): a "
                "stuck, dead or saturated axis has no noise to characterize; check the logger "
                "and its columns (--columns, --axes)")
    spans = ((0, acc.shape[0]),) if segments is None else tuple(segments)
    lag = correlation_time(acc[spans[0][0]:spans[0][1]])  # read on the first segment
    # the correlation's window leaves at least 20 windows; never shorter than asked for
    longest = max(b - a for a, b in spans)
    w = max(2, int(round(window * rate)), min(int(np.ceil(WINDOW_CORR * lag)), longest // 20))
    nwin = sum((b - a) // w for a, b in spans)
    out: dict[str, Any] = {"window": w / rate, "shift": shift, "var_ratio": var_ratio,
                           "max_shift": 0.0, "max_var_ratio": 1.0,
                           "correlation_time": lag / rate}
    if nwin >= 2:
        _check_windows(acc, rate, where, w, shift, var_ratio, gyro, max_rate, names, out,
                       spans, t)
    excess = [excess_scatter(acc[:, k], None if segments is None else spans)
              for k in range(acc.shape[1])]
    out["excess_std"] = [float(np.sqrt(max(e2, 0.0))) for e2, _ in excess]
    out["excess_limit"] = [float(np.sqrt(lim2)) for _, lim2 in excess]
    for k, (e2, lim2) in enumerate(excess):
        if e2 > lim2:
            noise = float(np.sqrt(max(np.var(acc[:, k], ddof=1) - e2, 0.0)))
            raise DataError(
                f"{where}: not a static log: axis {names[k]} scatters by {np.sqrt(e2):.3g} "
                f"m/s² (std) beyond its sample-to-sample noise ({noise:.3g} m/s²; limit "
                f"{np.sqrt(lim2):.3g} m/s²): the sensor moved, was carried or shaken during "
                "the log; `tiltbench noise` needs one held pose: record it lying still, or "
                "cut the log to a still stretch")
    return out


def correlation_time(acc: np.ndarray) -> int:
    """The longest over the axes of the first lag (samples) where the autocorrelation of the
    readings, a straight line removed, falls below 1/e: 1 for white noise, about the filter's
    time constant for a low-pass filtered log; read on the first :data:`CORR_SAMPLES`
    readings (module docstring: A filtered log)."""
    y = np.asarray(acc[:CORR_SAMPLES], dtype=float)
    if y.ndim == 1:
        y = y[:, None]
    n = y.shape[0]
    if n < 16:
        return 1
    t = np.arange(n, dtype=float)
    a = np.column_stack([np.ones(n), t - t.mean()])
    y = y - a @ np.linalg.lstsq(a, y, rcond=None)[0]
    # lag 1 first (O(n)): below 1/e on every axis — a white log, most logs — is the answer
    # without the FFT of every lag
    zero = np.einsum("ij,ij->j", y, y)
    one = np.einsum("ij,ij->j", y[1:], y[:-1])
    if np.all(one < np.exp(-1.0) * zero):
        return 1
    acf = lagged_sums(y, n // 2 - 1)
    acf = acf / np.where(acf[0] > 0, acf[0], 1.0)
    below = acf < np.exp(-1.0)
    first = np.where(below.any(axis=0), np.argmax(below, axis=0), n // 2)
    return int(max(1, first.max()))


def _window_stats(acc: np.ndarray, a: int, w: int, nwin: int
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(means (nwin, k), variances (nwin, k)) of ``nwin`` windows of ``w`` rows from row
    ``a`` (a view of the readings: no copy of a long log)."""
    k = acc.shape[1]
    means, var = np.empty((nwin, k)), np.empty((nwin, k))
    step = max(1, _BLOCK_ROWS // w)  # windows per piece: temporaries of ≈ _BLOCK_ROWS rows
    for i in range(0, nwin, step):
        j = min(i + step, nwin)
        blocks = acc[a + i * w:a + j * w].reshape(j - i, w, k)
        means[i:j] = blocks.mean(axis=1)
        centred = blocks - means[i:j, None, :]  # np.var would take the means again
        var[i:j] = np.einsum("ijk,ijk->ik", centred, centred) / (w - 1)
    return means, var


def _check_windows(acc: np.ndarray, rate: float, where: str, w: int, shift: float,
                   var_ratio: float, gyro: np.ndarray | None, max_rate: float,
                   names: tuple[str, ...], out: dict[str, Any],
                   spans: tuple[tuple[int, int], ...], t: np.ndarray | None) -> None:
    """The window tests of :func:`check_static` (windows of ``w`` samples laid from the start
    of each span of rows); their numbers go into ``out``."""
    parts = [(a, (b - a) // w) for a, b in spans if (b - a) // w > 0]
    stats = [_window_stats(acc, a, w, count) for a, count in parts]
    means = np.concatenate([m for m, _ in stats])
    var = np.concatenate([v for _, v in stats])
    del stats
    starts = np.concatenate([a + w * np.arange(count) for a, count in parts])
    nwin = means.shape[0]

    def when(k: int) -> float:  # the window's time: the log's clock, else rows / rate
        return float(t[starts[k]]) if t is not None else starts[k] / rate

    # the spread of the window means (largest minus smallest): a pose change anywhere,
    # also halfway through, shows in full (a distance to the median would halve it)
    dev = means - means.min(axis=0)
    med_var = np.median(var, axis=0)
    ratio = var / np.where(med_var > 0, med_var, np.inf)
    if gyro is not None:
        g = np.asarray(gyro, dtype=float)
        g = g.reshape(g.shape[0], -1)
        spin = np.abs(np.concatenate([g[a:a + count * w].reshape(count, w, -1).mean(axis=1)
                                      for a, count in parts])).max(axis=1)
        out["max_rate"], out["max_gyro_rate"] = max_rate, float(spin.max())
        if spin.max() > max_rate:
            k = int(np.argmax(spin))
            raise DataError(f"{where}: not a static log: in the {w / rate:g} s window at "
                            f"t = {when(k):.4g} s the gyro reads {spin[k]:.3g} rad/s "
                            f"(limit {max_rate:g} rad/s); `tiltbench noise` needs one held "
                            "pose: cut the log to a still stretch")
    out["max_shift"] = float(dev.max())
    out["max_var_ratio"] = float(ratio.max()) if np.isfinite(ratio).all() else float("inf")
    # A noisy sensor's window means scatter by σ/√w on their own: the range of nwin of them
    # stays below (2·sqrt(2 ln nwin) + 3)·σ/√w except with probability ≲ 1e-3 (extreme-value
    # bound of a Gaussian sample's range), so the shift limit is never below that floor.
    floor = (2.0 * np.sqrt(2.0 * np.log(max(nwin, 2))) + 3.0) * np.sqrt(med_var / w)
    limit_shift = np.maximum(shift, floor)
    out["shift_noise_floor"] = [float(v) for v in floor]
    for bad, what, limit in ((dev > limit_shift,
                              "mean is {v:.3g} m/s² above the lowest window mean",
                              f"--static-shift {shift:g} m/s², or the noise floor "
                              f"{float(np.max(floor)):.3g} m/s² where larger"),
                             (ratio > var_ratio, "variance is {v:.3g}× the median window's",
                              f"--static-var-ratio {var_ratio:g}")):
        if bad.any():
            k, ax = np.argwhere(bad)[0]
            v = (dev if "mean" in what else ratio)[k, ax]
            raise DataError(
                f"{where}: not a static log: in the {w / rate:g} s window at "
                f"t = {when(int(k)):.4g} s, axis {names[ax]}'s "
                + what.format(v=v) + f" (limit {limit}); `tiltbench noise` needs one held "
                "pose: cut the log to a still stretch")

__all__ = ["EXCESS_Z", "MAX_EXCESS_STD", "MAX_RATE", "SEGMENT_STEP_TOLERANCE", "STUCK_SPAN",
           "WINDOW_SHIFT", "LogSegments", "check_static", "excess_scatter", "log_segments",
           "quantization_step", "sample_rate_of", "stuck_axis"]
