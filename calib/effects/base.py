"""The contract between the likelihood engine and the effect plugins.

An effect is one small object (:class:`Effect`) registered once with :func:`register`. It
knows, for its catalog name (``calib.conventions.EFFECTS``: keys, units, timing):

* the model state (:class:`AxisState`, :class:`ModelState`, defined here): whether it is in
  an axis' model, how to add and remove it (:meth:`Effect.present`, :meth:`Effect.add`,
  :meth:`Effect.remove`), and how many free parameters it costs (:attr:`Effect.n_free`);
* its part of the likelihood: design columns (linear effects, :meth:`Effect.columns`) or a
  change of the reference, the noise or the whitening (read from the axis state by the
  engine);
* its test on top of a model (:meth:`Effect.test`, likelihood ratio and reference
  distribution) and, for a nonlinear parameter, its 1-D profile and refinement;
* its estimate in the catalog's keys and units from the final fit (:meth:`Effect.estimate`).

Effects are typed against two protocols, never against the classes that implement them:
:class:`Likelihood` (what an effect may ask of the engine,
:class:`calib.effects.engine.Extensions`) and :class:`FinalFit` (what it may read from the
final fit, :class:`calib.gap.estimates.Reporter`). So the dependencies point one way: the
engine and the catalog import the effects, the effects import only this module (and the run
data), and the model states ask the registry filled here (in the catalog's order) what each
effect means for them.

The stated noise variance σ² lives in one place: :attr:`AxisState.sigma2_stated`, set once
from the validated statement (:func:`stated_variances`, the one check, through
:meth:`ModelState.nominal`). ``noise_level`` adds an estimate beside it
(:attr:`AxisState.sigma2_fitted`); removing the effect drops the estimate, so the stated value
is never passed around again.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, replace
from typing import ClassVar, Protocol

import numpy as np
from scipy import optimize

from calib.calibration.ls import NotIdentifiableError
from calib.conventions import AXES, EFFECT_NAMES, EFFECTS, EffectInfo
from calib.effects.run import RunData
from calib.input_rules import stated_variances  # noqa: F401  (its home; re-exported)
from calib.stats.diagnostics import Lattice

SIGN_P: tuple[float, float] = (1.0, -1.0)
"""Sign of the other axis' reference in a rotation by +δ: x: A_rx + δA_ry; y: A_ry - δA_rx."""


class UntestableError(NotIdentifiableError):
    """The extension cannot be tested in this experiment (collinear, or no data for it)."""


@dataclass(frozen=True)
class AxisState:
    """The model of one axis: which extensions, and the values of the nonlinear ones.

    linear : effects present as design columns (:data:`calib.effects.LINEAR_COLUMNS`).
    tau : low-pass time constant, s (0: none).  q : random-walk intensity (0: none), m/s²
        per √(time unit).  limit : saturation limit, m/s² (inf: none).
    sigma2_stated : the stated white-noise variance, (m/s²)² (the only copy of it).
    sigma2_fitted : the estimated one when ``noise_level`` is in the model, else None.
    lsb : quantization step, m/s² (0: none); adds lsb²/12 to the noise variance.
    """

    linear: tuple[str, ...] = ()
    tau: float = 0.0
    q: float = 0.0
    limit: float = float("inf")
    sigma2_stated: float = 1.0
    sigma2_fitted: float | None = None
    lsb: float = 0.0

    @property
    def noise_free(self) -> bool:
        """``noise_level`` is in the model (σ² estimated)."""
        return self.sigma2_fitted is not None

    @property
    def sigma2(self) -> float:
        """White-noise variance in use, (m/s²)²: the estimate when ``noise_level`` is in the
        model, else the stated one."""
        return self.sigma2_stated if self.sigma2_fitted is None else self.sigma2_fitted

    @property
    def sigma2_eff(self) -> float:
        """Variance of the reading's white error: σ² + lsb²/12 (Sheppard), (m/s²)²."""
        return self.sigma2 + self.lsb**2 / 12.0

    def effects(self) -> tuple[str, ...]:
        """Catalog names of the extensions present (catalog order)."""
        return tuple(e.name for e in registered() if e.present(self))

    def has(self, name: str) -> bool:
        return name in self.effects()

    def add(self, name: str, value: float | None = None) -> AxisState:
        return effect(name).add(self, value)

    def remove(self, name: str) -> AxisState:
        return effect(name).remove(self)


