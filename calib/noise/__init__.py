"""Noise: the Allan deviation of a still log, its noise terms and the sensor profile.

One job per module:

* :mod:`calib.noise.allan_model`    — σ²_A(τ) of white noise N, bias instability B, rate random
  walk K, quantization Q and a Gauss–Markov term (IEEE Std 952 Annex C), and the exact
  covariance of the overlapping Allan estimates (cached on disk per record length).
* :mod:`calib.noise.allan_fit`      — the GLS fit of the terms, its adequacy checks, the rule
  that picks the model and its τ range, the score intervals and the resolved rules.
* :mod:`calib.noise.allan`          — the overlapping Allan deviation of each axis and its
  result objects (``tiltbench noise``).
* :mod:`calib.noise.closure`        — the twin closure: a twin's Allan deviation against the
  log's, one joint test over every octave (``noise --twin``).
* :mod:`calib.noise.term_units`     — the terms' SI and datasheet units per sensor kind, and
  the reader of a unit as people type it (``ug/rtHz``, ``deg/sqrt(h)``).
* :mod:`calib.noise.datasheet`      — datasheet values with their units against the measured
  terms' intervals: meets / exceeds / inconclusive (``noise --datasheet``).
* :mod:`calib.noise.sensor_profile` — ``sensor.json``: the measured sensor's terms, validated.

The checks a still log must pass first (sample rate, quantization step, stillness) live with
the logs: :mod:`calib.logs.static_log`.
"""
