"""Tilt offset: table angle = encoder + δ, shared by both axes.

One shared column per axis, ``sgn·(1 + ŝ_a)·LPF_τ(A_p)`` (the reading change per unit sin δ;
the gains ``1 + ŝ_a`` of the nominal fit are held fixed), coefficient ``sin_tilt``.
Test: ``LR = Δχ² ~ χ²(1)`` exactly (σ² known).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from calib import distributions as stats
from calib.effects import base


@base.register
class TiltOffset(base.Effect):
    name = "tilt_offset"
    shared = True
    confusion = (
        "identical on one table: a table-angle offset equals the same misalignment of both "
        "sensors; mounting the sensor block rotated by 90° (or an independent inclinometer) "
        "separates them")

    def shared_column(self, ext: base.Likelihood, k: int, st: base.AxisState) -> np.ndarray:
        """``sgn·(1 + ŝ_k)·LPF_τ(A_p)``: the reading change per unit sin δ of a tilt offset
        (the misalignment's physical column times the nominal gain)."""
        return ext.gains[k] * ext.physical_column(k, st.tau, "mis")

    def in_model(self, state: base.ModelState, axis: str) -> bool:
        return state.tilt

    def drop(self, state: base.ModelState, axis: str) -> base.ModelState:
        return replace(state, tilt=False)

    def test(self, ext: base.Likelihood, state: base.ModelState, axis: str) -> base.Trial:
        new = replace(state, tilt=True)
        nll1 = ext.nll(new)
        lr = max(ext.nll(state) - nll1, 0.0)
        return base.Trial(self.name, "both", new, lr, float(stats.chi2.logsf(lr, 1)), nll1,
                          "chi2(1)")

    def estimate(self, fit: base.FinalFit, axis: str) -> tuple[dict, dict]:
        s = fit.value("sin_tilt")
        sd = float(np.sqrt(fit.cov_of("sin_tilt")[0, 0]))
        d = float(np.arcsin(np.clip(s, -1, 1)))
        return {"delta": d}, {"delta": sd / np.cos(d)}
