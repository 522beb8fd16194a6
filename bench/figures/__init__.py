"""Figures of a calibration, a vehicle run and the N analysis (matplotlib, Agg backend).

Every figure is built by a ``*_figure`` function returning a :class:`matplotlib.figure.Figure`
and written by :func:`save_figure` (:mod:`bench.figures.save`) as PNG or SVG, chosen by the
file extension, atomically (refusing to overwrite without ``force``). Dense scatter layers are
rasterized in SVG so the files stay small. Metadata carrying dates is dropped so the same
data give the same bytes.

Figures (all quantities in SI units, angles in rad). Every function takes result objects and
returns the :class:`matplotlib.figure.Figure` (close it with ``plt.close(fig)``); every axis
label carries its unit; every plotted estimate carries its uncertainty at one level per
figure, said in the legend (docs/python-api.md, section 6):

* :func:`calibration_axis_figure`, :func:`calibration_figure` (``Calibration``, ``Ensayo``) —
  per axis: the sensor error A_m − A_r against A_r and θ, the LS fit with its confidence band,
  the truth when known and the ideal sensor (0); the binned mean with its ±q·σ/√n band (n
  samples per bin); estimates ± their level-L half-width; residuals with ±σ below.
* :func:`parameters_figure` (``Calibration``) — the four estimates with their intervals at the
  level, next to the true values (z-scores).
* :func:`acceleration_figure` (``Trajectory``) — measured, corrected (with the 95 % band of its
  binned mean) and true accelerations.
* :func:`trajectory_figure` (``Trajectory``, ``ArrivalRegion``) — raw and corrected paths,
  candidates, the level-L region, the course's 3σ box bound and the true arrival.
* :func:`uncertainty_growth_figure` (``Trajectory``, ``ArrivalRegion``, ``Calibration``) —
  ellipses along the corrected path and the position std against time.
* :func:`nmin_figure` (``ArrivalRegion``) — Mahalanobis distances against the calibration
  size N; P(decision made and right) against N with exact 95 % binomial bars.
* :func:`fusion_figure` (``Trajectory``, ``ArrivalRegion``, ``FusionResult``) — dead
  reckoning, fixes, the filtered (and smoothed) path, both regions, the truth when given.
* :func:`fusion_study_figure` (``StudyResult``) — RMS error with 95 % χ² bars, stated std,
  the outage panel, the NEES along the path.
* :func:`design_figure` (``DesignResult``) — power against effect size (Monte Carlo points
  with exact 95 % intervals).
* :func:`allan_figure` (``NoiseCharacterization``), :func:`multiposition_figure`
  (``MultiPositionFit``).

One module per figure, ``save`` for writing and ``write`` for the figure sets; this package
selects the Agg backend and re-exports their public names (no module here imports from it).
Binned means come from :func:`calib.stats.binning.binned_mean`, the covariance along the run from
:func:`calib.vehicle.propagation.position_cov_along`.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")  # before any module of this package imports pyplot

from bench.figures.acceleration import acceleration_figure  # noqa: E402
from bench.figures.allan import allan_figure, save_allan_plot  # noqa: E402
from bench.figures.calibration import (  # noqa: E402
    AXIS_LABEL,
    FIGURE_BINS,
    calibration_axis_figure,
    calibration_figure,
    save_calibration_plot,
)
from bench.figures.design import design_figure  # noqa: E402
from bench.figures.fusion import fusion_figure, save_fusion_plot  # noqa: E402
from bench.figures.fusion_study import fusion_study_figure, save_fusion_study_plot  # noqa: E402
from bench.figures.multiposition import (  # noqa: E402
    multiposition_figure,
    save_multiposition_plot,
)
from bench.figures.nmin import nmin_figure  # noqa: E402
from bench.figures.parameters import parameters_figure  # noqa: E402
from bench.figures.save import DPI, FORMATS, save_figure  # noqa: E402
from bench.figures.trajectory import save_trajectory_plot, trajectory_figure  # noqa: E402
from bench.figures.uncertainty import uncertainty_growth_figure  # noqa: E402
from bench.figures.write import write_calibration_figures, write_vehicle_figures  # noqa: E402

#: every figure function: result object(s) in, :class:`matplotlib.figure.Figure` out.
FIGURES = ("acceleration_figure", "allan_figure", "calibration_axis_figure",
           "calibration_figure", "design_figure", "fusion_figure", "fusion_study_figure",
           "multiposition_figure", "nmin_figure", "parameters_figure", "trajectory_figure",
           "uncertainty_growth_figure")

__all__ = ["AXIS_LABEL", "DPI", "FIGURES", "FIGURE_BINS", "FORMATS", "acceleration_figure",
           "allan_figure", "calibration_axis_figure", "calibration_figure", "design_figure",
           "fusion_figure", "fusion_study_figure", "multiposition_figure", "nmin_figure",
           "parameters_figure", "save_allan_plot", "save_calibration_plot", "save_figure",
           "save_fusion_plot", "save_fusion_study_plot", "save_multiposition_plot",
           "save_trajectory_plot", "trajectory_figure", "uncertainty_growth_figure",
           "write_calibration_figures", "write_vehicle_figures"]
