"""The physics every still log obeys: a sensor at rest reads 1 g of specific force.

A unit mistake does not show in the numbers' shape — a log in g labelled m/s² calibrates with
gains near 0.1, one in m/s² labelled g with gains near 10 — but it shows at rest: the held
samples (the detected or labelled poses; the whole log when none) must read about
``g_local``::

    0.8 ≤ median ‖a‖ / g ≤ 1.25        (three axes: ‖[a_x, a_y, a_n]‖)

The band is wide on purpose: local gravity varies by ±0.3 %, a sensor's scale error is a few
percent, and a unit mistake is a factor 9.8, 1000 or a wrong counts-per-g. With the two
tilt-plane axes only, gravity may leave the plane (a board lying flat reads ≈ 0 on x and y),
so only the upper side is checked, and the lower side when the log is a calibration run in
the tilt plane (read as an ``ensayo``, or giving θ: gravity turns in that plane, some pose
reads ≈ 1 g).
The message names the likely unit.
"""

from __future__ import annotations

import numpy as np

from calib.conventions import STANDARD_GRAVITY
from calib.input_rules import DataError

ONE_G_BAND: tuple[float, float] = (0.8, 1.25)
"""Accepted ratio of the still magnitude to g (module docstring)."""

_LIKELY = (  # (ratio of what is read to what is expected, what it suggests)
    (1.0 / STANDARD_GRAVITY, "the numbers look like g: give --units g (or fix the header)"),
    (STANDARD_GRAVITY, "the numbers look like m/s² read as g: give --units m/s2 (or fix the "
                       "header)"),
    (1e-3, "the numbers look like g read as mg: give --units g"),
    (1e3, "the numbers look like mg read as g: give --units mg"),
    # m/s² numbers taken for mg read 1e-3 · g₀ m/s² per m/s²: g₀/1000 of the truth; mg
    # numbers taken for m/s² read 1000/g₀ times it
    (STANDARD_GRAVITY / 1e3, "the numbers look like m/s² read as mg: give --units m/s2"),
    (1e3 / STANDARD_GRAVITY, "the numbers look like mg read as m/s²: give --units mg"),
)


def _advice(ratio: float, units: str | None, sensitivity: float | None) -> str:
    for r, text in _LIKELY:
        if abs(np.log(ratio / r)) < np.log(1.3):
            return text
    if units == "counts" and sensitivity:
        return (f"check --sensitivity: the still readings give {sensitivity * ratio:.4g} counts "
                f"per g, not {sensitivity:g}")
    return "check the unit (--units m/s2|g|mg|counts, --sensitivity) and the columns"


def check_one_g(acc: np.ndarray, acc_normal: np.ndarray | None, pose: np.ndarray | None,
                g: float, where: str, *, tilt_plane: bool = False, units: str | None = None,
                sensitivity: float | None = None) -> None:
    """DataError when the log at rest does not read about ``g`` m/s² (module docstring).

    Parameters
    ----------
    acc : (N, 2) m/s², the tilt-plane axes after unit conversion.
    acc_normal : (N,) m/s², the third axis, or None.
    pose : (N,) held-pose labels (-1 moving), or None: every sample counts as still.
    g : local gravity, m/s².
    where : the file, for the message.
    tilt_plane : a calibration run in the tilt plane (gravity turns in it).
    units, sensitivity : the unit read and the counts per g, for the advice.
    """
    held = np.ones(len(acc), dtype=bool) if pose is None else np.asarray(pose) >= 0
    if not np.any(held):
        held = np.ones(len(acc), dtype=bool)
    lo, hi = ONE_G_BAND
    if acc_normal is not None:
        # |a|² summed in one new array (no copies of the held rows when every row is held: a
        # static log read by `noise`), the median taken in place
        every = bool(held.all())
        a2, an = (acc, acc_normal) if every else (acc[held], acc_normal[held])
        sq = np.einsum("ij,ij->i", a2, a2)
        sq += np.square(an)
        np.sqrt(sq, out=sq)
        mag = float(np.median(sq, overwrite_input=True))
        low_checked = True
    else:
        labels = pose[held] if pose is not None and np.any(np.asarray(pose) >= 0) else None
        if labels is None:
            mag = float(np.median(np.linalg.norm(acc[held], axis=1)))
        else:  # the largest pose: the one where gravity lies most in the plane
            mag = max(float(np.linalg.norm(acc[held][labels == k].mean(axis=0)))
                      for k in np.unique(labels))
        low_checked = tilt_plane
    ratio = mag / g
    if ratio > hi or (low_checked and ratio < lo):
        axes = "three axes" if acc_normal is not None else "the tilt-plane axes"
        raise DataError(f"{where}: at rest the sensor reads {mag:.4g} m/s² on {axes}, where "
                        f"a still sensor reads 1 g ≈ {g:.4g} m/s² (×{ratio:.3g}); "
                        f"{_advice(ratio, units, sensitivity)}")


__all__ = ["ONE_G_BAND", "check_one_g"]
