"""Figures of a calibration, a vehicle run and the N analysis (matplotlib, Agg backend).

Every figure is built by a ``*_figure`` function returning a :class:`matplotlib.figure.Figure`
and written by :func:`save_figure` (:mod:`bench.figures.save`) as PNG or SVG, chosen by the
file extension, atomically (refusing to overwrite without ``force``). Dense scatter layers are
rasterized in SVG so the files stay small. Metadata carrying dates is dropped so the same
data give the same bytes.

Figures (all quantities in SI units, angles in rad):

* :func:`calibration_axis_figure` — per axis: measured A_m and the fitted line against A_r and
  against θ (course reports' figures 3–6), with the true line when the truth is known; under
  each, the residuals with the ±σ band, a binned mean (structure the model misses stands out)
  and the χ²/dof.
* :func:`parameters_figure` — the four estimates with their intervals at the level, next to
  the true values (z-scores).
* :func:`acceleration_figure` — the vehicle's measured, corrected (and true) accelerations.
* :func:`trajectory_figure` — raw and corrected paths, candidates, the confidence ellipse
  (the ``trajectory --plot`` figure).
* :func:`uncertainty_growth_figure` — ellipses growing along the corrected path and the
  position standard deviation against time (calibration part and vehicle-noise part).
* :func:`nmin_figure` — Mahalanobis distance of every candidate against the calibration size
  N with the level-L threshold, the data's N, the design N and the a-posteriori range.

One module per figure (``calibration``, ``parameters``, ``acceleration``, ``trajectory``,
``uncertainty``, ``nmin``), ``save`` for writing and ``write`` for the figure sets; this package
selects the Agg backend and re-exports their public names (no module here imports from it).
Binned means come from :func:`calib.binning.binned_mean`, the covariance along the run from
:func:`calib.propagation.position_cov_along`.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")  # before any module of this package imports pyplot

from bench.figures.acceleration import acceleration_figure  # noqa: E402
from bench.figures.calibration import (  # noqa: E402
    AXIS_LABEL,
    FIGURE_BINS,
    calibration_axis_figure,
    calibration_figure,
    save_calibration_plot,
)
from bench.figures.nmin import nmin_figure  # noqa: E402
from bench.figures.parameters import parameters_figure  # noqa: E402
from bench.figures.save import DPI, FORMATS, save_figure  # noqa: E402
from bench.figures.trajectory import save_trajectory_plot, trajectory_figure  # noqa: E402
from bench.figures.uncertainty import uncertainty_growth_figure  # noqa: E402
from bench.figures.write import write_calibration_figures, write_vehicle_figures  # noqa: E402

__all__ = ["AXIS_LABEL", "DPI", "FIGURE_BINS", "FORMATS", "acceleration_figure",
           "calibration_axis_figure", "calibration_figure", "nmin_figure",
           "parameters_figure", "save_calibration_plot", "save_figure",
           "save_trajectory_plot", "trajectory_figure", "uncertainty_growth_figure",
           "write_calibration_figures", "write_vehicle_figures"]
