"""The trajectory/decision report: the ``tiltbench trajectory --json`` object.

One builder for the object printed by ``trajectory --json``, logged under ``trajectory/`` in
the rerun recordings and written by the demo.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from calib.units import nest, with_units
from calib.vehicle.region import AREA_COMPARISON_UNITS

if TYPE_CHECKING:
    from calib.calibration.tilt_plane import Calibration
    from calib.vehicle.region import ArrivalRegion
    from calib.vehicle.trajectory import Trajectory

ELLIPSE_KEYS = ("level", "semi_axes", "angle_rad", "area", "center")
"""Keys of the arrival ellipse kept in the report."""

TRAJECTORY_UNITS: dict[str, str] = {
    "duration": "s", "n_samples": "count", "level": "1", "p0": "m", "v0": "m/s",
    "bias": "m/s²", "scale": "1", "std": "m", "noise_var": "(m/s²)²",
    "final_raw": "m", "final_corrected": "m",
    "final_velocity_raw": "m/s", "final_velocity_corrected": "m/s",
    "cov": "m²", "cov_calibration": "m²", "cov_noise": "m²",
    "jacobian": "[s², m, s², m] (∂position m / ∂[bias_x m/s², scale_x, bias_y m/s², scale_y])",
    "candidates.*.pos": "m", "candidates.*.mahalanobis": "1", "candidates.*.likelihood": "1",
    "course_box_k": "1", "course_box_a_max": "m/s²", "course_box_bound": "m",
    "ellipse.level": "1", "ellipse.semi_axes": "m", "ellipse.angle_rad": "rad",
    "ellipse.area": "m²", "ellipse.center": "m",
    **nest("area_comparison", AREA_COMPARISON_UNITS),
}
"""Units of :func:`trajectory_tree` (``trajectory --json``, ``trajectory.json``); the
calibration under ``"calibration"`` has
:attr:`calib.calibration.tilt_plane.Calibration._JSON_UNITS`."""


def trajectory_tree(traj: Trajectory, region: ArrivalRegion, cal: Calibration | None = None,
                    method: str = "ols", noise_var_source: str = "given") -> dict:
    """The trajectory/decision object (JSON-ready dictionary).

    Parameters
    ----------
    traj : raw and corrected trajectory (:func:`calib.vehicle.trajectory.compute_trajectory`):
        positions m, velocities m/s, accelerations m/s².
    region : arrival region and decision (:func:`calib.vehicle.region.arrival_region`).
    cal : the calibration used (its ``to_dict()`` goes under ``"calibration"``), optional.
    method : estimation method name of the calibration ("ols", ...).
    noise_var_source : where the vehicle noise variance came from ("given", ...).

    Returns
    -------
    ``traj.to_dict()`` and ``region.to_dict()`` merged (region keys win), with ``level``,
    ``method``, ``noise_var_source``, ``calibration`` (when given) and ``ellipse`` reduced to
    :data:`ELLIPSE_KEYS` (level, semi-axes m, angle rad, area m², centre m).
    """
    out = {**traj.to_dict(), **region.to_dict()}
    out.update(level=region.level, method=method, noise_var_source=noise_var_source)
    if cal is not None:
        out["calibration"] = cal.to_dict()
    out["ellipse"] = {k: region.ellipse.to_dict()[k] for k in ELLIPSE_KEYS}
    return with_units(out, tree_units(out))


def tree_units(tree: dict) -> dict[str, str]:
    """The ``units`` of a trajectory object: :data:`TRAJECTORY_UNITS` plus, when the object
    holds one, the calibration's (under ``calibration.``)."""
    from calib.calibration.tilt_plane import Calibration

    units = dict(TRAJECTORY_UNITS)
    if "calibration" in tree:
        # the calibration's own units (its optional keys, e.g. a pure-error dof, included)
        units.update(nest("calibration", tree["calibration"].get("units")
                          or Calibration._JSON_UNITS))
    return units
