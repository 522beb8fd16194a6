"""The checks of a static log before its noise is characterized (``tiltbench noise``): its
sample rate and even spacing (:func:`sample_rate_of`), that the table did not move
(:func:`check_static`), and the quantization step of its readings (:func:`quantization_step`).

The static check (:func:`check_static`) refuses a log in which the table moved: a window mean
more than ``shift`` m/s² above the lowest window mean (a tilt of ≈ 1.75° at 0.3 m/s²), a window
variance above ``var_ratio`` × the median window variance (handling, vibration), or, with a
gyro, a window mean rate above ``max_rate``.
The noise characterization itself: :mod:`calib.noise.allan`.
"""

from __future__ import annotations

import numpy as np

from calib.input_rules import DataError


def quantization_step(y: np.ndarray, rel_tol: float = 1e-3) -> float | None:
    """The lattice step of the readings (m/s²), or None when they are not on a lattice.

    The readings are on a lattice when they take few distinct values (at most half the
    samples) and every distinct value is ``u_0 + k·Δ`` (k integer, to ``rel_tol``·Δ), Δ the
    smallest gap between sorted distinct values (gaps below 1e-9 of the range are float
    noise of one value and merged)."""
    y = np.asarray(y, dtype=float)
    u = np.unique(y)
    if u.size < 2 or u.size > y.size // 2:
        return None
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


def check_static(acc: np.ndarray, rate: float, where: str, *, window: float = 1.0,
                 shift: float = 0.3, var_ratio: float = 9.0, gyro: np.ndarray | None = None,
                 max_rate: float = 0.05) -> dict[str, float]:
    """Refuse a log in which the table moved (module docstring; with a gyro, also a window
    whose mean rate exceeds ``max_rate`` rad/s, ≈ 3°/s); return the check's numbers (window s,
    thresholds, the largest window shift m/s² and variance ratio) for the report."""
    acc = np.asarray(acc, dtype=float)
    w = max(2, int(round(window * rate)))
    nwin = acc.shape[0] // w
    out = {"window": w / rate, "shift": shift, "var_ratio": var_ratio,
           "max_shift": 0.0, "max_var_ratio": 1.0}
    if nwin < 2:
        return out
    blocks = acc[:nwin * w].reshape(nwin, w, -1)
    means = blocks.mean(axis=1)
    # the spread of the window means (largest minus smallest): a pose change anywhere,
    # also halfway through, shows in full (a distance to the median would halve it)
    dev = means - means.min(axis=0)
    var = blocks.var(axis=1, ddof=1)
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
                f"t = {k * w / rate:.4g} s, axis {'xy'[ax] if ax < 2 else ax}'s "
                + what.format(v=v) + f" (limit {limit}); `tiltbench noise` needs one held "
                "pose: cut the log to a still stretch")
    return out


__all__ = ["check_static", "quantization_step", "sample_rate_of"]
