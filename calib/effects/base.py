"""The protocol of a catalog effect on the estimation side, and the registry.

An effect is one small object (:class:`Effect`) registered once with :func:`register`. It
knows, for its catalog name (``calib.conventions.EFFECTS``: keys, units, timing):

* the model state: whether it is in an axis' model, how to add and remove it
  (:meth:`Effect.present`, :meth:`Effect.add`, :meth:`Effect.remove`), and how many free
  parameters it costs (:attr:`Effect.n_free`);
* its part of the likelihood: design columns (linear effects, :meth:`Effect.columns`) or a
  change of the reference, the noise or the whitening (read from the axis state by
  :class:`calib.effects.engine.Extensions`);
* its test on top of a model (:meth:`Effect.test`, likelihood ratio and reference
  distribution) and, for a nonlinear parameter, its 1-D profile and refinement;
* its estimate in the catalog's keys and units from the final fit (:meth:`Effect.estimate`).

:class:`calib.effects.engine.Extensions` is generic: it asks the registered objects.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from scipy import optimize

from calib.conventions import AXES, EFFECTS, EffectInfo
from calib.ls import NotIdentifiableError

if TYPE_CHECKING:
    from calib.effects.engine import Extensions
    from calib.effects.state import AxisState, ModelState

SIGN_P: tuple[float, float] = (1.0, -1.0)
"""Sign of the other axis' reference in a rotation by +δ: x: A_rx + δA_ry; y: A_ry - δA_rx."""


class UntestableError(NotIdentifiableError):
    """The extension cannot be tested in this experiment (collinear, or no data for it)."""


@dataclass(frozen=True)
class Trial:
    """One extension tested on top of a model.

    name, axis : the effect.  state : the extended model (its parameter at the ML value).
    lr : likelihood-ratio statistic ``-2 log Λ`` (≥ 0).  logp : log p-value under the
    reference distribution in ``reference``.  nll : ``-2 log L`` of the extended model.
    """

    name: str
    axis: str
    state: ModelState
    lr: float
    logp: float
    nll: float
    reference: str

    @property
    def p_value(self) -> float:
        return float(np.exp(self.logp))


