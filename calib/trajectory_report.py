"""The trajectory/decision report: the ``tiltbench trajectory --json`` object.

One builder for the object printed by ``trajectory --json``, logged under ``trajectory/`` in
the rerun recordings and written by the demo.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from calib.calibration import Calibration
    from calib.region import ArrivalRegion
    from calib.trajectory import Trajectory

ELLIPSE_KEYS = ("level", "semi_axes", "angle_rad", "area", "center")
"""Keys of the arrival ellipse kept in the report."""


def trajectory_tree(traj: Trajectory, region: ArrivalRegion, cal: Calibration | None = None,
                    method: str = "ols", noise_var_source: str = "given") -> dict:
    """The trajectory/decision object (JSON-ready dictionary).

    Parameters
    ----------
    traj : raw and corrected trajectory (:func:`calib.trajectory.compute_trajectory`):
        positions m, velocities m/s, accelerations m/s².
    region : arrival region and decision (:func:`calib.region.arrival_region`).
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
    return out
