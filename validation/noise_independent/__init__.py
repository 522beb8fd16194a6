"""validation.noise_independent — static inertial logs with known noise, made apart from the
bench (``bench.terms``, ``bench.sensor_twin``) and from the estimator (``calib.noise``).

Written from the textbook definitions of each process and of the overlapping Allan variance
(IEEE Std 952-1997 Annex C; El-Sheimy, Hou & Niu, IEEE Trans. Instrum. Meas. 57(1), 2008;
Kasdin, Proc. IEEE 83(5), 1995 for why a bank of first-order Markov processes gives 1/f): it
imports numpy and scipy only, and nothing of ``bench``, ``calib`` or the rest of
``validation``. Its flicker noise is a *sum of AR(1) processes* (the bench and the estimator use
Kasdin's fractional-integration filter instead), its quantization is a real rounding of the
integrated output (Δv counts, not a Gaussian stand-in), and it adds a slow thermal drift that
neither the bench nor the estimator model.

Module: :mod:`.generator` — :class:`~.generator.NoiseSpec`, :func:`~.generator.static_log`
(the readings and the drift path) and :func:`~.generator.true_avar` (the exact expected
overlapping Allan variance of every component, the drift's as measured on its path).
"""
