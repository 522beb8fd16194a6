"""The lever arm or a bias tied to the drive? Told apart when the run can.

The lever arm (catalog) adds the centripetal and tangential accelerations of a site off the
hinge: columns ``ω²`` and ``α`` (:mod:`calib.effects.linear`). A bias that the drive adds
while the table moves (not in the catalog) follows the motion too: one that grows with the
speed (``c·|ω|``, m/s² per rad/s: a rate-sensitive sensor, the motor's field growing with its
current), one present while moving (``b·m``, m the moving indicator of
:func:`calib.gap.drive_state.drive_state`) or one that follows the acceleration's size
(``c·|α|``). On stop-and-go moves at one cruise speed ``ω²`` is nearly ``ω_max·|ω|``, and the
lever arm takes such a bias with a consistent gap after: the drive-state checks of the battery
then see only what is left.

So a lever arm named on axis k is swapped for each of the three columns in turn
(:func:`calib.gap.swaps.swap_gain`: in the whitened space of the model without it, every other
parameter refitted). The column costs one parameter, the choice of the best of three
``2·ln 3``, the lever arm its two, so the AIC gain is
``D = max_c (LR_c − 2) − 2·ln 3 − (LR_lever − 4)`` (``−2 log L``), read as the walk's steps are
(:data:`calib.gap.walk.LEAN_MARGIN`):

* ``D ≤ −AMBIGUITY_LR`` (2 ln 10, :mod:`calib.gap.confusions`): nothing to say;
* ``−AMBIGUITY_LR < D ≤ 0`` (``"ties"``, since stop 47): the lever arm fits better, but
  within the likelihood ratio of 10 under which two catalog explanations are listed as not
  told apart; the pair is listed as for ``"describes"``;
* ``0 < D ≤ LEAN_MARGIN`` (``"describes"``): the lever arm stays named and
  ``not_identifiable`` lists it beside the bias (``speed_bias``, ``move_bias``,
  ``accel_bias``);
* ``D > LEAN_MARGIN`` (``"leans"``): the bias fits better by a likelihood ratio beyond e³ ≈ 20
  after the charges, so the lever arm is **not named** and the verdict is "unexplained: … while
  the table moves" with the bias in words; the pair is listed.

A true lever arm has a tangential part ``α`` that is odd in the acceleration, which none of
the three even columns follows, and a centripetal part that differs from ``|ω|`` wherever the
speed varies: it keeps its name unless the run has neither.

The same review stands a **random walk** named on an axis against the three columns
(:func:`walk_or_drive_bias`; the walk charged its one parameter q, its path integrated out as
in the selection): on a stop-and-go run or a shuttle a bias present while the table moves is a
square wave in time, which a walk follows step by step, and the walk's own review (steps,
two-level switching) at best lists the pair. A true walk wanders in the held stretches as in
the moving ones and rarely follows the moving indicator better than itself after the charges
(the drive part's catalog walks and ``python -m validation.switching.score --analysis``,
``docs/gap.md``).

Why by hand: a swap of columns in this model's own whitened space; no library knows it.
"""

from __future__ import annotations

import numpy as np

from calib.conventions import AXES
from calib.effects import Extensions, ModelState
from calib.gap import cubic, swaps
from calib.gap.drive_state import drive_state, where_moving
from calib.gap.swaps import FITS, leaning, swap_base, swap_gain, tier

LEVER = "lever_arm"
BIASES = ("speed_bias", "move_bias", "accel_bias")
"""The names beside the lever arm in ``not_identifiable`` (not catalog effects), in the order
of :func:`_columns`."""


def _columns(run, moving: np.ndarray | None) -> dict[str, np.ndarray]:
    """The drive-state bias columns of a timed run: ``|ω|`` (rad/s), the moving indicator
    ``moving`` (when the run has moving and held stretches) and ``|α|`` (rad/s²)."""
    cols = {"speed_bias": np.abs(run.omega)}
    if moving is not None:
        cols["move_bias"] = moving.astype(float)
    cols["accel_bias"] = np.abs(run.alpha)
    return cols


def _shape(name: str, axis: str, coef: float, run, moving: np.ndarray | None
           ) -> tuple[str, float]:
    """The bias in words and its largest size, m/s²."""
    if name == "speed_bias":
        top = float(np.max(np.abs(run.omega)))
        size = abs(coef) * top
        return (f"a bias on {axis} that grows with the rotation rate while the table moves: "
                f"{coef:+.3g} m/s² per rad/s of |ω| ({coef * top:+.3g} m/s² at the top speed "
                f"{top:.3g} rad/s; a rate-sensitive sensor or the drive's field)"), size
    if name == "move_bias":
        where = where_moving(run, moving)
        return (f"a bias on {axis} of {coef:+.3g} m/s² while the table moves, {where} "
                "(the drive's field or a cable pulling the sensor)"), abs(coef)
    top = float(np.max(np.abs(run.alpha)))
    size = abs(coef) * top
    return (f"a bias on {axis} that follows the size of the acceleration while the table "
            f"moves: {coef:+.3g} m/s² per rad/s² of |α| ({coef * top:+.3g} m/s² at "
            f"{top:.3g} rad/s²; the drive's current, whichever the direction)"), size