@dataclass(frozen=True)
class ModelState:
    """The model of the run: both axes and the shared tilt offset (a column with sin δ)."""

    axes: tuple[AxisState, AxisState]
    tilt: bool = False

    @classmethod
    def nominal(cls, noise_var, lsb: Sequence[float] = (0.0, 0.0)) -> ModelState:
        """Bias + scale per axis at the stated σ² (:func:`stated_variances` checks it) and
        the quantization step of each axis (0: none), m/s²."""
        s2 = stated_variances(noise_var)
        return cls((AxisState(sigma2_stated=float(s2[0]), lsb=lsb[0]),
                    AxisState(sigma2_stated=float(s2[1]), lsb=lsb[1])))

    def axis(self, k: int) -> AxisState:
        return self.axes[k]

    def with_axis(self, k: int, st: AxisState) -> ModelState:
        axes = list(self.axes)
        axes[k] = st
        return replace(self, axes=(axes[0], axes[1]))

    def effects(self) -> list[tuple[str, str]]:
        """(name, axis) of every extension in the model, catalog order."""
        return [(e.name, a) for e in registered() for a in e.info.axes if e.in_model(self, a)]

    def has(self, name: str, axis: str) -> bool:
        """Whether extension ``name`` is in the model on ``axis`` ("both" for shared ones)."""
        return effect(name).in_model(self, axis)

    def without(self, name: str, axis: str) -> ModelState:
        """The model with extension ``name`` on ``axis`` dropped (a dropped noise level
        leaves the stated σ²)."""
        return effect(name).drop(self, axis)

    def n_params(self, k: int) -> int:
        """Parameters of axis k: bias, scale, and those of every extension on it (a shared
        one counts on both axes)."""
        return 2 + sum(effect(n).n_free for n, a in self.effects() if a in (AXES[k], "both"))


class ModelFit(Protocol):
    """What an effect reads from the engine's fit of a model (:meth:`Likelihood.fit`)."""

    nll: float
    """``-2 log L``."""
    rss: tuple[float, float]
    """Whitened RSS per axis."""


class Likelihood(Protocol):
    """What an effect may ask of the likelihood engine of one run
    (:class:`calib.effects.engine.Extensions` implements it; equations there)."""

    run: RunData
    gains: np.ndarray
    """(2,) ``1 + scale`` per axis of the nominal fit."""
    walk_bounds: dict[int, tuple[float, float]]
    """Axis index → (low, high) of a random walk's q stated by a sensor profile."""

    def nll(self, state: ModelState, reml: bool = False) -> float: ...

    def safe_nll(self, state: ModelState, reml: bool = False) -> float: ...

    def fit(self, state: ModelState) -> ModelFit: ...

    def n_params(self, state: ModelState, k: int) -> int: ...

    def filter(self, u: np.ndarray, tau: float) -> np.ndarray: ...

    def reference(self, k: int, tau: float = 0.0, limit: float = float("inf")
                  ) -> np.ndarray: ...

    def physical_column(self, k: int, tau: float, name: str) -> np.ndarray: ...

    def white(self, st: AxisState, m: np.ndarray, key: Hashable | None = None
              ) -> np.ndarray: ...

    def whitened_residual(self, k: int, state: ModelState
                          ) -> tuple[np.ndarray, np.ndarray]: ...

    def memo(self, key: Hashable, make: Callable[[], object]): ...


