"""Figure sets written into a directory (the demo's ``figures/``)."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bench.figures.acceleration import acceleration_figure
from bench.figures.calibration import calibration_axis_figure
from bench.figures.nmin import nmin_figure
from bench.figures.parameters import parameters_figure
from bench.figures.save import save_figure_as
from bench.figures.trajectory import trajectory_figure
from bench.figures.uncertainty import uncertainty_growth_figure
from calib.conventions import AXES

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from calib.calibration.tilt_plane import Calibration
    from calib.files.course import Ensayo
    from calib.vehicle.region import ArrivalRegion
    from calib.vehicle.trajectory import Trajectory


def _save(out: Path, figures: dict[str, Callable[[], Figure]], fmt: str | Sequence[str],
          force: bool) -> dict[str, Path]:
    """Build each figure once and write it in each format: ``{name: path}`` for one format
    (``fmt`` a string), ``{"name.fmt": path}`` for several."""
    fmts = (fmt,) if isinstance(fmt, str) else tuple(fmt)
    paths = {}
    for name, build in figures.items():
        written = save_figure_as(build(), [out / f"{name}.{f}" for f in fmts], force)
        for f, p in zip(fmts, written, strict=True):
            paths[name if isinstance(fmt, str) else f"{name}.{f}"] = p
    return paths


def write_calibration_figures(out: str | Path, cal: Calibration, ensayo: Ensayo,
                              truth: Mapping | None = None, level: float = 0.95,
                              fmt: str | Sequence[str] = "png", force: bool = False
                              ) -> dict[str, Path]:
    """``calibration_x``, ``calibration_y`` and ``parameters`` figures in ``out``, in the
    format ``fmt`` (keys: the figure names) or each of several (keys ``name.fmt``)."""
    figures: dict[str, Callable[[], Figure]] = {
        f"calibration_{a}": (lambda a=a: calibration_axis_figure(cal, ensayo, a, truth, level))
        for a in AXES}
    figures["parameters"] = lambda: parameters_figure(cal, truth, level)
    return _save(Path(out), figures, fmt, force)


def write_vehicle_figures(out: str | Path, traj: Trajectory, region: ArrivalRegion,
                          cal: Calibration, n_data: int, true_final: np.ndarray | None = None,
                          true_path: np.ndarray | None = None,
                          true_acc: np.ndarray | None = None,
                          fmt: str | Sequence[str] = "png", force: bool = False,
                          fixed_run: dict | None = None) -> dict[str, Path]:
    """``trajectory`` (helper figure of ``trajectory --plot``), ``acceleration``,
    ``uncertainty_growth`` and ``nmin`` figures in ``out`` (formats and keys as
    :func:`write_calibration_figures`); ``fixed_run``: the
    :func:`calib.vehicle.nmin.fixed_run_nmin` result if already computed (else the figure draws
    it)."""
    return _save(Path(out), {
        "trajectory": lambda: trajectory_figure(traj, region, truth=true_final),
        "acceleration": lambda: acceleration_figure(traj, true_acc),
        "uncertainty_growth": lambda: uncertainty_growth_figure(traj, region, cal,
                                                                true_path=true_path),
        "nmin": lambda: nmin_figure(region, n_data, cal.g, fixed_run=fixed_run),
    }, fmt, force)
