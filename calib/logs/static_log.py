"""The checks of a static log before its noise is characterized (``tiltbench noise``): its
sample rate and even spacing (:func:`sample_rate_of`), that every axis reads something and the
table did not move (:func:`check_static`), and the quantization step of its readings
(:func:`quantization_step`).

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
                       window's (handling, a burst of vibration)
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
The noise characterization itself: :mod:`calib.noise.allan`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from calib.input_rules import DataError

STUCK_SPAN = 1e-9
"""An axis is stuck when all its readings lie within ``STUCK_SPAN·max(1 m/s², max|y|)`` of each
other: float64 rounding and unit conversions (g, counts → m/s²) move a constant reading by a
few ulps (≈ 1e-15 relative); the finest quantizer of a logged accelerometer (a 24-bit
converter over ±2 g: 2.3e-6 m/s² ≈ 2.4e-7 g) is 200× above this span."""
MAX_EXCESS_STD = 0.3
"""Largest scatter not explained by sample-to-sample noise, m/s² (std): the same 0.3 m/s² as
the window shift (``--static-shift``: a tilt of ≈ 1.75°); a held sensor's drift over a log
(bias instability, random walk) stays far below it (0.02 m/s² for 5e-4 m/s²/√s over an
hour), a hand-held or shaken one is above it."""
EXCESS_Z = 6.0
"""The sampling error of ``e²`` allowed on top, in its standard deviations ``σ_d²/√n``: six
of them are exceeded by chance with probability ≈ 1e-9, so a noisy short log of white noise
is never refused (64 samples of σ = 0.8 m/s² allow e = 0.75 m/s²)."""


def quantization_step(y: np.ndarray, rel_tol: float = 1e-3) -> float | None:
    """The lattice step of the readings (m/s²), or None when they are not on a lattice.

    The readings are on a lattice when they take few distinct values (at most half the
    samples) and every distinct value is ``u_0 + k·Δ`` (k integer, to ``rel_tol``·Δ), Δ the
    smallest gap between sorted distinct values (gaps below 1e-9 of the range are float
    noise of one value and merged)."""
    y = np.asarray(y, dtype=float)
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


def sample_rate_of(t: np.ndarray | None, rate: float | None, where: str) -> float:
    """The log's sample rate (Hz): ``rate`` if given, else 1 / median Δt of ``t``. Refuses a
    log with gaps (a Δt above 1.5 × the median): the Allan deviation needs even spacing."""
    if t is None:
        if rate is None:
            raise DataError(f"{where}: the log has no sample times; give its rate with --rate HZ")
        return float(rate)
    t = np.asarray(t, dtype=float)
    dt = np.diff(t)
    med = float(np.median(dt))
    if not med > 0:
        raise DataError(f"{where}: sample times do not increase")
    gaps = np.nonzero(dt > 1.5 * med)[0]
    if gaps.size:
        k = int(gaps[0])
        raise DataError(f"{where}: gap of {dt[k]:.4g} s after t = {t[k]:.6g} s (median step "
                        f"{med:.4g} s; {gaps.size} gap(s)); the Allan deviation needs evenly "
                        "spaced samples: cut the log at the gap")
    if rate is not None:
        return float(rate)
    # the mean rate over the log, to 12 digits (time stamps in float carry ~1e-13 noise)
    return float(f"{(t.size - 1) / (t[-1] - t[0]):.12g}")


def stuck_axis(y: np.ndarray) -> float | None:
    """The constant value (m/s²) of a stuck axis (module docstring, :data:`STUCK_SPAN`), or
    None when its readings change."""
    y = np.asarray(y, dtype=float)
    if y.size == 0:
        return None
    span = float(np.max(y) - np.min(y))
    top = float(np.max(np.abs(y)))
    return float(np.median(y)) if span <= STUCK_SPAN * max(1.0, top) else None


def excess_scatter(y: np.ndarray) -> tuple[float, float]:
    """(e², allowed e²) of one axis, (m/s²)²: the variance the sample-to-sample noise does not
    explain, ``var(y) − var(Δy)/2``, and its limit ``MAX_EXCESS_STD² + EXCESS_Z·σ_d²/√n``
    (module docstring)."""
    y = np.asarray(y, dtype=float)
    n = y.size
    if n < 3:
        return 0.0, MAX_EXCESS_STD ** 2
    white = float(np.var(np.diff(y), ddof=1)) / 2.0
    excess = float(np.var(y, ddof=1)) - white
    return excess, MAX_EXCESS_STD ** 2 + EXCESS_Z * white / np.sqrt(n)


def check_static(acc: np.ndarray, rate: float, where: str, *, window: float = 1.0,
                 shift: float = 0.3, var_ratio: float = 9.0, gyro: np.ndarray | None = None,
                 max_rate: float = 0.05, axes: tuple[str, ...] | None = None
                 ) -> dict[str, Any]:
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
    gyro : (N,) rate about the tilt axis, rad/s, or None.
    max_rate : largest window mean gyro rate, rad/s.
    axes : the name of each column for the messages (default x, y, …).

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
    w = max(2, int(round(window * rate)))
    nwin = acc.shape[0] // w
    out: dict[str, Any] = {"window": w / rate, "shift": shift, "var_ratio": var_ratio,
                           "max_shift": 0.0, "max_var_ratio": 1.0}
    if nwin >= 2:
        _check_windows(acc, rate, where, w, shift, var_ratio, gyro, max_rate, names, out)
    excess = [excess_scatter(acc[:, k]) for k in range(acc.shape[1])]
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


def _check_windows(acc: np.ndarray, rate: float, where: str, w: int, shift: float,
                   var_ratio: float, gyro: np.ndarray | None, max_rate: float,
                   names: tuple[str, ...], out: dict[str, Any]) -> None:
    """The window tests of :func:`check_static` (windows of ``w`` samples); their numbers go
    into ``out``."""
    nwin = acc.shape[0] // w
    blocks = acc[:nwin * w].reshape(nwin, w, -1)
    means = blocks.mean(axis=1)
    # the spread of the window means (largest minus smallest): a pose change anywhere,
    # also halfway through, shows in full (a distance to the median would halve it)
    dev = means - means.min(axis=0)
    centred = blocks - means[:, None, :]  # one temporary; np.var would take the means again
    var = np.einsum("ijk,ijk->ik", centred, centred) / (w - 1)
    del centred
    med_var = np.median(var, axis=0)
    ratio = var / np.where(med_var > 0, med_var, np.inf)
    if gyro is not None:
        spin = np.abs(np.asarray(gyro, dtype=float)[:nwin * w].reshape(nwin, w).mean(axis=1))
        out["max_rate"], out["max_gyro_rate"] = max_rate, float(spin.max())
        if spin.max() > max_rate:
            k = int(np.argmax(spin))
            raise DataError(f"{where}: not a static log: in the {w / rate:g} s window at "
                            f"t = {k * w / rate:.4g} s the gyro reads {spin[k]:.3g} rad/s "
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
                f"t = {k * w / rate:.4g} s, axis {names[ax]}'s "
                + what.format(v=v) + f" (limit {limit}); `tiltbench noise` needs one held "
                "pose: cut the log to a still stretch")

__all__ = ["EXCESS_Z", "MAX_EXCESS_STD", "STUCK_SPAN", "check_static", "excess_scatter",
           "quantization_step", "sample_rate_of", "stuck_axis"]
