"""Noise: the Allan deviation of a still log, its noise terms and the sensor profile.

One job per module:

* :mod:`calib.noise.allan_model`    — σ²_A(τ) of white noise N, bias instability B, rate random
  walk K and quantization Q (IEEE Std 952 Annex C), and the covariance of Allan estimates.
* :mod:`calib.noise.allan`          — the overlapping Allan deviation of each axis and the fit of
  the terms, with intervals (``tiltbench noise``).
* :mod:`calib.noise.sensor_profile` — ``sensor.json``: the measured sensor's terms, validated.

The checks a still log must pass first (sample rate, quantization step, stillness) live with
the logs: :mod:`calib.logs.static_log`.
"""
