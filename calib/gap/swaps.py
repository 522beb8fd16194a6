"""One column in place of named effects: the AIC gain that the scale-asymmetry and the K3
reviews read (:mod:`calib.gap.asymmetry`, :mod:`calib.gap.cubic`).

The effects ``names`` named on axis k are removed from the final model and the column ``c``
(m/s² per unit of its coefficient) is fitted in their place, in the whitened space of the
model without them (:class:`calib.gap.space.AxisSpace`: every other parameter refitted). The
column costs one parameter and no search, the effects their parameters ``p``:
``D = (LR_c − 2) − (LR_named − 2p)`` (``−2 log L``). Read by :func:`tier`: beyond
:data:`calib.gap.walk.LEAN_MARGIN` the column "leans" (the effects are not named), above 0 it
"describes" and above ``−AMBIGUITY_LR`` it "ties" (either way the pair is listed in
``not_identifiable``); at or below ``−AMBIGUITY_LR`` there is nothing to say.
"""

from __future__ import annotations

import numpy as np

from calib.conventions import AXES
from calib.effects import Extensions, ModelState, effect
from calib.gap.confusions import AMBIGUITY_LR
from calib.gap.space import AxisSpace
from calib.gap.walk import LEAN_MARGIN


def swap_base(ext: Extensions, state: ModelState, k: int, names: list[str]
              ) -> tuple[AxisSpace, float, float]:
    """The model without the effects ``names`` of axis k, made once for every column tried in
    their place: its :class:`AxisSpace` on axis k, the effects' likelihood ratio
    ``LR_named`` (``−2 log L`` without them less with them) and their parameters p."""
    axis = AXES[k]
    reduced = state
    for n in names:
        reduced = reduced.without(n, axis)
    lr_named = float(ext.nll(reduced) - ext.nll(state))
    cost = float(sum(effect(n).n_free for n in names))
    return AxisSpace(ext, reduced, k), lr_named, cost


def swap_gain(ext: Extensions, state: ModelState, k: int, names: list[str],
              column: np.ndarray, base: tuple[AxisSpace, float, float] | None = None
              ) -> tuple[float, float, float] | None:
    """(D, the column's coefficient, the effects' parameters p) of the module docstring, or
    None when the column is in the model's span without the effects. ``base``: the
    :func:`swap_base` of ``names``, when several columns are tried in their place."""
    space, lr_named, cost = swap_base(ext, state, k, names) if base is None else base
    fit = space.test(np.asarray(column, dtype=float)[:, None])
    if fit is None:
        return None
    return (float(fit[0]) - 2.0) - (lr_named - 2.0 * cost), float(fit[2][0]), cost


def tier(gain: float) -> str | None:
    """What a column's AIC gain D over the named effects says (module docstring):

    * ``"leans"`` beyond :data:`LEAN_MARGIN`: the effects are not named;
    * ``"describes"`` above 0: the column fits better, not by enough to drop them;
    * ``"ties"`` above ``−AMBIGUITY_LR``: the effects fit better, but within the likelihood
      ratio of 10 under which :mod:`calib.gap.confusions` lists two catalog explanations as
      not told apart (the same rule, for a term outside the catalog);
    * None at or below ``−AMBIGUITY_LR``: nothing to say.

    The pair is listed for the three tiers."""
    if gain > LEAN_MARGIN:
        return "leans"
    if gain > 0.0:
        return "describes"
    return "ties" if gain > -AMBIGUITY_LR else None


def leaning(shape: str, fits: str, named: str, gain: float, holder: str, missing: str,
            dropped: str) -> str:
    """The ``description`` of a column that leans against named effects, one sentence for
    every review: "{shape} {fits} better than {named} by D after their charges (more than
    LEAN_MARGIN: {holder} has considerably less support; the catalog has no {missing}, so
    {dropped} not named)"."""
    return (f"{shape} {fits} better than {named} by {gain:.3g} after their charges (more than "
            f"{LEAN_MARGIN:g}: {holder} has considerably less support; the catalog has no "
            f"{missing}, so {dropped} not named)")


FITS = {"leans": "better", "describes": "as well", "ties": "nearly as well"}
"""How the column fits beside the named effects, in the ``not_identifiable`` reason."""


def signature(found: dict, name: str, reason: str) -> dict:
    """The ``unexplained`` entry of a column that leans against named effects."""
    return {"axis": found["axis"], "signature": name, "reason": reason,
            "size": float(found["size"]), "unit": "m/s²", "statistic": float(found["gain"]),
            "p_value": None, "description": found["description"]}
