"""validation — an independent validation set for the discrepancy ("gap") workflow.

The generator is written from the physics and the IEEE Std 1293 model equation, not from the
bench: its modules import numpy, scipy and mujoco only, never ``bench`` or ``calib``
(``tests/test_imports.py`` checks it). An error in the bench's effect code therefore cannot
hide itself by appearing on both sides of the comparison. Only :mod:`validation.score` imports
``calib``: it runs :func:`calib.gap.analyze_gap` on the cases and scores its answers.

Conventions (the course's, written again here on purpose)
---------------------------------------------------------
* SI units, angles in radians, ``g`` = :data:`validation.effects.G` = 9.80665 m/s² (standard
  gravity; ``calib`` defaults to 9.8: the difference is a common scale change, absorbed by the
  two scale factors — the ``gravity_mismatch`` confusion of ``docs/effects.md``).
* True specific force on the tilt table (course signs): ``A_rx = -g sin θ``,
  ``A_ry = -g cos θ``; x column first.
* Reading of axis a (IEEE Std 1293: K0 = bias, K1 = 1 + scale, K2, K_ip)::

      A_m = bias + (1 + scale)·LPF_τ( r(clip(a_i, ±L), a_p) ) + drift + walk + v,
      r(a_i, a_p) = a_i + k2·a_i² + k_ip·a_i·a_p,     v ~ N(0, σ²)

  then the output stage rounds to multiples of ``lsb``. ``a_i`` / ``a_p`` are the true
  specific force along the sensor's (possibly misaligned) sensitive axis and along the other
  in-plane axis. Parameter names, keys and units are those of ``docs/effects.md``.

Layout (one job per module)
---------------------------
* :mod:`~validation.designs` — the θ designs: ``(tita, t or None)``.
* :mod:`~validation.sweep`   — the MuJoCo dynamic sweep (own MJCF string, two sensors on the
  hinge axis and two off it), the only place where the physics needs a simulator.
* :mod:`~validation.effects` — the sensor chain above plus the effects outside the catalog.
* :mod:`~validation.sizes`   — effect sizes in σ, defined once.
* :mod:`~validation.cases`   — :class:`~validation.cases.Case` and the three case sets.
* :mod:`~validation.generate` — ``python -m validation.generate OUTDIR``: course-format files.
* :mod:`~validation.score`   — ``python -m validation.score``: runs the gap analysis, scores it.
"""
