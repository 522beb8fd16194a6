"""The reader-neutral form of a log (:class:`RawLog`) and the unit vocabulary of headers.

Units are recognized from what a header states — ``ax (m/s^2)``, ``acc_x [g]``, ``az_mg``,
``gyro_z (deg/s)``, ``Time (s)`` — or from what a format documents (phyphox and ROS state SI;
Sensor Logger documents m/s² for its calibrated accelerometer files). Nothing is inferred from
the values' size. Acceleration units: ``m/s2``, ``g`` (standard gravity as a unit, converted
with the command's g), ``mg``, ``counts`` (raw ADC counts; need ``--sensitivity`` counts per g).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

ACCEL_UNITS = ("m/s2", "g", "mg", "counts")
"""Acceleration units a log may be in (``--units``)."""
GYRO_UNITS = ("rad/s", "deg/s")
"""Angular-rate units a log may be in (``--gyro-unit``)."""

_ACCEL_WORDS = {
    "m/s2": ("m/s^2", "m/s²", "m/s2", "m s^-2", "m s-2", "ms^-2", "ms-2", "m*s^-2", "ms2",
             "mps2", "m_s2", "m/s/s", "m.s^-2", "m.s-2"),
    "g": ("g", "g0", "gee", "g_0"),
    "mg": ("mg", "milli-g", "millig"),
    "counts": ("counts", "count", "lsb", "raw", "adc", "digits"),
}
_GYRO_WORDS = {"rad/s": ("rad/s", "rad s^-1", "rad*s^-1", "rads", "rad_s", "rps", "rad.s^-1",
                         "rad s-1", "rad/sec"),
               "deg/s": ("deg/s", "°/s", "dps", "degps", "deg_s", "deg/sec", "deg s^-1")}
_ANGLE_WORDS = {"rad": ("rad", "radian", "radians"), "deg": ("deg", "°", "degree", "degrees")}
_TIME_WORDS = {1.0: ("s", "sec", "secs", "second", "seconds"), 1e-3: ("ms", "msec"),
               1e-6: ("us", "µs", "μs", "usec"), 1e-9: ("ns", "nsec")}

_BRACKET = re.compile(r"^(.*?)\s*[\(\[]\s*([^\)\]]*?)\s*[\)\]]\s*$")
_SUFFIX = re.compile(r"^(.+?)[_ ](mps2|m_s2|ms2|mg|g|counts|lsb|raw|dps|degps|deg_s|rad_s|rads|"
                     r"deg|rad|ns|us|ms|s)$")


def split_unit(name: str) -> tuple[str, str | None]:
    """A header cell as (base name, unit text or None): ``"Acceleration x (m/s^2)"`` →
    ``("acceleration_x", "m/s^2")``; ``"az_mg"`` → ``("az", "mg")``; ``"ax"`` → ``("ax",
    None)``. The base is lower case with spaces, dots and dashes as ``_``."""
    text = name.strip().strip('"').strip()
    unit = None
    m = _BRACKET.match(text)
    if m:
        text, unit = m.group(1), m.group(2)
    base = re.sub(r"[\s.\-]+", "_", text.strip().lower()).strip("_")
    if unit is None:
        m = _SUFFIX.match(base)
        if m:
            base, unit = m.group(1), m.group(2)
    return base, unit


def _lookup(words: dict, unit: str) -> Any:
    folded = unit.strip().lower()
    for key, names in words.items():
        if folded in names or folded.replace(" ", "") in names:
            return key
    return None


def accel_unit(unit: str | None) -> str | None:
    """The acceleration unit (:data:`ACCEL_UNITS`) a header's unit text names, else None."""
    return None if unit is None else _lookup(_ACCEL_WORDS, unit)


def gyro_unit(unit: str | None) -> str | None:
    """The angular-rate unit (:data:`GYRO_UNITS`) a header's unit text names, else None."""
    return None if unit is None else _lookup(_GYRO_WORDS, unit)


def angle_unit(unit: str | None) -> str | None:
    """``"rad"`` or ``"deg"`` from a header's unit text, else None."""
    return None if unit is None else _lookup(_ANGLE_WORDS, unit)


def time_factor(unit: str | None) -> float | None:
    """Seconds per unit of a time column (``s`` 1, ``ms`` 1e-3, ``us`` 1e-6, ``ns`` 1e-9)."""
    return None if unit is None else _lookup(_TIME_WORDS, unit)


@dataclass(frozen=True)
class RawLog:
    """A log as read, before axes, units and poses (:func:`calib.logs.reader.read_log` does those).

    Attributes
    ----------
    fmt : the reader: ``csv``, ``phyphox``, ``sensorlogger``, ``rosbag1``, ``rosbag2``,
        ``mat``.
    acc : the log's acceleration axes (``"x"``, ``"y"``, ``"z"``) → (N,) samples in
        ``acc_unit``.
    acc_unit : unit stated by the header or documented by the format; None: not stated.
    t : (N,) s or None.
    theta : (N,) angle in ``theta_unit`` (None: not stated) or None.
    label : (N,) pose labels as text (a label column) or None.
    gyro : the log's gyro axes (``"x"`` …) → (N,) rates in ``gyro_unit``; a single named
        rate about the tilt axis is stored under ``"tilt"``.
    rows : (N,) where each sample came from (file line, message number or index), for
        messages; ``row_word`` names it.
    mapping : role → the column, field or variable it was read from (provenance).
    columns : role → the column name to quote in messages (acc axes as ``acc.x`` …).
    notes : what the reader saw (delimiter, decimal mark, topic, …) — JSON-able.
    """

    fmt: str
    acc: dict[str, np.ndarray]
    acc_unit: str | None = None
    t: np.ndarray | None = None
    theta: np.ndarray | None = None
    theta_unit: str | None = None
    label: np.ndarray | None = None
    gyro: dict[str, np.ndarray] = field(default_factory=dict)
    gyro_unit: str | None = None
    rows: np.ndarray | None = None
    row_word: str = "sample"
    mapping: dict[str, str] = field(default_factory=dict)
    notes: dict[str, Any] = field(default_factory=dict)

    @property
    def n(self) -> int:
        return int(next(iter(self.acc.values())).shape[0]) if self.acc else 0

    def where(self, i: int) -> str:
        """Sample ``i`` in the file's own terms (``line 57``, ``message 12``, ``index 3``)."""
        if self.rows is None:
            return f"{self.row_word} {i}"
        return f"{self.row_word} {int(self.rows[i])}"


__all__ = ["ACCEL_UNITS", "GYRO_UNITS", "RawLog", "accel_unit", "angle_unit", "gyro_unit",
           "split_unit", "time_factor"]
