"""Figures of a calibration, a vehicle run and the N analysis (matplotlib, Agg backend).

Every figure is built by a ``*_figure`` function returning a :class:`matplotlib.figure.Figure`
and written by :func:`save_figure` (:mod:`bench.figures.save`) as PNG or SVG, chosen by the
file extension, atomically (refusing to overwrite without ``force``). Dense scatter layers are
rasterized in SVG so the files stay small. Metadata carrying dates is dropped so the same
data give the same bytes.

Figures (all quantities in SI units, angles in rad):

* :func:`calibration_axis_figure` — per axis: the sensor error A_m − A_r against A_r and
  against θ, with the LS fit (scale·A_r + bias), the truth when known and the ideal sensor (0)
  on a scale where a few per cent of scale and 0.1 m/s² of bias stand apart; the binned mean
  and its ±2σ/√n band drawn over the light samples; estimates ± 1 std (as the command line);
  under each, the residuals A_m − fit with ±σ, their binned mean and the χ²/dof.
* :func:`parameters_figure` — the four estimates with their intervals at the level, next to
  the true values (z-scores).
* :func:`acceleration_figure` — the vehicle's measured, corrected (and true) accelerations.
* :func:`trajectory_figure` — raw and corrected paths, candidates, the level-L region (shaded
  ellipse), the course's 3σ box bound (a rectangle around each candidate) and the true arrival
  on top (the ``trajectory --plot`` figure).
* :func:`uncertainty_growth_figure` — ellipses growing along the corrected path and the
  position standard deviation against time (calibration part and vehicle-noise part).
* :func:`nmin_figure` — Mahalanobis distance of every candidate against the calibration size
  N with the level-L threshold, the data's N, the design N and the a-posteriori range; it says
  why the distances rise with N (Σ_P shrinks) and where the calibration-only curve of the
  nearest candidate crosses the threshold.

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
