"""The named effects of an axis or one step of the bias? Told apart when the run can.

On a run whose angle follows the clock — a stop-and-go tour that turns one way, a sweep, a
pose tour in order — a function of time is a function of θ: a bias that jumps once (a
connector, a supply that switches) at t₀ is ``[t ≥ t₀]``, and the catalog's columns that
follow the angle (misalignment, K2, the cross-axis term, …) with a drift in time take it
between them, with a consistent gap after (the drive part's seed 11: a step at z = 6 on a
stop-and-go run named as a drift, K2, the cross-axis term and a misalignment of y). A walk
named there is reviewed against steps by the walk's own review (:mod:`calib.gap.walk`); the
structured effects are reviewed here.

The structured effects named on axis k (:data:`SWAPPED`: :data:`calib.gap.cubic.SWAPPED` and
the drift) are removed from the final model and one step column ``[k ≥ i]`` is fitted in
their place (:class:`calib.gap.space.AxisSpace`: in the model's whitened space, every other
parameter refitted), its place i the best of every place at least
:data:`calib.gap.steps.MIN_SEGMENT` samples from either end (:meth:`AxisSpace.step_scan`:
cumulative sums, O(N·p) for all of them), the best tested alone. The step is charged its
size and its place, ``1 + ln N`` (:func:`calib.gap.walk.step_charge`, as the walk's steps
are), the effects their parameters p:

    D = (LR_step − 2·(1 + ln N)) − (LR_named − 2p)

read by :func:`calib.gap.swaps.tier` as the other swaps: ``"leans"`` beyond
:data:`calib.gap.walk.LEAN_MARGIN` (the effects are not named; the verdict is "unexplained"
with the step in words), ``"describes"`` above 0 and ``"ties"`` above ``−AMBIGUITY_LR`` (the
pair is listed in ``not_identifiable``). A true catalog effect is a column of the model
itself; a step must then beat it by the place's charge, which a function of the angle on
several poses does not give it. Not on an axis with a walk (its own review), nor with a
sensor profile's fixed walk.

Why by hand: a swap of columns in this model's own whitened space; no library knows it.
"""

from __future__ import annotations

import numpy as np

from calib.conventions import AXES
from calib.effects import Extensions, ModelState
from calib.gap import cubic, swaps
from calib.gap.steps import MIN_SEGMENT, StepFit, describe
from calib.gap.swaps import FITS, leaning, swap_base, tier
from calib.gap.walk import step_charge

STEP = "bias_step"
"""The name beside the swapped effects in ``not_identifiable`` (not a catalog effect)."""

SWAPPED = (*cubic.SWAPPED, "bias_drift")
"""Named per-axis effects a step of the bias may stand for on a run whose angle follows the
clock: those whose columns follow the angle or the motion, and the drift in time."""


def named_or_step(ext: Extensions, state: ModelState, k: int, named: list[str]
                  ) -> dict | None:
    """The effects of :data:`SWAPPED` in ``named`` (named on axis k) against one step of the
    bias in their place (module docstring).

    Returns ``{"axis", "names", "decision": "ties" | "describes" | "leans", "gain" (D, 1),
    "step" (m/s²), "at" (s, or the sample index without timing), "size" (|step|, m/s²),
    "description", "reason"}``, or None when none of them is named on axis k, the axis has a
    walk, or ``D ≤ −AMBIGUITY_LR``.
    """
    axis = AXES[k]
    names = [n for n in SWAPPED if n in named and (n, axis) in state.effects()]
    if not names or state.axes[k].q > 0:
        return None
    run = ext.run
    if run.n < 2 * MIN_SEGMENT + 1:
        return None
    space, lr_named, cost = swap_base(ext, state, k, names)
    gains = space.step_scan()  # entry i − 1: the step at place i
    if gains is None:
        return None
    best = MIN_SEGMENT + int(np.argmax(gains[MIN_SEGMENT - 1:run.n - MIN_SEGMENT]))
    fit = space.test((np.arange(run.n) >= best).astype(float)[:, None])
    if fit is None:
        return None
    gain = (float(fit[0]) - 2.0 * step_charge(run.n)) - (lr_named - 2.0 * cost)
    decision = tier(gain)
    if decision is None:
        return None
    size = float(fit[2][0])
    sigma = float(np.sqrt(state.axes[k].sigma2_eff))
    # one step's words read its place and size only (the levels are the model's, not a path's)
    shape = describe(StepFit(np.array([best]), np.zeros(2), np.array([size]), float(fit[0]),
                             sigma, run.n), run.tcol, run.time_unit, axis)
    them = " + ".join(names)
    reason = (f"cannot tell {them} from {shape} on this run: the step alone fits "
              f"{FITS[decision]} (AIC gain {gain:.3g} over their {cost:g} parameter(s), the "
              f"step charged its size and its place, 1 + ln N = {step_charge(run.n):.3g}); a "
              "run whose angle does not follow the clock (back and forth, or the poses in "
              "another order) separates them")
    description = leaning(shape, "explains the reading", them, gain, "the named set",
                          "step of the bias", "they are")
    at = float(run.tcol[best]) if run.time_unit == "s" else float(best)
    return {"axis": axis, "names": names, "decision": decision, "gain": float(gain),
            "step": size, "at": at, "size": abs(size), "description": description,
            "reason": reason}


def signature(found: dict) -> dict:
    """The ``unexplained`` entry of effects a step of the bias leans against."""
    return swaps.signature(found, STEP, "step of the bias")
