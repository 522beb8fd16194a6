"""The vehicle case every N question of :mod:`calib.vehicle.nmin` is asked about, as one value."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calib.conventions import G
from calib.vehicle.trajectory import COURSE_P0, COURSE_V0, Integrator


@dataclass(frozen=True)
class VehicleCase:
    """How a vehicle run is corrected, integrated and decided.

    Attributes
    ----------
    candidates : name → (2,) candidate arrival point, m.
    p0 : (2,) initial position, m.  v0 : (2,) initial velocity, m/s (the course's by default).
    level : confidence level L of the region and the decision.
    method : calibration fit, "ols" or "wls".  integrator : "trapezoid" or "simpson".
    g : gravity, m/s².
    """

    candidates: dict
    p0: tuple = COURSE_P0
    v0: tuple = COURSE_V0
    level: float = 0.997
    method: str = "ols"
    integrator: Integrator = "trapezoid"
    g: float = G

    def __post_init__(self) -> None:
        object.__setattr__(self, "candidates", {k: np.asarray(c, dtype=float)
                                                for k, c in self.candidates.items()})
        object.__setattr__(self, "p0", tuple(float(x) for x in np.broadcast_to(self.p0, (2,))))
        object.__setattr__(self, "v0", tuple(float(x) for x in np.broadcast_to(self.v0, (2,))))
        object.__setattr__(self, "level", float(self.level))
        object.__setattr__(self, "g", float(self.g))

    def moved(self, shift) -> VehicleCase:
        """The same case with every candidate translated by ``shift`` (2,) m."""
        s = np.asarray(shift, dtype=float)
        return VehicleCase({k: c + s for k, c in self.candidates.items()}, self.p0, self.v0,
                           self.level, self.method, self.integrator, self.g)


__all__ = ["VehicleCase"]
