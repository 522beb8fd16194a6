"""Vehicle: where the vehicle went and where it arrived, with a region of stated coverage.

One job per module:

* :mod:`calib.vehicle.trajectory`         — correct, integrate twice (course vehicle).
* :mod:`calib.vehicle.turning_trajectory` — dead reckoning of a vehicle that turns.
* :mod:`calib.vehicle.region`             — the arrival point's covariance, its ellipse and the
  decision among the candidate points.
* :mod:`calib.vehicle.propagation`        — the position covariance along the run.
* :mod:`calib.vehicle.arrival`            — the arrival fused with position fixes.
* :mod:`calib.vehicle.report`             — the ``tiltbench trajectory --json`` object.
* :mod:`calib.vehicle.nmin`               — how many calibration samples N decide the arrival.
"""
