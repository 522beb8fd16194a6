"""Model structure: which extensions each axis has, and the values of the nonlinear ones.

The states are generic: what each field means for an effect (present? how to add or remove
it? how many parameters?) is asked of the registered effect objects
(:mod:`calib.effects.catalog`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from calib.conventions import AXES
from calib.effects.catalog import CATALOG, effect


@dataclass(frozen=True)
class AxisState:
    """The model of one axis: which extensions, and the values of the nonlinear ones.

    linear : effects present as design columns (:data:`calib.effects.LINEAR_COLUMNS`).
    tau : low-pass time constant, s (0: none).  q : random-walk intensity (0: none), m/s²
        per √(time unit).  limit : saturation limit, m/s² (inf: none).
    sigma2 : white-noise variance in use, (m/s²)² (the stated one unless ``noise_free``).
    noise_free : ``noise_level`` is in the model (σ² estimated).
    lsb : quantization step, m/s² (0: none); adds lsb²/12 to the noise variance.
    """

    linear: tuple[str, ...] = ()
    tau: float = 0.0
    q: float = 0.0
    limit: float = float("inf")
    sigma2: float = 1.0
    noise_free: bool = False
    lsb: float = 0.0

    @property
    def sigma2_eff(self) -> float:
        """Variance of the reading's white error: σ² + lsb²/12 (Sheppard), (m/s²)²."""
        return self.sigma2 + self.lsb**2 / 12.0

    def effects(self) -> tuple[str, ...]:
        """Catalog names of the extensions present (catalog order)."""
        return tuple(e.name for e in CATALOG if e.present(self))

    def has(self, name: str) -> bool:
        return name in self.effects()

    def add(self, name: str, value: float | None = None) -> AxisState:
        return effect(name).add(self, value)

    def remove(self, name: str, stated_sigma2: float) -> AxisState:
        return effect(name).remove(self, stated_sigma2)


@dataclass(frozen=True)
class ModelState:
    """The model of the run: both axes and the shared tilt offset (a column with sin δ)."""

    axes: tuple[AxisState, AxisState]
    tilt: bool = False

    def axis(self, k: int) -> AxisState:
        return self.axes[k]

    def with_axis(self, k: int, st: AxisState) -> ModelState:
        axes = list(self.axes)
        axes[k] = st
        return replace(self, axes=(axes[0], axes[1]))

    def effects(self) -> list[tuple[str, str]]:
        """(name, axis) of every extension in the model, catalog order."""
        return [(e.name, a) for e in CATALOG for a in e.info.axes if e.in_model(self, a)]

    def has(self, name: str, axis: str) -> bool:
        """Whether extension ``name`` is in the model on ``axis`` ("both" for shared ones)."""
        return effect(name).in_model(self, axis)

    def without(self, name: str, axis: str, stated_sigma2: np.ndarray) -> ModelState:
        """The model with extension ``name`` on ``axis`` dropped (stated σ² back if needed)."""
        return effect(name).drop(self, axis, stated_sigma2)

    def n_params(self, k: int) -> int:
        """Parameters of axis k: bias, scale, and those of every extension on it (a shared
        one counts on both axes)."""
        return 2 + sum(effect(n).n_free for n, a in self.effects() if a in (AXES[k], "both"))
