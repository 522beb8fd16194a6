"""Linear-column effects: extra design columns on top of ``[1, r]`` of one axis.

Each coefficient c multiplies a column; the catalog parameter follows from c and the scale
factor s of the same fit (IEEE 1293: the effect acts before the gain ``1 + s``)::

    misalignment     column sgn·LPF_τ(A_p)        δ = atan2(c, 1 + s)
    nonlinearity_k2  column r²                    k2 = c / (1 + s)
    cross_axis       column r·A_p                 k_ip = c / (1 + s)
    bias_drift       column t - t0 (or k)         rate = c (additive, after the gain)
    lever_arm        columns LPF_τ(ω²), LPF_τ(α)  x: pos_x = -c_w2/(1+s), pos_z = c_α/(1+s)
                                                  y: pos_z = c_w2/(1+s), pos_x = c_α/(1+s)

Test: σ² known, so ``LR = Δχ² ~ χ²(k)`` exactly, k the number of columns.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from calib import distributions as stats
from calib.conventions import AXES, EFFECT_NAMES
from calib.effects import base


def ratio(c: float, s: float, cov2: np.ndarray) -> tuple[float, float]:
    """``c / (1 + s)`` and its delta-method std; ``cov2`` = cov of (s, c)."""
    v = c / (1.0 + s)
    grad = np.array([-c / (1.0 + s) ** 2, 1.0 / (1.0 + s)])
    return v, float(np.sqrt(max(grad @ cov2 @ grad, 0.0)))


class LinearEffect(base.Effect):
    """An effect that is design columns of one axis (one coefficient per column)."""

    @property
    def n_free(self) -> int:  # type: ignore[override]
        return len(self.coefficients)

    def present(self, st: base.AxisState) -> bool:
        return self.name in st.linear

    def add(self, st: base.AxisState, value: float | None = None) -> base.AxisState:
        order = [n for n in EFFECT_NAMES if n in set(st.linear) | {self.name}]
        return replace(st, linear=tuple(order))

    def remove(self, st: base.AxisState) -> base.AxisState:
        return replace(st, linear=tuple(n for n in st.linear if n != self.name))

    def test(self, ext: base.Likelihood, state: base.ModelState, axis: str) -> base.Trial:
        k = AXES.index(axis)
        nll0 = ext.nll(state)
        new = state.with_axis(k, self.add(state.axes[k]))
        nll1 = ext.nll(new)
        lr = max(nll0 - nll1, 0.0)
        df = len(self.coefficients)
        return base.Trial(self.name, axis, new, lr, float(stats.chi2.logsf(lr, df)), nll1,
                          f"chi2({df})")


@base.register
class Misalignment(LinearEffect):
    """Sensitive axis rotated by +δ: column ``sgn·A_p`` through the low-pass (physical)."""

    name = "misalignment"
    coefficients = ("c_mis",)

    def raw_physical(self, run, k: int) -> dict[str, np.ndarray]:
        return {"mis": base.SIGN_P[k] * run.a_ref[:, 1 - k]}

    def columns(self, ext: base.Likelihood, k: int, st: base.AxisState) -> list[np.ndarray]:
        return [ext.physical_column(k, st.tau, "mis")]

    def estimate(self, fit: base.FinalFit, axis: str) -> tuple[dict, dict]:
        sc, cn = f"{axis}.scale", f"{axis}.c_mis"
        s, c = fit.value(sc), fit.value(cn)
        den = (1 + s) ** 2 + c * c
        grad = np.array([-c / den, (1 + s) / den])
        sd = float(np.sqrt(max(grad @ fit.cov_of(sc, cn) @ grad, 0.0)))
        return {"delta": float(np.arctan2(c, 1 + s))}, {"delta": sd}


class ReferenceProduct(LinearEffect):
    """A one-column effect on the reference before the gain: column ``r·f`` (``r`` the axis'
    reference, ``f`` :meth:`factor`), catalog parameter ``c / (1 + s)`` (module docstring)
    with its delta-method std (:func:`ratio`)."""

    def factor(self, ext: base.Likelihood, k: int, r: np.ndarray) -> np.ndarray:
        """(N,) what multiplies the reference ``r`` of axis k."""
        raise NotImplementedError

    def columns(self, ext: base.Likelihood, k: int, st: base.AxisState) -> list[np.ndarray]:
        r = ext.reference(k, st.tau, st.limit)
        return [r * self.factor(ext, k, r)]

    def estimate(self, fit: base.FinalFit, axis: str) -> tuple[dict, dict]:
        key = self.info.keys[0]
        sc, cn = f"{axis}.scale", f"{axis}.{self.coefficients[0]}"
        v, sd = ratio(fit.value(cn), fit.value(sc), fit.cov_of(sc, cn))
        return {key: v}, {key: sd}


@base.register
class NonlinearityK2(ReferenceProduct):
    """Second-order response k2·r² (IEEE K2/K1)."""

    name = "nonlinearity_k2"
    coefficients = ("c_k2",)

    def factor(self, ext: base.Likelihood, k: int, r: np.ndarray) -> np.ndarray:
        return r


@base.register
class CrossAxis(ReferenceProduct):
    """Cross-coupling k_ip·r·A_p (IEEE K_ip/K1)."""

    name = "cross_axis"
    coefficients = ("c_cross",)

    def factor(self, ext: base.Likelihood, k: int, r: np.ndarray) -> np.ndarray:
        return ext.run.a_ref[:, 1 - k]


@base.register
class BiasDrift(LinearEffect):
    """Linear bias drift rate·(t - t0), per second with timing, else per sample."""

    name = "bias_drift"
    coefficients = ("c_drift",)
    confusion = (
        "a linear trend is one realisation of a random walk; a longer run, or repeated runs, "
        "separate them")

    def columns(self, ext: base.Likelihood, k: int, st: base.AxisState) -> list[np.ndarray]:
        return [ext.run.tcol]

    def estimate(self, fit: base.FinalFit, axis: str) -> tuple[dict, dict]:
        cn = f"{axis}.c_drift"
        key = self.info.keys[0] if fit.run.time_unit == "s" else self.info.keys[1]
        return {key: fit.value(cn)}, {key: float(np.sqrt(fit.cov_of(cn)[0, 0]))}

    def needs_times_to_predict(self, time_unit: str) -> bool:
        return time_unit == "s"


@base.register
class LeverArm(LinearEffect):
    """Site off the hinge axis: columns ω² and α through the low-pass (physical, timed)."""

    name = "lever_arm"
    coefficients = ("c_w2", "c_alpha")

    def raw_physical(self, run, k: int) -> dict[str, np.ndarray]:
        if run.omega is None:
            return {}
        return {"w2": run.omega**2, "alpha": run.alpha}

    def columns(self, ext: base.Likelihood, k: int, st: base.AxisState) -> list[np.ndarray]:
        if ext.run.omega is None:
            raise base.UntestableError("lever_arm needs sample times")
        return [ext.physical_column(k, st.tau, "w2"), ext.physical_column(k, st.tau, "alpha")]

    def estimate(self, fit: base.FinalFit, axis: str) -> tuple[dict, dict]:
        sc, w2, al = f"{axis}.scale", f"{axis}.c_w2", f"{axis}.c_alpha"
        s = fit.value(sc)
        c = fit.cov_of(sc, w2, al)
        vw, sw = ratio(fit.value(w2), s, c[np.ix_([0, 1], [0, 1])])
        va, sa = ratio(fit.value(al), s, c[np.ix_([0, 2], [0, 2])])
        if axis == "x":  # x: -ω² pos_x + α pos_z
            return {"pos_x": -vw, "pos_z": va}, {"pos_x": sw, "pos_z": sa}
        return {"pos_x": va, "pos_z": vw}, {"pos_x": sa, "pos_z": sw}  # y: ω² pos_z + α pos_x

    def needs_times_to_predict(self, time_unit: str) -> bool:
        return True
