"""The registered effects, one object per catalog name, in the catalog's order.

Importing this module imports every effect module (each registers its classes once with
:func:`calib.effects.base.register`) and checks that the registry covers the vocabulary of
:data:`calib.conventions.EFFECTS` exactly.
"""

from __future__ import annotations

import calib.effects.gravity  # noqa: F401  (each effect module registers its classes)
import calib.effects.linear  # noqa: F401
import calib.effects.noise  # noqa: F401
import calib.effects.response  # noqa: F401
import calib.effects.tilt  # noqa: F401
from calib.conventions import EFFECT_NAMES
from calib.effects.base import REGISTRY, Effect, registered

if set(REGISTRY) != set(EFFECT_NAMES):
    raise ImportError(f"effect registry {sorted(REGISTRY)} != vocabulary {sorted(EFFECT_NAMES)}")

CATALOG: tuple[Effect, ...] = registered()
"""Every effect object, in the catalog's order."""

REFINED: tuple[Effect, ...] = tuple(sorted((e for e in CATALOG if e.refine_rank is not None),
                                           key=lambda e: e.refine_rank))
"""Effects with a nonlinear parameter, in coordinate-descent order (τ, L, q, σ²)."""

SHARED: tuple[Effect, ...] = tuple(e for e in CATALOG if e.shared)
"""Model-level effects with one column shared by both axes (the tilt offset)."""

LINEAR_COLUMNS: dict[str, tuple[str, ...]] = {e.name: e.coefficients for e in CATALOG
                                              if e.coefficients}
"""Effects that are extra design-matrix columns on top of [1, A_r], and their coefficients."""

PHYSICAL_COLUMNS: tuple[str, ...] = tuple(
    e.name for e in CATALOG if e.coefficients and e.info.physical)
"""Columns that act on the true specific force, so they pass through the sensor's low-pass."""

