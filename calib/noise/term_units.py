"""Units of the noise terms per sensor kind: SI (as the JSON outputs write them) and as
datasheets print them (µg/√Hz, µg, °/√h, °/h), with the factor between the two.

=====================  ======================  ===========  =====================  ===========
term                   accelerometer, SI       datasheet    gyro, SI               datasheet
=====================  ======================  ===========  =====================  ===========
white_noise_density N  (m/s^2)/sqrt(Hz)        µg/√Hz       (rad/s)/sqrt(Hz)       °/√h (ARW)
bias_instability B     m/s^2                   µg           rad/s                  °/h
rate_random_walk K     m/s^2/sqrt(s)           µg/√s        rad/s/sqrt(s)          °/h/√h
quantization_noise Q   m/s (Δv step/√12)       mm/s         rad (Δθ step/√12)      µrad
gauss_markov σ         m/s^2                   µg           rad/s                  °/h
correlation time T_c   s                       s            s                      s
=====================  ======================  ===========  =====================  ===========

Factors: 1 g = 9.80665 m/s² (the standard gravity that datasheets' "g" means, not the local
g), so 1 µg = 9.80665e-6 m/s²; 1 rad = 180/π °; 1 h = 3600 s, so a gyro's white-noise
density N in rad/s/√Hz = rad/√s is ``N·(180/π)·√3600 = N·(180/π)·60`` °/√h (angle random walk,
IEEE Std 952: the −½ line at τ = 1 h read in °/h·√h), a bias instability in rad/s is
``B·(180/π)·3600`` °/h, a rate random walk in rad/s/√s is ``K·(180/π)·3600·60`` °/h/√h.
"""

from __future__ import annotations

import math

from calib.conventions import STANDARD_GRAVITY

KINDS: tuple[str, ...] = ("accelerometer", "gyro")
"""Sensor kinds an axis belongs to."""

SI_UNITS: dict[str, dict[str, str]] = {
    "accelerometer": {"white_noise_density": "(m/s^2)/sqrt(Hz)", "bias_instability": "m/s^2",
                      "rate_random_walk": "m/s^2/sqrt(s)", "quantization_noise": "m/s",
                      "gauss_markov": "m/s^2", "correlation_time": "s",
                      "reading": "m/s^2"},
    "gyro": {"white_noise_density": "(rad/s)/sqrt(Hz)", "bias_instability": "rad/s",
             "rate_random_walk": "rad/s/sqrt(s)", "quantization_noise": "rad",
             "gauss_markov": "rad/s", "correlation_time": "s", "reading": "rad/s"},
}
"""SI unit of each term's value, interval and upper bound (and of the readings), per kind."""

_MICRO_G = STANDARD_GRAVITY * 1e-6
_DEG = 180.0 / math.pi
DATASHEET: dict[str, dict[str, tuple[str, float]]] = {
    "accelerometer": {"white_noise_density": ("µg/√Hz", 1.0 / _MICRO_G),
                      "bias_instability": ("µg", 1.0 / _MICRO_G),
                      "rate_random_walk": ("µg/√s", 1.0 / _MICRO_G),
                      "quantization_noise": ("mm/s", 1e3),
                      "gauss_markov": ("µg", 1.0 / _MICRO_G),
                      "correlation_time": ("s", 1.0)},
    "gyro": {"white_noise_density": ("°/√h", _DEG * 60.0),
             "bias_instability": ("°/h", _DEG * 3600.0),
             "rate_random_walk": ("°/h/√h", _DEG * 3600.0 * 60.0),
             "quantization_noise": ("µrad", 1e6),
             "gauss_markov": ("°/h", _DEG * 3600.0),
             "correlation_time": ("s", 1.0)},
}
"""Per kind and term: (the datasheet unit, the factor from SI): datasheet = SI × factor."""


def kind_of(axis: str) -> str:
    """The sensor kind of an axis name: ``gyro_*`` is a gyro, anything else an
    accelerometer."""
    return "gyro" if axis.startswith("gyro") else "accelerometer"


def si_unit(name: str, kind: str) -> str:
    """SI unit of term ``name`` for ``kind`` (module table)."""
    return SI_UNITS[kind][name]


def datasheet(name: str, kind: str, value: float | None) -> tuple[float | None, str]:
    """``value`` (SI) in the datasheet unit of term ``name`` for ``kind``: (value, unit)."""
    unit, factor = DATASHEET[kind][name]
    return (None if value is None else float(value) * factor), unit


__all__ = ["DATASHEET", "KINDS", "SI_UNITS", "datasheet", "kind_of", "si_unit"]
