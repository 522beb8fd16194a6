"""Degenerate calibration data, told in the user's terms before any fit runs.

A calibration run only carries information when each sensor sees gravity turn with the table.
These checks run where an ensayo enters (:func:`calib.files.course.validate_ensayo`) and say what is
wrong with the *data* — a dead sensor, a column that does not follow the table, too few
poses — instead of letting a solver fail later ("SVD did not converge", "scale must be > -1
… got -16605").

Rules (per axis k ∈ {x, y}; nominal course model ``A_mk = bias_k + K_k · A_rk(θ)`` with the
gain ``K_k = 1 + scale_k``, ``A_rx = -g sin θ``, ``A_ry = -g cos θ``, g = :data:`G`):

1. **distinct θ**: at least :data:`MIN_DISTINCT_THETA` = 2 distinct table angles — with one
   pose, bias and scale are confounded on both axes. (Three are needed to tell radians from
   degrees, :mod:`calib.files.angles`; with two the file is read as radians.) θ values are compared
   exactly as stored: a float32 file converts to float64 exactly, so equal angles stay equal
   in the file's own precision.
2. **dead sensor**: a column whose readings are all equal (to :data:`CONSTANT_TOL` m/s²) while
   its reference ``A_rk`` varies over the run.
3. **no gravity signal**: the least-squares gain of the column on its reference is
   *definitely* below :data:`MIN_GAIN` — ``K̂_k + 3·se(K̂_k) < MIN_GAIN`` — pure noise, the
   wrong column or file (e.g. x and y swapped), a sign flip (``K̂ ≈ -1``: the reading follows
   ``+g sin θ``). ``se`` is the standard error of the slope, ``σ̂/‖A_rk - mean A_rk‖``, with
   the noise level ``σ̂² = RSS/(N - rank)`` of the column fitted on ``[1, sin θ, cos θ]``: the
   noise whichever gravity component the column follows, so the signal of a swapped column
   is not mistaken for noise (which would widen ``se`` and let it through). The bound is
   deliberately loose: :data:`MIN_GAIN` = 0.05 accepts a local g down to 5 % of 9.8 m/s²
   (Pluto's 0.62 m/s² passes) and a strongly mis-scaled sensor; an axis whose θ range is
   too small to determine the gain (large ``se``) is never refused here —
   :mod:`calib.calibration.ls` reports it as poorly identified. Readings that follow the reference
   are never refused: their gain is ≈ 1 ± a few se.

Magnitudes (:data:`MAX_ABS_READING`, :data:`MAX_ABS_THETA`) are checked first so that the
fits below cannot overflow.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from calib.conventions import AXES, G
from calib.input_rules import MAX_ABS_ACCEL, DataError

MIN_DISTINCT_THETA = 2
"""Fewest distinct θ a calibration needs (bias and scale per axis)."""

MIN_GAIN = 0.05
"""Smallest plausible gain ``1 + scale`` (dimensionless): below it there is no gravity signal."""

GAIN_SE = 3.0
"""Standard errors of the fitted gain allowed above :data:`MIN_GAIN` before refusing."""

CONSTANT_TOL = 1e-9 * G
"""Readings spanning no more than this (m/s²) are constant: a dead sensor."""

MAX_ABS_READING = MAX_ABS_ACCEL
"""Largest |reading| accepted, m/s² (≈ 10⁸ g: no accelerometer; a units or file error)."""

MAX_ABS_THETA = 2.0**33
"""Largest |θ| accepted, rad (≈ 8.6·10⁹): beyond it float64 cannot resolve 1 µrad."""


class DegenerateDataError(DataError):
    """Calibration data that cannot determine the sensor errors (message says why)."""


_REF_NAME = {"x": "−g sin θ", "y": "−g cos θ"}


def refuse_beyond(values: np.ndarray, limit: float, message: Callable[[float], str],
                  error: type[DataError] = DegenerateDataError) -> None:
    """Raise ``error(message(big))`` when the largest magnitude ``big = max |values|`` (0 for
    no values; the values' unit) exceeds ``limit``: the one test of a plausible size."""
    big = float(np.max(np.abs(values))) if values.size else 0.0
    if big > limit:
        raise error(message(big))


def check_magnitudes(tita: np.ndarray, datos: np.ndarray, where: str) -> None:
    """Refuse finite values too large to be angles in rad or accelerations in m/s²."""
    refuse_beyond(tita, MAX_ABS_THETA, lambda big: (
        f"{where}: variable 'tita' reaches |θ| = {big:.3g} rad; at that size a float "
        f"cannot resolve 1 µrad (spacing {np.spacing(big):.3g} rad): subtract whole "
        f"turns (2π) or check the units (limit {MAX_ABS_THETA:.3g} rad)"))
    for k, axis in enumerate(AXES):
        refuse_beyond(datos[:, k], MAX_ABS_READING, lambda big, k=k, axis=axis: (
            f"{where}: variable 'datos' column {k + 1} ({axis}) reaches |A| = {big:.3g} "
            f"m/s² ({big / G:.3g} g): not accelerations in m/s² (limit "
            f"{MAX_ABS_READING:.3g} m/s²); check the units or the file"))


def _noise_sd(tita: np.ndarray, y: np.ndarray, g: float) -> float:
    """σ̂ of ``y`` about ``b + c₁·sin θ + c₂·cos θ`` (m/s²): the noise whichever gravity
    component the column follows (a swapped column's signal is not counted as noise)."""
    n = y.shape[0]
    H = np.column_stack([np.ones(n), g * np.sin(tita), g * np.cos(tita)])
    p, _, rank, _ = np.linalg.lstsq(H, y, rcond=None)
    r = y - H @ p
    dof = n - int(rank)
    return math.sqrt(float(r @ r) / dof) if dof > 0 else math.inf


def _gain_fit(ref: np.ndarray, y: np.ndarray, sd: float) -> tuple[float, float, float]:
    """``y = b + K·ref`` by least squares on centred columns: (K, se(K), R²), with the
    standard error from the noise level ``sd`` (m/s²) rather than this fit's residuals."""
    rc = ref - ref.mean()
    yc = y - y.mean()
    norm2 = float(rc @ rc)
    gain = float(rc @ yc) / norm2
    r = yc - gain * rc
    tss = float(yc @ yc)
    r2 = 1.0 - float(r @ r) / tss if tss > 0 else 0.0
    return gain, sd / math.sqrt(norm2), r2


def check_signal(tita: np.ndarray, datos: np.ndarray, where: str, g: float = G) -> None:
    """Refuse calibration data that cannot determine bias and scale (module rules 1–3).

    Parameters
    ----------
    tita : (N,) rad, finite.  datos : (N, 2) m/s², finite, ``[A_mx, A_my]``.
    where : the file (for messages; the variables are ``tita`` and ``datos``).
    g : gravity, m/s² (only scales the reference; the gain bound allows another local g).

    Raises
    ------
    DegenerateDataError : (a ``ValueError``) naming the file, the variable, the column and
        what the data show.
    """
    check_magnitudes(tita, datos, where)
    distinct = np.unique(tita)
    if distinct.size < MIN_DISTINCT_THETA:
        raise DegenerateDataError(
            f"{where}: variable 'tita' has only {distinct.size} distinct θ "
            f"({float(distinct[0]):.6g} rad for all {tita.size} samples): a calibration needs "
            f"at least {MIN_DISTINCT_THETA} (3 to tell radians from degrees); with one pose "
            "bias and scale are confounded (scale_x, scale_y cannot be identified): tilt the "
            "table to several angles, spread over a turn")
    ref = np.column_stack([-g * np.sin(tita), -g * np.cos(tita)])
    for k, axis in enumerate(AXES):
        col, rk = datos[:, k], ref[:, k]
        if float(np.ptp(rk)) <= 1e-12 * abs(g):  # reference constant: ls names it
            continue
        if float(np.ptp(col)) <= CONSTANT_TOL:
            raise DegenerateDataError(
                f"{where}: variable 'datos' column {k + 1}: the {axis} sensor reads a "
                f"constant {float(col[0]):.6g} m/s² while θ turns the table "
                f"({_REF_NAME[axis]} spans {float(np.ptp(rk)):.3g} m/s²): dead sensor?")
        gain, se, r2 = _gain_fit(rk, col, _noise_sd(tita, col, g))
        if gain + GAIN_SE * se < MIN_GAIN:
            other = ref[:, 1 - k]
            swapped = (float(np.ptp(other)) > 1e-12 * abs(g)
                       and abs(_gain_fit(other, col, 0.0)[0] - 1.0) < 0.5)
            if swapped:
                hint = (f"they follow {_REF_NAME[AXES[1 - k]]}, the {AXES[1 - k]} reference: "
                        "are the x and y columns swapped?")
            elif gain < -0.5:
                hint = (f"the readings follow +{_REF_NAME[axis][1:]} instead (gain "
                        f"{gain:.3g}): sign flipped, sensor mounted the other way round, or "
                        "the wrong column?")
            else:
                hint = "is this the right column/file?"
            raise DegenerateDataError(
                f"{where}: variable 'datos' column {k + 1}: the {axis} readings do not follow "
                f"{_REF_NAME[axis]} at all (R² = {max(r2, 0.0):.2f}, gain 1 + scale = "
                f"{gain:.3g} ± {se:.2g}, expected ≈ 1): {hint}")
