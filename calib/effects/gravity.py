"""Gravity mismatch: never in a model (absorbed by the scale factors), always reported."""

from __future__ import annotations

from calib.effects import base


@base.register
class GravityMismatch(base.Effect):
    """A different local g is a common scale change of both axes: no extension of its own."""

    name = "gravity_mismatch"
    confusion = (
        "absorbed by the scale factors: a different local g is a common scale change of both "
        "axes; only an independent gravity reference (or a known scale) separates them")

    def in_model(self, state: base.ModelState, axis: str) -> bool:
        return False
