"""Response effects with one nonlinear parameter: ``lowpass_lag`` (τ) and ``saturation`` (L).

Both change the reference of the axis, ``r = LPF_τ(clip(A_r, ±L))`` (read from the axis state
by :meth:`Extensions.reference`), and are estimated by a 1-D profile likelihood.

* lowpass_lag (τ ≥ 0, needs sample times): τ on the boundary under "no such effect", so
  ``LR ~ ½χ²₀ + ½χ²₁`` (χ̄²).
* saturation: L exists only under the alternative: Davies' bound on the sup of the one-sided
  score process over the grid of limits (:func:`calib.stats.diagnostics.flat_top_score`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

import numpy as np

from calib import distributions as stats
from calib.conventions import AXES
from calib.effects import base
from calib.stats.diagnostics import LN2, flat_top_score, hinge_columns, hinge_levels


class ProfiledEffect(base.Effect):
    """A per-axis effect with one nonlinear parameter, the axis-state field ``field``,
    estimated by :meth:`profile` and refined in a local window ``refine_window``."""

    field: ClassVar[str]
    off: ClassVar[float]
    """The field's value when the effect is absent."""
    refine_window: ClassVar[float | None] = None

    def present(self, st: base.AxisState) -> bool:
        return getattr(st, self.field) != self.off

    def add(self, st: base.AxisState, value: float | None = None) -> base.AxisState:
        return replace(st, **{self.field: float(value)})

    def remove(self, st: base.AxisState) -> base.AxisState:
        return replace(st, **{self.field: self.off})

    def profile(self, ext: base.Likelihood, state: base.ModelState, k: int,
                window: float | None = None) -> tuple[float, float]:
        """ML (or REML) of the parameter of axis k, others fixed: (value, -2 log L)."""
        raise NotImplementedError

    def refine(self, ext: base.Likelihood, state: base.ModelState, k: int) -> base.ModelState:
        val, _ = self.profile(ext, state, k, window=self.refine_window)
        return state.with_axis(k, self.add(state.axes[k], val))

    def nonlinear(self, fit: base.FinalFit, k: int) -> tuple[float, float]:
        return getattr(fit.state.axes[k], self.field), self.std(fit, k)

    def std(self, fit: base.FinalFit, k: int) -> float:
        """Gauss-Newton std from the final fit's column ``d_<field>`` (:meth:`gn_column`)."""
        return fit.gn_std[f"{AXES[k]}.d_{self.field}"]

    def estimate(self, fit: base.FinalFit, axis: str) -> tuple[dict, dict]:
        k = AXES.index(axis)
        key = self.info.keys[0]
        return {key: getattr(fit.state.axes[k], self.field)}, {key: self.std(fit, k)}


class BoundaryEffect(ProfiledEffect):
    """Parameter ≥ 0 with "none" on the boundary: the χ̄² = ½χ²₀ + ½χ²₁ test."""

    reml: ClassVar[bool] = False

    def test(self, ext: base.Likelihood, state: base.ModelState, axis: str) -> base.Trial:
        k = AXES.index(axis)
        nll0 = ext.nll(state)
        self.check_testable(ext)
        val, nll1 = self.profile(ext, state, k)
        lr = (ext.nll(state, reml=True) if self.reml else nll0) - nll1
        if not np.isfinite(nll1) or lr <= 0:
            return base.Trial(self.name, axis, state, 0.0, 0.0, nll0, "chibar2(0:1)")
        new = state.with_axis(k, self.add(state.axes[k], val))
        return base.Trial(self.name, axis, new, lr, float(-LN2 + stats.chi2.logsf(lr, 1)),
                          ext.nll(new), "chibar2(0:1)")

    def check_testable(self, ext: base.Likelihood) -> None:
        return None


@base.register
class LowpassLag(BoundaryEffect):
    """First-order low-pass τ·dy/dt + y = u on the signal (the white noise stays white)."""

    name = "lowpass_lag"
    field = "tau"
    off = 0.0
    refine_rank = 0
    refine_window = 0.5
    confusion = (
        "at a constant sweep rate a lag τ looks like an angle offset -τ·ω; a sweep with a "
        "varying rate or a reversal (up-then-down) separates them")

    def check_testable(self, ext: base.Likelihood) -> None:
        if not ext.run.timed:
            raise base.UntestableError("lowpass_lag needs sample times")

    def profile(self, ext: base.Likelihood, state: base.ModelState, k: int,
                window: float | None = None) -> tuple[float, float]:
        """ML of the low-pass time constant τ (s) of axis k (others fixed): (τ, nll)."""
        st = state.axes[k]
        h = float(np.median(np.diff(ext.run.t)))
        dur = float(ext.run.t[-1] - ext.run.t[0])

        def f(lt: float) -> float:
            return ext.safe_nll(state.with_axis(k, replace(st, tau=float(np.exp(lt)))))

        if window is None:
            grid = np.linspace(np.log(0.01 * h), np.log(max(0.25 * dur, 2 * h)), 24)
        else:
            c = np.log(st.tau)
            grid = np.linspace(c - window, c + window, 7)
        lt, val = base.minimise(f, grid)
        return float(np.exp(lt)), val

    def gn_column(self, ext: base.Likelihood, k: int, st: base.AxisState, gain: float
                  ) -> tuple[str, np.ndarray] | None:
        """``d r / d τ`` by a central difference (relative step 1e-3), times the gain."""
        eps = 1e-3
        d = (ext.reference(k, st.tau * (1 + eps), st.limit)
             - ext.reference(k, st.tau * (1 - eps), st.limit)) / (2 * eps * st.tau)
        return "d_tau", gain * d

    def needs_times_to_predict(self, time_unit: str) -> bool:
        return True


