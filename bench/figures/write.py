"""Figure sets written into a directory (the demo's ``figures/``)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bench.figures.acceleration import acceleration_figure
from bench.figures.calibration import calibration_axis_figure
from bench.figures.nmin import nmin_figure
from bench.figures.parameters import parameters_figure
from bench.figures.save import save_figure
from bench.figures.trajectory import trajectory_figure
from bench.figures.uncertainty import uncertainty_growth_figure
from calib.conventions import AXES

if TYPE_CHECKING:
    from calib.calibration.tilt_plane import Calibration
    from calib.files.course import Ensayo
    from calib.vehicle.region import ArrivalRegion
    from calib.vehicle.trajectory import Trajectory


def write_calibration_figures(out: str | Path, cal: Calibration, ensayo: Ensayo,
                              truth: Mapping | None = None, level: float = 0.95,
                              fmt: str = "png", force: bool = False) -> dict[str, Path]:
    """``calibration_x``, ``calibration_y`` and ``parameters`` figures in ``out``."""
    out = Path(out)
    paths = {}
    for a in AXES:
        paths[f"calibration_{a}"] = save_figure(
            calibration_axis_figure(cal, ensayo, a, truth, level),
            out / f"calibration_{a}.{fmt}", force)
    paths["parameters"] = save_figure(parameters_figure(cal, truth, level),
                                      out / f"parameters.{fmt}", force)
    return paths


def write_vehicle_figures(out: str | Path, traj: Trajectory, region: ArrivalRegion,
                          cal: Calibration, n_data: int, true_final: np.ndarray | None = None,
                          true_path: np.ndarray | None = None,
                          true_acc: np.ndarray | None = None, fmt: str = "png",
                          force: bool = False, fixed_run: dict | None = None
                          ) -> dict[str, Path]:
    """``trajectory`` (helper figure of ``trajectory --plot``), ``acceleration``,
    ``uncertainty_growth`` and ``nmin`` figures in ``out``; ``fixed_run``: the
    :func:`calib.vehicle.nmin.fixed_run_nmin` result if already computed (else the figure draws
    it)."""
    out = Path(out)
    paths = {"trajectory": save_figure(trajectory_figure(traj, region, truth=true_final),
                                       out / f"trajectory.{fmt}", force),
             "acceleration": save_figure(acceleration_figure(traj, true_acc),
                                         out / f"acceleration.{fmt}", force),
             "uncertainty_growth": save_figure(
                 uncertainty_growth_figure(traj, region, cal, true_path=true_path),
                 out / f"uncertainty_growth.{fmt}", force),
             "nmin": save_figure(nmin_figure(region, n_data, cal.g, fixed_run=fixed_run),
                                 out / f"nmin.{fmt}", force)}
    return paths
