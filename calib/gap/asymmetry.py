"""K2 or a scale asymmetry? The even part of the response, told apart when the run can.

IEEE Std 1293's accelerometer model has a scale factor that differs by the sign of the input
(scale asymmetry, as in the terminology of IEEE Std 528); the catalog has the second-order
term K2 and not the asymmetry. On the axis' reference ``A_r`` (m/s², the course signs
``A_rx = −g sin θ``, ``A_ry = −g cos θ``) an asymmetric gain adds ``κ·max(A_r, 0)`` (the
gain is ``1 + s + κ`` for positive specific force, ``1 + s`` for negative; ``κ``
dimensionless), whose even part ``κ·|A_r|/2`` K2's ``K2·A_r²`` follows closely: on a turn
``|sin θ|`` and ``sin² θ`` share their ``cos 2θ`` term and part with ``cos 4θ`` (one fifth
of the amplitude). A true asymmetry is therefore named K2, and the gap after the fit is
consistent, unless the battery's ``rival_shapes`` check sees it beyond its Bonferroni level.

With K2 in the final model of axis k, its column is swapped for ``max(A_r, 0)``
(:func:`calib.gap.swaps.swap_gain`: in the whitened space of the model without K2, every
other parameter refitted). One parameter each, no search, so the AIC gain of the asymmetry is the
difference of their likelihood ratios, ``D = LR_asym − LR_K2`` (``−2 log L``), and it is read
as the walk's steps are (:data:`calib.gap.walk.LEAN_MARGIN`):

* ``D ≤ −AMBIGUITY_LR`` (2 ln 10, :mod:`calib.gap.confusions`): nothing to say;
* ``−AMBIGUITY_LR < D ≤ 0`` (``"ties"``, since stop 47): K2 fits better, but
  within the likelihood ratio of 10 under which two catalog explanations are listed as not
  told apart; the pair is listed as for ``"describes"``;
* ``0 < D ≤ LEAN_MARGIN`` (``"describes"``): K2 stays named and ``not_identifiable`` lists
  ``nonlinearity_k2`` / ``scale_asymmetry``;
* ``D > LEAN_MARGIN`` (``"leans"``): the asymmetry fits better by a likelihood ratio beyond
  e³ ≈ 20 after their (equal) charges — K2 has considerably less support — so K2 is **not
  named** and the verdict is "unexplained" with the asymmetry in words; the pair is listed.

Measured through the whole analysis on runs made with numpy (``python -m
validation.asymmetry.score``, ``docs/gap.md`` "K2 or a scale asymmetry").

Why by hand: a two-column swap in this model's own whitened space; no library knows it.
"""

from __future__ import annotations

import numpy as np

from calib.conventions import AXES
from calib.effects import Extensions, ModelState
from calib.gap import swaps
from calib.gap.swaps import FITS, leaning, swap_gain, tier

K2 = "nonlinearity_k2"
PAIR = "scale_asymmetry"
"""The name beside K2 in ``not_identifiable`` (not a catalog effect)."""


def k2_or_asymmetry(ext: Extensions, state: ModelState, k: int) -> dict | None:
    """K2 of axis k against a scale asymmetry in its place (module docstring).

    Returns ``{"axis", "decision": "ties" | "describes" | "leans", "gain" (D, 1), "asymmetry"
    (κ, 1), "size" (κ·max|A_r|, m/s²), "description", "reason"}``, or None when K2 is not in
    the model of axis k, the reference keeps one sign (no asymmetry to see) or
    ``D ≤ −AMBIGUITY_LR``.
    """
    axis = AXES[k]
    if (K2, axis) not in state.effects():
        return None
    a = np.asarray(ext.run.a_ref[:, k], dtype=float)
    if not (np.min(a) < 0.0 < np.max(a)):
        return None
    found = swap_gain(ext, state, k, [K2], np.maximum(a, 0.0))
    decision = None if found is None else tier(found[0])
    if decision is None:
        return None
    gain, kappa, _ = found
    size = abs(kappa) * float(np.max(np.abs(a)))
    shape = (f"a gain on {axis} that differs for positive and negative specific force by "
             f"{kappa:+.3g} ({100 * kappa:+.3g} %; {size:.3g} m/s² at full scale: a scale "
             "asymmetry, IEEE Std 1293)")
    reason = (f"cannot tell K2 from a scale asymmetry on {axis}: {shape} fits "
              f"{FITS[decision]} (AIC gain {gain:.3g} over "
              f"K2, one parameter each); a run whose specific force reaches both signs at "
              "more levels (poses spread over the whole turn) separates them")
    description = leaning(shape, "fits the even part of the response", "K2", gain, "K2",
                          "asymmetry", "K2 is")
    return {"axis": axis, "decision": decision, "gain": gain, "asymmetry": kappa,
            "size": size, "description": description, "reason": reason}


def signature(found: dict) -> dict:
    """The ``unexplained`` entry of a K2 the asymmetry leans against."""
    return swaps.signature(found, PAIR, "scale asymmetry")
