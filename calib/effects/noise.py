"""Noise effects: ``bias_random_walk`` (q), ``noise_level`` (σ²), ``quantization`` (lsb).

* bias_random_walk: enters the whitening, ``Σ_Δ = σ² T + q² diag(Δt)``; q by restricted ML
  (REML, :meth:`Extensions.nll`); q ≥ 0 on the boundary, ``LR ~ ½χ²₀ + ½χ²₁`` (χ̄²; for a
  variance component the true point mass at 0 is larger than ½, so this p-value is
  conservative).
* noise_level: σ² free (profile); ``RSS/σ²_stated ~ χ²(dof)`` exactly, two-sided; on
  ``"both"`` axes the two statistics pooled (a stated σ² off by one factor on both axes).
* quantization: found from the lattice of the readings (step 0 of the selection, not a
  likelihood-ratio test); adds lsb²/12 to σ² (Sheppard).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from calib import distributions as stats
from calib.calibration.ls import NotIdentifiableError
from calib.conventions import AXES
from calib.effects import base
from calib.effects.response import BoundaryEffect, ProfiledEffect
from calib.stats.diagnostics import chi2_two_sided_logp

BOTH = "both"


@base.register
class BiasRandomWalk(BoundaryEffect):
    """Bias random walk ``b_k = b_{k-1} + q·√Δt·w_k`` (per √s with timing, else per √sample)."""

    name = "bias_random_walk"
    field = "q"
    off = 0.0
    reml = True
    refine_rank = 2
    refine_window = 1.0

    def profile(self, ext: base.Likelihood, state: base.ModelState, k: int,
                window: float | None = None) -> tuple[float, float]:
        """REML of the random-walk intensity q of axis k (others fixed): (q, REML -2 log L).

        Searched on ``log(q²·Δt/σ²)``, the walk-to-noise variance ratio per step; within
        ``ext.walk_bounds[k]`` = (low, high) when a sensor profile states q (``gap
        --sensor``: its interval; a single value when low = high)."""
        st = state.axes[k]
        s2 = st.sigma2_eff
        dtm = float(np.median(ext.run.dt_walk))
        n = ext.run.n

        def f(lk: float) -> float:
            q = float(np.sqrt(np.exp(lk) * s2 / dtm))
            return ext.safe_nll(state.with_axis(k, replace(st, q=q)), reml=True)

        bounds = getattr(ext, "walk_bounds", {}).get(k)
        if bounds is not None:  # a sensor profile gives q (its interval): not free
            lo, hi = (np.log(b * b * dtm / s2) for b in bounds)
            if hi - lo < 1e-9:
                return float(bounds[0]), f(lo)
            lk, val = base.minimise(f, np.linspace(lo, hi, 7))
            return float(np.sqrt(np.exp(lk) * s2 / dtm)), val
        if window is None:
            grid = np.linspace(np.log(0.01 / n**2), 0.0, 18)
        else:
            c = np.log(st.q**2 * dtm / s2)
            grid = np.linspace(c - window, c + window, 7)
        lk, val = base.minimise(f, grid)
        return float(np.sqrt(np.exp(lk) * s2 / dtm)), val

    def std(self, fit: base.FinalFit, k: int) -> float:
        """From the REML profile interval (:func:`calib.gap.random_walk.q_uncertainty`)."""
        return fit.q_uncertainty(k)[0]

    def _key(self, fit) -> str:
        return self.info.keys[0] if fit.run.time_unit == "s" else self.info.keys[1]

    def estimate(self, fit: base.FinalFit, axis: str) -> tuple[dict, dict]:
        k = AXES.index(axis)
        key = self._key(fit)
        return {key: fit.state.axes[k].q}, {key: self.std(fit, k)}

    def interval(self, fit: base.FinalFit, axis: str, params: dict) -> dict:
        """The REML profile-likelihood interval of q (asymmetric)."""
        return {self._key(fit): fit.q_uncertainty(AXES.index(axis))[1]}


@base.register
class NoiseLevel(ProfiledEffect):
    """True white-noise variance σ² differs from the stated one: σ² estimated."""

    name = "noise_level"
    field = "sigma2"
    refine_rank = 3

    def present(self, st: base.AxisState) -> bool:
        return st.noise_free

    def add(self, st: base.AxisState, value: float | None = None) -> base.AxisState:
        return replace(st, sigma2_fitted=float(value))

    def remove(self, st: base.AxisState) -> base.AxisState:
        return replace(st, sigma2_fitted=None)  # the stated σ² is in use again

    def in_model(self, state: base.ModelState, axis: str) -> bool:
        """On one axis, or on ``"both"``: a fitted σ² on each axis."""
        if axis == BOTH:
            return all(self.present(st) for st in state.axes)
        return super().in_model(state, axis)

    def drop(self, state: base.ModelState, axis: str) -> base.ModelState:
        if axis == BOTH:
            return replace(state, axes=tuple(self.remove(st) for st in state.axes))
        return super().drop(state, axis)

    @staticmethod
    def _dof(ext: base.Likelihood, state: base.ModelState, k: int) -> int:
        """Degrees of freedom of axis k's whitened RSS under ``state``: ``N − p_k``."""
        return ext.run.n - ext.n_params(state, k)

    def test(self, ext: base.Likelihood, state: base.ModelState, axis: str) -> base.Trial:
        if axis == BOTH:
            return self._test_both(ext, state)
        k = AXES.index(axis)
        nll0 = ext.nll(state)
        fit = ext.fit(state)
        dof = self._dof(ext, state, k)
        if dof < 2:  # σ² fitted would leave no degree of freedom (N = 3): not testable
            return base.Trial(self.name, axis, state, 0.0, 0.0, nll0, f"chi2({dof})")
        logp = chi2_two_sided_logp(fit.rss[k], dof)
        s2, nll1 = self.profile(ext, state, k)
        new = state.with_axis(k, self.add(state.axes[k], s2))
        return base.Trial(self.name, axis, new, max(nll0 - nll1, 0.0), logp, nll1, f"chi2({dof})")

    def _test_both(self, ext: base.Likelihood, state: base.ModelState) -> base.Trial:
        """The stated σ² of both axes off by one common factor ρ (``σ² = ρ·σ²_stated``, one
        parameter): the pooled statistic ``RSS_x/σ_x² + RSS_y/σ_y² ~ χ²(dof_x + dof_y)`` under
        "both stated right", two-sided (the per-axis test's statistic, summed). Against a
        common ρ it is the most powerful of the three noise-level tests: two axes each
        ≈ 3.8 σ above their χ² mean give ≈ 5.4 σ pooled. When it is named, each axis keeps
        its own σ² (profiled), so nothing downstream assumes the ratio common. Not
        testable where either axis has a noise level already (its χ² is then fitted)."""
        if any(self.present(st) for st in state.axes):
            raise NotIdentifiableError("noise_level on both axes: an axis has its own already")
        nll0 = ext.nll(state)
        fit = ext.fit(state)
        dof = sum(self._dof(ext, state, k) for k in range(2))
        if dof < 4:
            return base.Trial(self.name, BOTH, state, 0.0, 0.0, nll0, f"chi2({dof})")
        logp = chi2_two_sided_logp(float(fit.rss[0] + fit.rss[1]), dof)
        new = state
        for k in range(2):
            s2, _ = self.profile(ext, new, k)
            new = new.with_axis(k, self.add(new.axes[k], s2))
        nll1 = ext.nll(new)
        return base.Trial(self.name, BOTH, new, max(nll0 - nll1, 0.0), logp, nll1,
                          f"chi2({dof}), both axes pooled")

    def profile(self, ext: base.Likelihood, state: base.ModelState, k: int,
                window: float | None = None) -> tuple[float, float]:
        """ML of the white-noise variance σ² of axis k (others fixed): (σ², nll)."""
        st = state.axes[k]
        fit = ext.fit(state)
        m = ext.run.n - 1
        guess = max(fit.rss[k] * st.sigma2_eff / m - st.lsb**2 / 12.0, 1e-12 * st.sigma2_eff)
        if st.q == 0:  # RSS ∝ 1/σ²_eff exactly: closed form
            return guess, ext.safe_nll(state.with_axis(k, self.add(st, guess)))

        def f(ls: float) -> float:
            return ext.safe_nll(state.with_axis(k, self.add(st, float(np.exp(ls)))))

        ls, val = base.minimise(f, np.log(guess) + np.linspace(-0.7, 0.7, 7))
        return float(np.exp(ls)), val

    def std(self, fit: base.FinalFit, k: int) -> float:
        """``σ̂²·sqrt(2/dof)`` (χ²(dof) variance)."""
        return fit.state.axes[k].sigma2 * float(np.sqrt(2.0 / self._dof(fit.ext, fit.state, k)))

    def interval(self, fit: base.FinalFit, axis: str, params: dict) -> dict:
        """``(dof·σ̂²/χ²_{0.975}, dof·σ̂²/χ²_{0.025})``."""
        dof = self._dof(fit.ext, fit.state, AXES.index(axis))
        lo, hi = dof * params["sigma2"] / stats.chi2.ppf([0.975, 0.025], dof)
        return {"sigma2": (float(lo), float(hi))}


@base.register
class Quantization(base.Effect):
    """Output rounded to multiples of lsb: adds lsb²/12 to the noise variance."""

    name = "quantization"
    n_free = 0
    lr_tested = False

    def present(self, st: base.AxisState) -> bool:
        return st.lsb > 0

    def remove(self, st: base.AxisState) -> base.AxisState:
        return replace(st, lsb=0.0)

    def estimate(self, fit: base.FinalFit, axis: str) -> tuple[dict, dict]:
        lat = fit.lattice[AXES.index(axis)]
        return {"lsb": lat.lsb}, {"lsb": lat.lsb_std}
