"""calib — the estimation side of tiltbench.

Everything here works on measured arrays only; it never imports ``bench`` or ``mujoco``, so an
estimator cannot peek at the simulation or the truth.

Conventions (stated once, used everywhere)
------------------------------------------
* SI units: accelerations in m/s², time in s, positions in m, angles in **radians**.
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
"""