class FinalFit(Protocol):
    """What an effect reads from the final fit of the selected model to report its estimate
    (:class:`calib.gap.estimates.Reporter` implements it)."""

    ext: Likelihood
    state: ModelState
    run: RunData
    lattice: list[Lattice] | None
    gn_std: dict[str, float]
    """Gauss-Newton std of the nonlinear parameters, ``"<axis>.d_<field>"`` → std."""

    def value(self, name: str) -> float: ...

    def cov_of(self, *names: str) -> np.ndarray: ...

    def q_uncertainty(self, k: int) -> tuple[float, tuple[float, float]]: ...


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

    def remove(self, st: AxisState) -> AxisState:
        raise ValueError(f"{self.name} is not a per-axis extension")

    def in_model(self, state: ModelState, axis: str) -> bool:
        """Whether the effect is in the model on ``axis``."""
        return self.present(state.axes[AXES.index(axis)])

    def drop(self, state: ModelState, axis: str) -> ModelState:
        """The model without the effect on ``axis``."""
        k = AXES.index(axis)
        return state.with_axis(k, self.remove(state.axes[k]))

    # --- likelihood and test --------------------------------------------------------------

    def columns(self, ext: Likelihood, k: int, st: AxisState) -> list[np.ndarray]:
        """Design columns (N,) of axis k, one per coefficient (linear effects only).

        A function of k and of the axis state's τ and L only (through the reference and the
        low-pass): the engine caches them by (k, linear effects, τ, L)
        (:meth:`calib.effects.engine.Extensions.columns`).
        """
        return []

    def raw_physical(self, run: RunData, k: int) -> dict[str, np.ndarray]:
        """Columns that act on the true specific force (before the sensor's low-pass)."""
        return {}

    def shared_column(self, ext: Likelihood, k: int, st: AxisState) -> np.ndarray:
        """The column of axis k of a model-level effect shared by both axes."""
        raise ValueError(f"{self.name} has no shared column")

    def test(self, ext: Likelihood, state: ModelState, axis: str) -> Trial:
        """Test the effect on ``axis`` on top of ``state`` (likelihood ratio)."""
        raise ValueError(f"unknown extension {self.name!r}")

    def refine(self, ext: Likelihood, state: ModelState, k: int) -> ModelState:
        """One local coordinate-descent step of the effect's nonlinear parameter on axis k."""
        return state

    # --- reporting ---------------------------------------------------------------------------

    def estimate(self, fit: FinalFit, axis: str) -> tuple[dict, dict]:
        """Catalog parameters and their std (keys and units of ``info``) from the final
        fit."""
        raise ValueError(self.name)

    def interval(self, fit: FinalFit, axis: str, params: dict) -> dict:
        """Optional 95 % intervals, key → (low, high)."""
        return {}

    def nonlinear(self, fit: FinalFit, k: int) -> tuple[float, float] | None:
        """(value, std) of the nonlinear parameter on axis k (``ExtendedModel.nonlinear``)."""
        return None

    def gn_column(self, ext: Likelihood, k: int, st: AxisState, gain: float
                  ) -> tuple[str, np.ndarray] | None:
        """(``"d_<field>"``, Gauss-Newton column ``d mean / d parameter``) of a nonlinear
        parameter whose std comes from the final linearised fit, or None."""
        return None

    def needs_times_to_predict(self, time_unit: str) -> bool:
        """Whether :func:`calib.gap.predict` needs sample times for this effect."""
        return False


REGISTRY: dict[str, Effect] = {}
"""Catalog name → its effect object, filled by :func:`register` (see ``calib.effects.catalog``)."""

_IN_ORDER: list[Effect] = []


def registered() -> tuple[Effect, ...]:
    """Every registered effect in the catalog's order. Complete once
    :mod:`calib.effects.catalog` is imported (importing :mod:`calib.effects` does);
    LookupError before that, never a silently partial list."""
    if len(_IN_ORDER) != len(EFFECT_NAMES):
        missing = [n for n in EFFECT_NAMES if n not in REGISTRY]
        if missing:
            raise LookupError(f"effects not registered yet: {missing} (import calib.effects)")
        _IN_ORDER[:] = [REGISTRY[n] for n in EFFECT_NAMES]
    return tuple(_IN_ORDER)


def effect(name: str) -> Effect:
    """The registered object of a catalog effect."""
    try:
        return REGISTRY[name]
    except KeyError:
        raise ValueError(f"unknown extension {name!r}") from None


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
