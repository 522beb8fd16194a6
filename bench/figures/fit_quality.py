"""How well a fit fits, in words for a figure title: χ²/dof with its dof, or — when no degree
of freedom is left — a sentence saying so (never "nan")."""

from __future__ import annotations

import math


def fit_quality(chi2_dof: float, dof: int) -> str:
    """``"χ²/dof = 1.02 (dof 6)"``, or ``"no degrees of freedom left: …"`` when ``dof`` ≤ 0
    or χ²/dof is not finite (the poses or samples fit exactly; nothing checks the fit)."""
    if dof <= 0 or not math.isfinite(chi2_dof):
        return "no degrees of freedom left: the data fit exactly, nothing checks the fit"
    return f"χ²/dof = {chi2_dof:.3g} (dof {dof})"