LIMIT_BELOW_TOP = 1e-9
"""A refined saturation limit stays this fraction below the largest ``|A_r|`` (where it would
clip nothing and its Gauss-Newton column would vanish)."""


@base.register
class Saturation(ProfiledEffect):
    """True specific force clipped to ±L."""

    name = "saturation"
    field = "limit"
    off = float("inf")
    refine_rank = 1
    refine_window = 0.05

    def test(self, ext: base.Likelihood, state: base.ModelState, axis: str) -> base.Trial:
        k = AXES.index(axis)
        nll0 = ext.nll(state)
        logp = self.score(ext, state, k)
        lim, nll1 = self.profile(ext, state, k)
        lr = max(nll0 - nll1, 0.0)
        new = state.with_axis(k, self.add(state.axes[k], lim)) if np.isfinite(lim) else state
        return base.Trial(self.name, axis, new, lr, logp, min(nll1, nll0), "davies")

    def score(self, ext: base.Likelihood, state: base.ModelState, k: int) -> float:
        """log p of the flat-top score test (clip at ±L, L unknown) on axis k."""
        st = state.axes[k]
        levels = self.levels(ext, k)
        if levels.size == 0:
            raise base.UntestableError("no range of |A_r| to clip")
        ext.fit(state)  # raises when the model is not identifiable
        resid, design = ext.whitened_residual(k, state)
        hinges = ext.memo((self.name, "hinges", k, st.tau), lambda: ext.filter(
            hinge_columns(ext.run.a_ref[:, k], levels), st.tau))
        hinges_w = ext.memo((self.name, "hinges_w", k, st.tau, st.sigma2_eff, st.q),
                            lambda: ext.white(st, hinges))
        _, logp = flat_top_score(resid, design, hinges_w)
        return logp

    def levels(self, ext: base.Likelihood, k: int) -> np.ndarray:
        """The grid of limits of axis k (:func:`calib.stats.diagnostics.hinge_levels`), m/s²."""
        return ext.memo((self.name, "levels", k), lambda: hinge_levels(ext.run.a_ref[:, k]))

    def profile(self, ext: base.Likelihood, state: base.ModelState, k: int,
                window: float | None = None) -> tuple[float, float]:
        """ML of the saturation limit L (m/s²) of axis k (others fixed): (L, nll).

        The grid (:meth:`levels`, half-way between distinct ``|A_r|``) is searched up to the
        largest ``|A_r|`` itself: a limit that clips only the largest values a little lies
        above the top level (on held poses, between the top pose's ``|A_r|`` and the level
        half-way to the next), and Brent reaches it only with that point as its upper
        bracket. A limit at or above every ``|A_r|`` clips nothing (the effect would vanish and
        its column be 0): the refinement stays just below it, and when no clip fits best the
        top level is returned as before (with its own ``-2 log L``)."""
        st = state.axes[k]
        top = float(np.max(np.abs(ext.run.a_ref[:, k])))
        levels = self.levels(ext, k)

        def f(lim: float) -> float:
            return ext.safe_nll(state.with_axis(k, replace(st, limit=float(lim))))

        if window is None:
            grid = np.sort(np.r_[levels, top]) if levels.size else levels
        else:
            grid = st.limit * np.linspace(1 - window, 1 + window, 7)
            if levels.size:
                grid = np.unique(np.minimum(grid, top * (1.0 - LIMIT_BELOW_TOP)))
        if grid.size == 0:
            return float("inf"), ext.nll(state)
        lim, val = base.minimise(f, grid)
        if lim >= top * (1.0 - LIMIT_BELOW_TOP):
            if window is None:  # nothing clipped fits best: the top level, as before
                lim = float(np.max(levels))
                return lim, f(lim)
            lim = top * (1.0 - LIMIT_BELOW_TOP)
            return lim, f(lim)
        return lim, val

    def gn_column(self, ext: base.Likelihood, k: int, st: base.AxisState, gain: float
                  ) -> tuple[str, np.ndarray] | None:
        """``d r / d L = LPF_τ(sgn(A_r)·[|A_r| > L])``, times the gain."""
        a = ext.run.a_ref[:, k]
        return "d_limit", gain * ext.filter(np.sign(a) * (np.abs(a) > st.limit), st.tau)
