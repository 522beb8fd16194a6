"""bench — the simulation side of tiltbench: MuJoCo models, sensor error models, run
generators, datasets, recordings, the discrepancy workflow and the command line.

``bench`` may import ``calib``; never the other way round.

Public API (``import bench`` is cheap: mujoco, matplotlib, rerun and scipy load on first use)
------------------------------------------------------------------------------------------
Calibration runs  :func:`generate_calibration` (``CalibrationConfig`` → a run with ``tita``
                  (N,) rad, ``datos`` (N, 2) m/s²), :class:`CalibrationConfig`,
                  :class:`ThetaDesign`, :class:`SweepProfile` (``bench.tilt``)
Sensor errors     :class:`SensorErrorModel` (``bench.sensors``)
Vehicle runs      :func:`make_vehicle_run`, :class:`VehicleConfig` (``bench.vehicle``)
Course sets       :func:`make_course_set` (``bench.course``)
Gap workflow      :func:`run_gap` → :class:`GapReport` (``bench.gap``)
Recordings        :func:`record_calibration`, :func:`read_recording` (``bench.record``)
Ground truth      :func:`validate` → :class:`Validation` (``bench.validate``)

``bench.validate`` names the function; the module is ``sys.modules["bench.validate"]``
(``from bench.validate import design_cov``).

Example
-------
>>> import bench, calib
>>> run = bench.generate_calibration(bench.CalibrationConfig(), seed=1)  # doctest: +SKIP
>>> cal = calib.calibrate(run.ensayo(), noise_var=[0.25, 0.64])  # doctest: +SKIP
"""

import sys
import types

from bench.version import __version__
from calib.exports import install_lazy_exports

_EXPORTS: dict[str, str] = {
    "generate_calibration": "bench.tilt:generate_calibration",
    "CalibrationConfig": "bench.tilt:CalibrationConfig",
    "ThetaDesign": "bench.tilt:ThetaDesign",
    "SweepProfile": "bench.tilt:SweepProfile",
    "SensorErrorModel": "bench.sensors:SensorErrorModel",
    "make_vehicle_run": "bench.vehicle:make_vehicle_run",
    "VehicleConfig": "bench.vehicle:VehicleConfig",
    "make_course_set": "bench.course:make_course_set",
    "run_gap": "bench.gap:run_gap",
    "GapReport": "bench.gap:GapReport",
    "record_calibration": "bench.record:record_calibration",
    "read_recording": "bench.record:read_recording",
    "validate": "bench.validate:validate",
    "Validation": "bench.validate:Validation",
}
"""Public name → ``"module:attribute"`` (PEP 562 lazy exports)."""

__all__ = ["__version__", *_EXPORTS]


def _module(name: str) -> types.ModuleType:
    """Import one of the exporting modules. Plain import statements, no ``importlib``: the
    import-rule test (``tests/test_imports.py``) sees every edge."""
    if name == "bench.tilt":
        import bench.tilt
    elif name == "bench.sensors":
        import bench.sensors
    elif name == "bench.vehicle":
        import bench.vehicle
    elif name == "bench.course":
        import bench.course
    elif name == "bench.gap":
        import bench.gap
    elif name == "bench.record":
        import bench.record
    elif name == "bench.validate":
        import bench.validate  # noqa: F401
    return sys.modules[name]


install_lazy_exports(__name__, _EXPORTS, _module)
