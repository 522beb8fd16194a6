"""The named effects of an axis or a third-order term K3? Told apart when the run can.

IEEE Std 1293's accelerometer model has a third-order term ``K3·A_r³`` beside K2; the catalog
does not. On a turn ``sin³ θ = (3 sin θ − sin 3θ)/4``: the scale takes the first part and a
3rd harmonic of θ remains, which the ``harmonics`` check sees — unless catalog effects bend
to follow it first. On a back-and-forth oscillation ``θ = θ₀ sin Ωt`` the lever arm's
columns (ω², α) are functions of θ too, and K2 with the lever arm (on y), or the cross-axis
term with the lever arm (on x), take a true K3 with a consistent gap after; on a few held
poses K2 or the cross-axis term alone can.

So the structured effects named on axis k (:data:`SWAPPED`: those whose columns follow the
table's angle or motion; not the bias' path, the noise or the lattice) are swapped, all
together, for the one column ``A_r³`` (m/s², the axis' reference, the course signs;
:func:`calib.gap.swaps.swap_gain`: in the whitened space of the model without them, every
other parameter refitted). K3 costs one parameter and no search, the named set its parameters
``p``, so the AIC gain of K3 is ``D = (LR_K3 − 2) − (LR_named − 2p)`` (``−2 log L``), read as
the walk's steps are (:data:`calib.gap.walk.LEAN_MARGIN`):

* ``D ≤ −AMBIGUITY_LR`` (2 ln 10, :mod:`calib.gap.confusions`): nothing to say;
* ``−AMBIGUITY_LR < D ≤ 0`` (``"ties"``, since stop 47): the named set fits better, but
  within the likelihood ratio of 10 under which two catalog explanations are listed as not
  told apart; the pair is listed as for ``"describes"``;
* ``0 < D ≤ LEAN_MARGIN`` (``"describes"``): the effects stay named and ``not_identifiable``
  lists them beside ``nonlinearity_k3``;
* ``D > LEAN_MARGIN`` (``"leans"``): K3 fits better by a likelihood ratio beyond e³ ≈ 20 after
  the charges, so the effects are **not named** and the verdict is "unexplained" with K3 in
  words; the pair is listed.

Measured through the whole analysis on runs made with numpy (``python -m
validation.asymmetry.score --k3``, ``docs/gap.md`` "The named effects or a K3").

Why by hand: a swap of columns in this model's own whitened space; no library knows it.
"""

from __future__ import annotations

import numpy as np

from calib.conventions import AXES
from calib.effects import Extensions, ModelState
from calib.gap import swaps
from calib.gap.swaps import FITS, leaning, swap_gain, tier

K3 = "nonlinearity_k3"
"""The name beside the swapped effects in ``not_identifiable`` (not a catalog effect)."""

SWAPPED = ("nonlinearity_k2", "cross_axis", "misalignment", "lever_arm", "saturation",
           "lowpass_lag")
"""Named per-axis effects whose columns follow the table's angle or motion: those a K3 may
stand for."""


def named_or_k3(ext: Extensions, state: ModelState, k: int, named: list[str]) -> dict | None:
    """The effects of :data:`SWAPPED` in ``named`` (named on axis k) against K3 in their
    place (module docstring).

    Returns ``{"axis", "names", "decision": "ties" | "describes" | "leans", "gain" (D, 1),
    "k3" (m/s² per (m/s²)³), "size" (|K3|·max|A_r|³, m/s²), "description", "reason"}``, or
    None when none of them is named on axis k, or ``D ≤ −AMBIGUITY_LR``.
    """
    axis = AXES[k]
    names = [n for n in SWAPPED if n in named and (n, axis) in state.effects()]
    if not names:
        return None
    a = np.asarray(ext.run.a_ref[:, k], dtype=float)
    found = swap_gain(ext, state, k, names, a**3)
    decision = None if found is None else tier(found[0])
    if decision is None:
        return None
    gain, k3, cost = found
    size = abs(k3) * float(np.max(np.abs(a))) ** 3
    them = " + ".join(names)
    shape = (f"a third-order term on {axis}, K3 = {k3:+.3g} (m/s²)⁻² ({size:.3g} m/s² at "
             "full scale; IEEE Std 1293's K3, not in the catalog)")
    reason = (f"cannot tell {them} from {shape} on this run: K3 alone fits "
              f"{FITS[decision]} (AIC gain {gain:.3g} over "
              f"their {cost:g} parameter(s)); a run that turns through whole turns at a "
              "steady rate separates them")
    description = leaning(shape, "explains the response", them, gain, "the named set", "K3",
                          "they are")
    return {"axis": axis, "names": names, "decision": decision, "gain": gain, "k3": k3,
            "size": size, "description": description, "reason": reason}


def signature(found: dict) -> dict:
    """The ``unexplained`` entry of effects K3 leans against."""
    return swaps.signature(found, K3, "third-order term")
