"""The multi-position result against the θ-based least squares (:func:`compare_methods`) and
the ``calibrate --method multiposition --json`` object (:func:`multiposition_document`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calib.calibration.lackoffit import LackOfFit
from calib.calibration.multiposition.planar import MultiPositionFit
from calib.calibration.multiposition.spatial import MultiPosition3DFit
from calib.conventions import JOINT_PARAM_NAMES
from calib.results import ResultMixin, readonly
from calib.units import nest, with_units


@dataclass(frozen=True, eq=False)
class MethodComparison(ResultMixin):
    """The multi-position estimates against the θ-based least squares on the same run.

    ``z = (p_mp − p_ls) / sqrt(var_mp + var_ls)`` per parameter: the difference in units of
    the combined std. Both use the same readings, so their errors are positively correlated
    and this std is conservative (|z| tends to be small when both are right); when the
    θ-based fit is efficient, ``var(p_mp − p_ls) = var_mp − var_ls`` (Hausman 1978) is the
    exact spread, reported as ``z_hausman`` (NaN, null in JSON, where that difference is not
    positive).
    """

    param_names: tuple[str, ...]
    multiposition: np.ndarray
    multiposition_std: np.ndarray
    least_squares: np.ndarray
    least_squares_std: np.ndarray

    _TITLE = "Multi-position vs θ-based least squares"
    _UNITS = "bias m/s²; scale dimensionless; z dimensionless"
    JSON_UNITS = {"multiposition": "[m/s², 1, m/s², 1]",
                  "multiposition_std": "[m/s², 1, m/s², 1]",
                  "least_squares": "[m/s², 1, m/s², 1]",
                  "least_squares_std": "[m/s², 1, m/s², 1]",
                  "difference": "[m/s², 1, m/s², 1]", "combined_std": "[m/s², 1, m/s², 1]",
                  "z": "1", "z_hausman": "1"}

    def __post_init__(self) -> None:
        for name in ("multiposition", "multiposition_std", "least_squares",
                     "least_squares_std"):
            object.__setattr__(self, name, readonly(getattr(self, name)))
        object.__setattr__(self, "param_names", tuple(self.param_names))

    @property
    def difference(self) -> np.ndarray:
        return self.multiposition - self.least_squares

    @property
    def combined_std(self) -> np.ndarray:
        return np.hypot(self.multiposition_std, self.least_squares_std)

    @property
    def z(self) -> np.ndarray:
        return self.difference / self.combined_std

    @property
    def z_hausman(self) -> np.ndarray:
        v = self.multiposition_std**2 - self.least_squares_std**2
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(v > 0, self.difference / np.sqrt(np.where(v > 0, v, 1.0)), np.nan)

    def summary(self) -> str:
        rows = [f"{'param':<9}{'multi-position':>16}{'least squares':>16}{'difference':>13}"
                f"{'z':>8}"]
        for i, name in enumerate(self.param_names):
            rows.append(f"{name:<9}{self.multiposition[i]:>16.6g}{self.least_squares[i]:>16.6g}"
                        f"{self.difference[i]:>13.4g}{self.z[i]:>8.2f}")
        rows.append("z = difference / sqrt(std_mp² + std_ls²) (combined std)")
        return "\n".join(rows)

    def to_dict(self) -> dict:
        return {"param_names": list(self.param_names),
                "multiposition": self.multiposition.tolist(),
                "multiposition_std": self.multiposition_std.tolist(),
                "least_squares": self.least_squares.tolist(),
                "least_squares_std": self.least_squares_std.tolist(),
                "difference": self.difference.tolist(),
                "combined_std": self.combined_std.tolist(), "z": self.z.tolist(),
                "z_hausman": [float(v) if np.isfinite(v) else None for v in self.z_hausman]}

    @classmethod
    def from_dict(cls, d: dict) -> MethodComparison:
        return cls(tuple(d["param_names"]), d["multiposition"], d["multiposition_std"],
                   d["least_squares"], d["least_squares_std"])


def compare_methods(mp, ls) -> MethodComparison:
    """:class:`MethodComparison` of a multi-position fit (planar or 3-axis: its tilt-plane
    parameters, the first four) and a θ-based :class:`calib.calibration.tilt_plane.Calibration` of
    the same readings."""
    return MethodComparison(JOINT_PARAM_NAMES, mp.params[:4], mp.std[:4], ls.params, ls.std)


def multiposition_document(fit: MultiPositionFit | MultiPosition3DFit,
                           comparison: MethodComparison | None, chosen: str) -> dict:
    """The ``calibrate --method multiposition --json`` object: ``method``, how it was
    ``chosen`` ("given" or "automatic: θ unknown"), the ``fit`` (:meth:`MultiPositionFit.to_dict`),
    the ``comparison`` with the θ-based least squares (or None) and ``units``."""
    units = {**nest("fit", {k: v for k, v in type(fit).JSON_UNITS.items()
                            if not k.startswith("lack_of_fit")}),
             **nest("fit.lack_of_fit", LackOfFit.JSON_UNITS),
             **nest("comparison", MethodComparison.JSON_UNITS)}
    return with_units({"method": "multiposition", "chosen": chosen, "fit": fit.to_dict(),
                       "comparison": None if comparison is None else comparison.to_dict()},
                      units)