def lever_or_drive_bias(ext: Extensions, state: ModelState, k: int) -> dict | None:
    """A lever arm named on axis k against a bias tied to the drive in its place (module
    docstring).

    Returns ``{"axis", "names": ["lever_arm"], "bias" (the name of the best column),
    "decision": "ties" | "describes" | "leans", "gain" (D, 1), "coefficient" (m/s² per rad/s,
    per 1 or per rad/s² as ``bias`` is speed_bias, move_bias or accel_bias), "size" (its
    largest effect, m/s²), "description", "reason"}``, or None when no lever arm is named on
    axis k, the run has no sample times, or ``D ≤ −AMBIGUITY_LR``.
    """
    if (LEVER, AXES[k]) not in state.effects():
        return None
    return _against_drive_bias(ext, state, k, [LEVER])


WALK = "bias_random_walk"


def walk_or_drive_bias(ext: Extensions, state: ModelState, k: int) -> dict | None:
    """A random walk named on axis k against a bias tied to the drive in its place (module
    docstring): the lever arm's review with the walk's one parameter,
    ``D = max_c (LR_c − 2) − 2·ln 3 − (LR_walk − 2)``, ``LR_walk`` its marginal likelihood
    ratio. Returns the dict of :func:`lever_or_drive_bias` (``names``: the walk), or None when
    no walk is named on axis k, a sensor profile states its q (``ext.walk_bounds``: the walk
    is the sensor's known noise, not a fitted explanation), the run has no sample times, or
    ``D ≤ −AMBIGUITY_LR``."""
    if (WALK, AXES[k]) not in state.effects() or k in getattr(ext, "walk_bounds", {}):
        return None
    return _against_drive_bias(ext, state, k, [WALK])


STRUCTURED = tuple(n for n in cubic.SWAPPED if n != LEVER)
"""Named per-axis effects whose columns follow the table's angle (K2, the cross-axis term, a
misalignment, saturation, low-pass lag): on a shuttle between two poses or a tour at one speed
the moving indicator, |ω| and |α| are functions of θ too, and they take a bias tied to the
drive as the lever arm does (the drive part's seed 12: a bias while moving at z = 5 on a
one-speed shuttle named a misalignment of y; the bias fits better by D = 16.6)."""


def structured_or_drive_bias(ext: Extensions, state: ModelState, k: int, named: list[str]
                             ) -> dict | None:
    """The effects of :data:`STRUCTURED` in ``named`` (named on axis k), all together, against
    a bias tied to the drive in their place: the lever arm's review (module docstring) with
    their parameters p, ``D = max_c (LR_c − 2) − 2·ln 3 − (LR_named − 2p)``, the same tiers.
    Returns the dict of :func:`lever_or_drive_bias` with their names, or None when none of
    them is named on axis k, the run has no sample times, or ``D ≤ −AMBIGUITY_LR``."""
    names = [n for n in STRUCTURED if n in named and (n, AXES[k]) in state.effects()]
    return _against_drive_bias(ext, state, k, names) if names else None


def _against_drive_bias(ext: Extensions, state: ModelState, k: int, names: list[str]
                        ) -> dict | None:
    """The named effects ``names`` of axis k against each drive-state bias column in their
    place, the best of them charged ``2·ln 3`` for the choice (module docstring)."""
    axis = AXES[k]
    run = ext.run
    if run.omega is None or run.alpha is None:
        return None
    moving = drive_state(run.tita)
    cols = _columns(run, moving)
    base = swap_base(ext, state, k, names)  # the model without them: once for the columns
    found = {name: f for name, c in cols.items()
             if np.ptp(c) > 0.0 and (f := swap_gain(ext, state, k, names, c, base)) is not None}
    if not found:
        return None
    best = max(found, key=lambda name: found[name][0])
    gain = found[best][0] - 2.0 * float(np.log(len(cols)))
    decision = tier(gain)
    if decision is None:
        return None
    coef, cost = found[best][1], found[best][2]
    shape, size = _shape(best, axis, coef, run, moving)
    if names == [LEVER]:
        them, held, dropped = "the lever arm", "the lever arm", "the lever arm is"
        parts, split = "the lever arm's 2 parameters", "moves at several speeds, each way"
    elif names == [WALK]:
        them, held, dropped = "a random walk", "the random walk", "it is"
        parts = "the walk's 1 parameter q, its path integrated out"
        split = ("long holds, where a walk wanders and a drive bias does not, and moves at "
                 "irregular times")
    else:
        them, held, dropped = " + ".join(names), "the named set", "they are"
        parts = f"their {cost:g} parameter(s)"
        split = "moves at several speeds, each way, and poses reached from both sides"
    reason = (f"cannot tell {them} on {axis} from {shape}: the bias fits "
              f"{FITS[decision]} (AIC gain {gain:.3g} over {parts}, the best of {len(cols)} "
              f"drive-state columns); {split} separate them")
    description = leaning(shape, "explains the reading",
                          "a lever arm" if names == [LEVER] else them, gain, held,
                          "bias tied to the drive", dropped)
    return {"axis": axis, "names": list(names), "bias": best, "decision": decision,
            "gain": gain, "coefficient": coef, "size": size, "description": description,
            "reason": reason}


def signature(found: dict) -> dict:
    """The ``unexplained`` entry of named effects (a lever arm, angle-shaped effects, a walk)
    a drive-state bias leans against."""
    return swaps.signature(found, found["bias"], "a bias tied to the drive")
