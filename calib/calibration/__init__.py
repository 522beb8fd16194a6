"""Calibration: the sensor errors estimated by least squares, with honest covariances.

Sensor model (course; IEEE Std 1293 K0 = bias, K1 = 1 + scale): ``A_m = (1 + scale)·A_r +
bias + v``, with the course signs ``A_rx = −g sin θ``, ``A_ry = −g cos θ``.

One job per module:

* :mod:`calib.calibration.ls`          — per-axis and joint (W)LS by QR: :class:`FitResult`.
* :mod:`calib.calibration.tilt_plane`  — both tilt-plane axes from a tilt-table run:
  :func:`calibrate` → :class:`Calibration`.
* :mod:`calib.calibration.lackoffit`   — pure error vs lack of fit over repeated θ.
* :mod:`calib.calibration.correct`     — the model inverted: ``A_r = (A_m − bias)/(1 + scale)``.
* :mod:`calib.calibration.calfile`     — the calibration file ``cal.json`` (and its ``.mat``),
  version 3: its fields (:mod:`~calib.calibration.calfile_fields`), the six-face part
  (:mod:`~calib.calibration.calfile_sixface`), what it applies to (the log's axes and unit,
  the source of g: :mod:`~calib.calibration.readings`), and a log corrected with it
  (:mod:`~calib.calibration.corrected_log`, ``tiltbench apply``).
* :mod:`calib.calibration.montecarlo`  — batched Monte Carlo of "generate + calibrate".
* :mod:`calib.calibration.multiposition` — without an angle reference: held poses on the
  gravity circle (planar) or sphere (3-axis).
"""
