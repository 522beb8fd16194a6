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
selects the Agg backend and re-exports their public names on first use (PEP 562
``__getattr__``; the first use imports every figure module): together they pull in most of
``calib`` and scipy.stats (≈ 1.5 s), and a command that draws one figure (``gap --report``:
:mod:`bench.figures.save` alone) should not wait for the others. No module here imports from
this package.
Binned means come from :func:`calib.stats.binning.binned_mean`, the covariance along the run from
:func:`calib.vehicle.propagation.position_cov_along`.
"""

from __future__ import annotations

import sys
from typing import Any

import matplotlib

matplotlib.use("Agg")  # before any module of this package imports pyplot

_HOME: dict[str, str] = {
    "acceleration_figure": "acceleration",
    "allan_figure": "allan", "save_allan_plot": "allan",
    "AXIS_LABEL": "calibration", "FIGURE_BINS": "calibration",
    "calibration_axis_figure": "calibration", "calibration_figure": "calibration",
    "save_calibration_plot": "calibration",
    "design_figure": "design",
    "fusion_figure": "fusion", "save_fusion_plot": "fusion",
    "fusion_study_figure": "fusion_study", "save_fusion_study_plot": "fusion_study",
    "multiposition_figure": "multiposition", "save_multiposition_plot": "multiposition",
    "nmin_figure": "nmin",
    "parameters_figure": "parameters",
    "DPI": "save", "FORMATS": "save", "save_figure": "save",
    "save_trajectory_plot": "trajectory", "trajectory_figure": "trajectory",
    "uncertainty_growth_figure": "uncertainty",
    "write_calibration_figures": "write", "write_vehicle_figures": "write",
}
"""Each public name → the module of this package that defines it."""

#: every figure function: result object(s) in, :class:`matplotlib.figure.Figure` out.
FIGURES = ("acceleration_figure", "allan_figure", "calibration_axis_figure",
           "calibration_figure", "design_figure", "fusion_figure", "fusion_study_figure",
           "multiposition_figure", "nmin_figure", "parameters_figure", "trajectory_figure",
           "uncertainty_growth_figure")

__all__ = ["FIGURES", *sorted(_HOME)]


def __getattr__(name: str) -> Any:
    """A public name, taken from its module on first use (then kept here). The first such use
    imports every figure module, as importing this package once did; importing one module of
    it (``bench.figures.save``) does not. Static imports, so the import rules see them."""
    home = _HOME.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from bench.figures import (  # noqa: F401  (each one registered in sys.modules)
        acceleration,
        allan,
        calibration,
        design,
        fusion,
        fusion_study,
        multiposition,
        nmin,
        parameters,
        save,
        trajectory,
        uncertainty,
        write,
    )

    value = getattr(sys.modules[f"{__name__}.{home}"], name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_HOME})