class Effect:
    """One catalog effect as an extension of the nominal model (defaults: a per-axis effect
    that is not in any model and cannot be tested)."""

    name: ClassVar[str]
    """Catalog name (a key of ``calib.conventions.EFFECTS``)."""
    coefficients: ClassVar[tuple[str, ...]] = ()
    """Names of the design-matrix coefficients (linear effects only)."""
    n_free: ClassVar[int] = 1
    """Free parameters the effect adds to an axis' model (the AIC count of the swap tests)."""
    lr_tested: ClassVar[bool] = True
    """Selected by a likelihood-ratio test (quantization is found from the lattice instead)."""
    refine_rank: ClassVar[int | None] = None
    """Position in the coordinate descent over the nonlinear parameters (None: no such
    parameter). It is also the order of ``ExtendedModel.nonlinear``."""
    shared: ClassVar[bool] = False
    """One column shared by both axes (its coefficient ``sin_tilt``): :meth:`shared_column`."""
    confusion: ClassVar[str | None] = None
    """Why this effect may not be told apart from another, and which experiment separates
    them (reported in ``not_identifiable``)."""

    @property
    def info(self) -> EffectInfo:
        """The catalog row: keys, units, axes, timing (the single vocabulary)."""
        return EFFECTS[self.name]

    @property
    def units(self) -> dict[str, str]:
        """Parameter key → unit, from the catalog row."""
        return dict(zip(self.info.keys, self.info.units, strict=True))

    # --- the model state ----------------------------------------------------------------

    def present(self, st: AxisState) -> bool:
        """Whether the effect is in the model of one axis."""
        return False

    def add(self, st: AxisState, value: float | None = None) -> AxisState:
        raise ValueError(f"{self.name} is not a per-axis extension")

    def remove(self, st: AxisState, stated_sigma2: float) -> AxisState:
        raise ValueError(f"{self.name} is not a per-axis extension")

    def in_model(self, state: ModelState, axis: str) -> bool:
        """Whether the effect is in the model on ``axis``."""
        return self.present(state.axes[AXES.index(axis)])

    def drop(self, state: ModelState, axis: str, stated_sigma2: np.ndarray) -> ModelState:
        """The model without the effect on ``axis`` (the stated σ² back for noise_level)."""
        k = AXES.index(axis)
        return state.with_axis(k, self.remove(state.axes[k], float(stated_sigma2[k])))

    # --- likelihood and test --------------------------------------------------------------

    def columns(self, ext: Extensions, k: int, st: AxisState) -> list[np.ndarray]:
        """Design columns (N,) of axis k, one per coefficient (linear effects only).

        A function of k and of the axis state's τ and L only (through the reference and the
        low-pass): :meth:`Extensions.columns` caches them by (k, linear effects, τ, L).
        """
        return []

    def raw_physical(self, run, k: int) -> dict[str, np.ndarray]:
        """Columns that act on the true specific force (before the sensor's low-pass)."""
        return {}

    def shared_column(self, ext: Extensions, k: int, st: AxisState) -> np.ndarray:
        """The column of axis k of a model-level effect shared by both axes."""
        raise ValueError(f"{self.name} has no shared column")

    def test(self, ext: Extensions, state: ModelState, axis: str) -> Trial:
        """Test the effect on ``axis`` on top of ``state`` (likelihood ratio)."""
        raise ValueError(f"unknown extension {self.name!r}")

    def refine(self, ext: Extensions, state: ModelState, k: int) -> ModelState:
        """One local coordinate-descent step of the effect's nonlinear parameter on axis k."""
        return state

    # --- reporting ---------------------------------------------------------------------------

    def estimate(self, fit, axis: str) -> tuple[dict, dict]:
        """Catalog parameters and their std (keys and units of ``info``) from the final fit
        (:class:`calib.gap.estimates.Reporter`)."""
        raise ValueError(self.name)

    def interval(self, fit, axis: str, params: dict) -> dict:
        """Optional 95 % intervals, key → (low, high)."""
        return {}

    def nonlinear(self, fit, k: int) -> tuple[float, float] | None:
        """(value, std) of the nonlinear parameter on axis k (``ExtendedModel.nonlinear``)."""
        return None

    def gn_column(self, ext: Extensions, k: int, st: AxisState, gain: float
                  ) -> tuple[str, np.ndarray] | None:
        """(``"d_<field>"``, Gauss-Newton column ``d mean / d parameter``) of a nonlinear
        parameter whose std comes from the final linearised fit, or None."""
        return None

    def needs_times_to_predict(self, time_unit: str) -> bool:
        """Whether :func:`calib.gap.predict` needs sample times for this effect."""
        return False


REGISTRY: dict[str, Effect] = {}
"""Catalog name → its effect object, filled by :func:`register` (see ``calib.effects.catalog``)."""


def register(cls: type[Effect]) -> type[Effect]:
    """Class decorator: register one instance of an effect class under its catalog name."""
    if cls.name not in EFFECTS:
        raise ValueError(f"{cls.name!r} is not in the effect vocabulary (calib.conventions)")
    if cls.name in REGISTRY:
        raise ValueError(f"effect {cls.name!r} registered twice")
    REGISTRY[cls.name] = cls()
    return cls



def minimise(f: Callable[[float], float], grid: np.ndarray) -> tuple[float, float]:
    """Minimise f over a sorted grid, then Brent between the best point's neighbours."""
    vals = np.array([f(x) for x in grid])
    i = int(np.nanargmin(vals))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    best_x, best_f = float(grid[i]), float(vals[i])
    if hi > lo:
        res = optimize.minimize_scalar(f, bounds=(lo, hi), method="bounded",
                                       options={"xatol": 1e-4 * (hi - lo) + 1e-12})
        if res.fun < best_f:
            best_x, best_f = float(res.x), float(res.fun)
    return best_x, best_f
