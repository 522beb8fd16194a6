"""A noise level, or noise that the drive adds while the table moves? Told apart when the run can.

``noise_level`` (catalog) fits one white-noise variance σ² for the whole run in place of the
stated one. Noise that the drive adds (a vibration, the motor's electrical noise; not in the
catalog) is there only while the table moves: the stated variance s² while it holds, a larger
one while it moves. On a run with both drive states the selection takes such noise as a noise
level, and the battery's ``drive_variance`` (``s²_moving / s²_held``, both free) sees it only
when the held stretches are long enough to pin their own variance.

So a noise level named on axis k is set beside that rival, both on the final model's residuals
``e`` (m/s²; their regression parameters as fitted), with ``n_m``, ``n_h`` the moving and held
samples (:func:`calib.gap.drive_state.drive_state`), ``S_m``, ``S_h`` their sums of ``e²`` and
``s² = σ²_stated + lsb²/12``, each at its maximum likelihood (``-2 log L``, constants dropped):

* noise level: one variance ``σ̂² = (S_m + S_h)/n``: ``n·log σ̂² + n``;
* noise while moving: ``s²`` while held, ``v̂ = max(S_m/n_m, s²)`` while moving (noise added
  to the sensor's own, never less): ``n_h·log s² + S_h/s² + n_m·log v̂ + S_m/v̂``.

Each has one free parameter, so ``D`` = the first minus the second is the AIC gain of the rival
(the choice between them is the only search: no charge), read by
:func:`calib.gap.swaps.tier` as the other reviews are: beyond
:data:`calib.gap.walk.LEAN_MARGIN` the noise level is not named and the verdict is
"unexplained: noise larger while moving …" with where and how big; above ``−AMBIGUITY_LR`` the
pair is listed in ``not_identifiable``.

A true noise level raises the held stretches' variance too: ``D ≈ −n_h·(r − 1 − ln r)`` for
``r = σ²/s²`` (about −19 at r = 1.3 over 500 held samples), so it keeps its name unless the
held stretches are short. A noise level below the stated one (r < 1) cannot be noise added
while moving. Axes with a random walk are left out (their residuals are not white).

Why by hand: a comparison of two variance models on this bench's drive states; no library
conditions a variance on the held stretches of an encoder.
"""

from __future__ import annotations

import numpy as np

from calib.conventions import AXES
from calib.effects import Extensions, ModelState
from calib.gap import swaps
from calib.gap.drive_state import drive_state, where_moving
from calib.gap.swaps import FITS, leaning, tier

LEVEL = "noise_level"
RIVAL = "move_noise"
"""The name beside the noise level in ``not_identifiable`` (not a catalog effect)."""


def gain(resid: np.ndarray, moving: np.ndarray, s2: float) -> tuple[float, float]:
    """(D, v̂) of the module docstring: the rival's AIC gain over the noise level (1) and its
    variance while moving, (m/s²)², from residuals ``resid`` (m/s²), the moving mask and the
    stated variance ``s2``."""
    e2 = np.asarray(resid, dtype=float) ** 2
    n, n_m = e2.size, int(np.sum(moving))
    n_h = n - n_m
    s_m, s_h = float(np.sum(e2[moving])), float(np.sum(e2[~moving]))
    level = n * np.log((s_m + s_h) / n) + n
    v = max(s_m / n_m, s2)
    rival = n_h * np.log(s2) + s_h / s2 + n_m * np.log(v) + s_m / v
    return float(level - rival), float(v)


def level_or_drive_noise(ext: Extensions, state: ModelState, k: int, resid: np.ndarray
                         ) -> dict | None:
    """A noise level named on axis k against noise added while the table moves (module
    docstring); ``resid`` the final model's residuals of axis k, m/s².

    Returns ``{"axis", "names": ["noise_level"], "rival": "move_noise", "decision": "ties" |
    "describes" | "leans", "gain" (D, 1), "moving_std" (√v̂, m/s²), "stated_std" (s, m/s²),
    "size" (the added noise's std √(v̂ − s²), m/s²), "description", "reason"}``, or None when
    no noise level is named on axis k, the axis has a random walk, the run lacks a drive state
    or ``D ≤ −AMBIGUITY_LR``.
    """
    axis = AXES[k]
    st = state.axes[k]
    if (LEVEL, axis) not in state.effects() or st.q > 0:
        return None
    moving = drive_state(ext.run.tita)
    if moving is None:
        return None
    s2 = st.sigma2_stated + st.lsb**2 / 12.0
    d, v = gain(resid, moving, s2)
    decision = tier(d)
    if decision is None:
        return None
    added = float(np.sqrt(max(v - s2, 0.0)))
    where = where_moving(ext.run, moving)
    shape = (f"noise on {axis} larger while the table moves, {where}: std "
             f"{np.sqrt(v):.3g} m/s² against the stated {np.sqrt(s2):.3g} m/s² while it holds "
             f"(an added noise of std {added:.3g} m/s²: a vibration of the drive or the "
             "motor's electrical noise)")
    reason = (f"cannot tell a noise level on {axis} from {shape}: the moving-only noise fits "
              f"{FITS[decision]} (AIC gain {d:.3g}, one variance each); longer holds between "
              "the moves separate them")
    description = leaning(shape, "explains the residuals", "one noise level", d,
                          "the noise level", "noise tied to the drive", "the noise level is")
    return {"axis": axis, "names": [LEVEL], "rival": RIVAL, "decision": decision, "gain": d,
            "moving_std": float(np.sqrt(v)), "stated_std": float(np.sqrt(s2)), "size": added,
            "description": description, "reason": reason}


def signature(found: dict) -> dict:
    """The ``unexplained`` entry of a noise level that moving-only noise leans against."""
    return swaps.signature(found, RIVAL, "noise larger while the table moves")
