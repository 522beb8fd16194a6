"""calib — the estimation side of tiltbench.

Everything here works on measured arrays only; it never imports ``bench`` or ``mujoco``, so an
estimator cannot peek at the simulation or the truth.

Conventions (stated once, used everywhere)
------------------------------------------
* SI units: accelerations in m/s², time in s, positions in m, angles in **radians** — any
  finite value (several turns, negative, past 2π); degrees are told from the readings, never
  from a range (:mod:`calib.angles`).
* ``g`` = 9.8 m/s² unless the user gives another value (:data:`calib.conventions.G`).
* Columns: x first, then y. ``datos`` is (N, 2) = [A_mx, A_my].
* Course tilt-table convention (reference accelerations, specific force along each sensitive
  axis)::

      A_rx = -g · sin θ          A_ry = -g · cos θ

* Course sensor model (IEEE Std 1293 terms K0 = bias, K1 = 1 + scale)::

      A_m = (1 + scale) · A_r + bias + v,     v ~ N(0, σ²)

  ``scale`` is dimensionless (positive: the sensor reads too much), ``bias`` in m/s²
  (positive: the reading is shifted up). Correction: ``A_r = (A_m - bias) / (1 + scale)``.
* Parameter order in every vector and covariance: per axis ``[bias, scale]``; jointly
  ``[bias_x, scale_x, bias_y, scale_y]``.

Types
-----
:class:`calib.io.Ensayo`  ``tita`` (N,) rad, ``datos`` (N, 2) m/s², optional ``t`` (N,) s.
:class:`calib.io.Acel`    ``t`` (M,) s, ``aerr`` (M, 2) m/s² (vehicle run, uncorrected).

Public API (``import calib`` is cheap: every name below is imported on first use)
-------------------------------------------------------------------------------
Readers      :func:`read_ensayo`, :func:`read_acel`, :func:`read_puntos`, :func:`read_datos`
             → :class:`Ensayo`, :class:`Acel` (``calib.io``)
Fits         :func:`fit_axis`, :func:`fit_joint` → :class:`FitResult` (``calib.ls``);
             :func:`calibrate` → :class:`Calibration` (``calib.calibration``)
Correction   :func:`correct` — ``(A_m - bias) / (1 + scale)`` (``calib.correct``)
Trajectory   :func:`compute_trajectory` → :class:`Trajectory` (``calib.trajectory``)
Arrival      :func:`arrival_region` → :class:`ArrivalRegion` (``calib.region``);
             :func:`analyze_nmin` → ``NminResult`` (``calib.nmin``)
Gap          :func:`analyze_gap` → :class:`GapAnalysis` (``calib.gap``)
Fusion       :func:`fuse` → :class:`FusionResult` — Kalman filter and RTS smoother with
             position fixes (``calib.fusion``; the turning vehicle: ``calib.fusion_turning``)
Files        :func:`save_calibration`, :func:`load_calibration` (``calib.calfile``)
Monte Carlo  :func:`simulate_calibrations` → :class:`MonteCarloResult` (``calib.montecarlo``)
Design       :func:`analyze_design` → ``DesignResult`` (``calib.design``)

Every result type is frozen, compares by value (``==``), renders in a notebook
(``_repr_markdown_``) and round-trips: ``T.from_dict(x.to_state()) == x`` (see
:mod:`calib.results`). ``calib.correct`` names the function; the module is
``sys.modules["calib.correct"]`` (``from calib.correct import apply_errors``).

Example
-------
>>> import numpy as np
>>> import calib
>>> th = np.linspace(0.0, 2 * np.pi, 200, endpoint=False)
>>> datos = np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)]) * 1.01 + 0.05
>>> cal = calib.calibrate(calib.Ensayo(th, datos), noise_var=[0.25, 0.64])
>>> np.round(cal.scale, 6).tolist(), np.round(cal.bias, 6).tolist()
([0.01, 0.01], [0.05, 0.05])
"""

import sys
import types

from calib.exports import install_lazy_exports

_EXPORTS: dict[str, str] = {
    "read_ensayo": "calib.io:read_ensayo",
    "read_acel": "calib.io:read_acel",
    "read_puntos": "calib.io:read_puntos",
    "read_datos": "calib.io:read_datos",
    "Ensayo": "calib.io:Ensayo",
    "Acel": "calib.io:Acel",
    "fit_axis": "calib.ls:fit_axis",
    "fit_joint": "calib.ls:fit_joint",
    "FitResult": "calib.ls:FitResult",
    "calibrate": "calib.calibration:calibrate",
    "Calibration": "calib.calibration:Calibration",
    "correct": "calib.correct:correct",
    "compute_trajectory": "calib.trajectory:compute_trajectory",
    "Trajectory": "calib.trajectory:Trajectory",
    "arrival_region": "calib.region:arrival_region",
    "ArrivalRegion": "calib.region:ArrivalRegion",
    "analyze_nmin": "calib.nmin:analyze_nmin",
    "analyze_gap": "calib.gap:analyze_gap",
    "GapAnalysis": "calib.gap:GapAnalysis",
    "fuse": "calib.fusion:fuse",
    "FusionResult": "calib.fusion:FusionResult",
    "save_calibration": "calib.calfile:save_calibration",
    "load_calibration": "calib.calfile:load_calibration",
    "simulate_calibrations": "calib.montecarlo:simulate_calibrations",
    "MonteCarloResult": "calib.montecarlo:MonteCarloResult",
    "analyze_design": "calib.design:analyze_design",
}
"""Public name → ``"module:attribute"`` (PEP 562 lazy exports)."""

__all__ = list(_EXPORTS)


def _module(name: str) -> types.ModuleType:
    """Import one of the exporting modules. Plain import statements, no ``importlib``: the
    import-rule test (``tests/test_imports.py``) sees every edge."""
    if name == "calib.io":
        import calib.io
    elif name == "calib.ls":
        import calib.ls
    elif name == "calib.calibration":
        import calib.calibration
    elif name == "calib.correct":
        import calib.correct
    elif name == "calib.trajectory":
        import calib.trajectory
    elif name == "calib.region":
        import calib.region
    elif name == "calib.nmin":
        import calib.nmin
    elif name == "calib.gap":
        import calib.gap
    elif name == "calib.fusion":
        import calib.fusion
    elif name == "calib.calfile":
        import calib.calfile
    elif name == "calib.montecarlo":
        import calib.montecarlo
    elif name == "calib.design":
        import calib.design  # noqa: F401
    return sys.modules[name]


install_lazy_exports(__name__, _EXPORTS, _module)
