"""The reader-neutral form of a log (:class:`RawLog`) and the unit vocabulary of headers.

Units are recognized from what a header states — ``ax (m/s^2)``, ``acc_x [g]``, ``az_mg``,
``gyro_z (deg/s)``, ``gyro_x_deg_per_s``, ``Time (s)`` — or from what a format documents
(phyphox and ROS state SI; Sensor Logger documents m/s² for its calibrated accelerometer
files). Nothing is inferred from the values' size. Acceleration units: ``m/s2``, ``g``
(standard gravity as a unit, converted with the command's g), ``mg``, ``counts`` (raw ADC
counts; need ``--sensitivity`` counts per g).

Unit suffixes (:func:`split_unit`), after ``_`` or a space at the end of a name:

============  =====================================================================
unit          suffixes
============  =====================================================================
m/s²          ``_m_per_s2``, ``_m_per_s_2``, ``_mps2``, ``_m_s2``, ``_ms2``
g, mg         ``_g``, ``_mg``
counts        ``_counts``, ``_lsb``, ``_raw``
deg/s         ``_deg_per_s``, ``_deg_per_sec``, ``_dps``, ``_degps``, ``_deg_s``
rad/s         ``_rad_per_s``, ``_rad_per_sec``, ``_rad_s``, ``_rads``, ``_rps``
angle         ``_deg``, ``_rad``
time          ``_s``, ``_ms``, ``_us``, ``_ns``
============  =====================================================================

The longest suffix wins (``gyro_x_deg_per_s`` is ``gyro_x`` in deg/s, not ``gyro_x_deg_per``
in s). A unit text that is not read here is refused by the reader unless the matching option
(``--units``, ``--gyro-unit``, ``--time-unit``) states the unit: the option then wins.
"""

from __future__ import annotations

import operator
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

GAP_FACTOR = 5.0
"""A step longer than this many median steps is a gap (every reader's rule and the static
log's segments; :mod:`calib.logs.reader` exports it too)."""

ACCEL_UNITS = ("m/s2", "g", "mg", "counts")
"""Acceleration units a log may be in (``--units``)."""
GYRO_UNITS = ("rad/s", "deg/s")
"""Angular-rate units a log may be in (``--gyro-unit``)."""
TIME_UNITS = ("s", "ms", "us", "ns")
"""Units of a log's time column (``--time-unit``)."""

_ACCEL_WORDS = {
    "m/s2": ("m/s^2", "m/s²", "m/s2", "m s^-2", "m s-2", "ms^-2", "ms-2", "m*s^-2", "ms2",
             "mps2", "m_s2", "m/s/s", "m.s^-2", "m.s-2", "m_per_s2", "m_per_s_2",
             "m_per_s^2"),
    "g": ("g", "g0", "gee", "g_0"),
    "mg": ("mg", "milli-g", "millig"),
    "counts": ("counts", "count", "lsb", "raw", "adc", "digits"),
}
_GYRO_WORDS = {"rad/s": ("rad/s", "rad s^-1", "rad*s^-1", "rads", "rad_s", "rps", "rad.s^-1",
                         "rad s-1", "rad/sec", "rad_per_s", "rad_per_sec"),
               "deg/s": ("deg/s", "°/s", "dps", "degps", "deg_s", "deg/sec", "deg s^-1",
                         "deg_per_s", "deg_per_sec")}
_ANGLE_WORDS = {"rad": ("rad", "radian", "radians"), "deg": ("deg", "°", "degree", "degrees")}
_TIME_WORDS = {1.0: ("s", "sec", "secs", "second", "seconds"), 1e-3: ("ms", "msec"),
               1e-6: ("us", "µs", "μs", "usec"), 1e-9: ("ns", "nsec")}

_BRACKET = re.compile(r"^(.*?)\s*[\(\[]\s*([^\)\]]*?)\s*[\)\]]\s*$")
_SUFFIX = re.compile(r"^(.+?)[_ ](m_per_s_?2|mps2|m_s2|ms2|mg|g|counts|lsb|raw|"
                     r"(?:deg|rad)_per_s(?:ec)?|dps|degps|deg_s|rad_s|rads|rps|"
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
class LineIndex:
    """The file line of each sample, stored as runs of consecutive lines: a log with no blank
    or comment line between its rows is one run, so a 24-hour log's line numbers take a few
    bytes instead of 8 per sample. ``index[i]`` is sample ``i``'s line (1-based, the file's
    own); ``numpy.asarray(index)`` expands them all.

    Attributes
    ----------
    starts : (R,) int64, the first sample of each run (increasing, ``starts[0] == 0``).
    lines : (R,) int64, the file line of that sample; run ``k`` covers samples
        ``starts[k] …`` at lines ``lines[k] …``, one line per sample.
    n : the number of samples.

    Examples
    --------
    >>> index = LineIndex.from_lines([2, 3, 4, 7, 8])
    >>> index[3], len(index), index.starts.tolist()
    (7, 5, [0, 3])
    """

    starts: np.ndarray
    lines: np.ndarray
    n: int

    @classmethod
    def from_lines(cls, lines) -> LineIndex:
        """The runs of a list of line numbers (one per sample, increasing)."""
        arr = np.asarray(lines, dtype=np.int64).reshape(-1)
        if arr.size == 0:
            return cls(np.zeros(0, np.int64), np.zeros(0, np.int64), 0)
        new = np.flatnonzero(np.diff(arr) != 1) + 1
        starts = np.concatenate(([0], new)).astype(np.int64)
        return cls(starts, arr[starts], int(arr.size))

    def __len__(self) -> int:
        return self.n

    def __getitem__(self, i: int) -> int:
        i = operator.index(i)
        if i < 0:
            i += self.n
        if not 0 <= i < self.n:
            raise IndexError(f"sample {i} of {self.n}")
        k = int(np.searchsorted(self.starts, i, side="right")) - 1
        return int(self.lines[k]) + i - int(self.starts[k])

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        lengths = np.diff(np.append(self.starts, self.n))
        out = np.repeat(self.lines - self.starts, lengths) + np.arange(self.n)
        return out if dtype is None else out.astype(dtype)


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
        messages; ``row_word`` names it. A CSV's lines are a :class:`LineIndex`.
    mapping : role → the column, field or variable it was read from (provenance).
    columns : role → the column name to quote in messages (acc axes as ``acc.x`` …).
    notes : what the reader saw (delimiter, decimal mark, topic, …) — JSON-able.
    sha256 : the file's sha256 (hex) when the reader hashed it as it read it (CSV), else
        None (the provenance then hashes the file: :func:`calib.logs.reader.file_sha256`).
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
    rows: np.ndarray | LineIndex | None = None
    row_word: str = "sample"
    mapping: dict[str, str] = field(default_factory=dict)
    notes: dict[str, Any] = field(default_factory=dict)
    sha256: str | None = None

    @property
    def n(self) -> int:
        return int(next(iter(self.acc.values())).shape[0]) if self.acc else 0

    def where(self, i: int) -> str:
        """Sample ``i`` in the file's own terms (``line 57``, ``message 12``, ``index 3``)."""
        if self.rows is None:
            return f"{self.row_word} {i}"
        return f"{self.row_word} {int(self.rows[i])}"


__all__ = ["ACCEL_UNITS", "GYRO_UNITS", "TIME_UNITS", "LineIndex", "RawLog", "accel_unit",
           "angle_unit", "gyro_unit", "split_unit", "time_factor"]
