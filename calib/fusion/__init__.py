"""Fusion: the Kalman filters that fuse corrected accelerometers with position fixes.

One job per module:

* :mod:`calib.fusion.kalman`           — what both filters share: the update (Joseph form),
  the process noise, the RTS smoother, the gate threshold.
* :mod:`calib.fusion.linear`           — the course vehicle (no turning): :func:`fuse` →
  :class:`FusionResult`.
* :mod:`calib.fusion.turning`          — the turning vehicle: an extended Kalman filter with
  heading from the gyro, body → world rotation.
* :mod:`calib.fusion.innovation_check` — does the filter believe its fixes? gate count, NIS.
* :mod:`calib.fusion.fix_check`        — before fusing: do the fixes and the gyro agree?

The arrival decision that uses these filters is the vehicle's: :mod:`calib.vehicle.arrival`.
"""
