"""What a calibration applies to: the log's readings it was fitted on (which of the log's axes,
with which signs, in which unit) and where its g came from. Recorded in every calibration file
of version 3 (``docs/calibration-file.md``) and compared with the log a command applies the
calibration to (:func:`calib.calibration.calfile.check_applies`).

Readings
--------
A log becomes readings in m/s² in the frame of the tilt plane (:mod:`calib.logs.reader`):
``--axes a,b`` makes the log's signed axis ``a`` the calibration's x and ``b`` its y, the third
axis is the tilt axis ``n = â × b̂`` (the six-face calibration's z); the log's unit (``m/s2``,
``g``, ``mg``, or ``counts`` with a sensitivity in counts per g) is converted with
:data:`calib.conventions.STANDARD_GRAVITY` per g. A bias and a scale factor fitted on these
readings correct those readings only: the same sensor read through other axes, or in counts
at another sensitivity (the scale factor absorbs the sensitivity's error), is another
measurement. A course file (``ensayo.mat``, ``acel.mat``) reads axes x, y in m/s², and so does
a calibration file of version 2.

Gravity
-------
``source`` is ``"given"`` (``--g``, or a Python caller's g), ``"latitude"`` (the WGS84 normal
gravity of ``--latitude`` in degrees and ``--height`` in m, :func:`calib.conventions.
normal_gravity`) or ``"assumed"`` (the course value :data:`calib.conventions.G` = 9.8 m/s²,
said so when the calibration was made).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from calib.calibration.calfile_fields import (
    fail,
    inconsistent,
    number,
    short,
)
from calib.conventions import STANDARD_GRAVITY, G, normal_gravity
from calib.logs.reader import ImuLog, accel_factor, tilt_axis
from calib.logs.table import ACCEL_UNITS

GRAVITY_SOURCES: tuple[str, ...] = ("given", "latitude", "assumed")
"""Where a calibration's g came from (module docstring)."""
_SPECS = ("x", "y", "z", "-x", "-y", "-z")


def _spec(axis: str) -> str:
    """``"+x"`` → ``"x"``: one spelling per signed axis."""
    return axis[1:] if axis.startswith("+") else axis


@dataclass(frozen=True)
class LogReadings:
    """The readings of a log a calibration corrects (module docstring).

    Attributes
    ----------
    axes : the log's signed axes that are the calibration's x and y (``--axes``), e.g.
        ``("x", "y")`` or ``("-y", "z")``.
    unit : the log's acceleration unit, one of ``m/s2``, ``g``, ``mg``, ``counts``.
    sensitivity : counts per g when ``unit`` is ``counts``, else None.
    """

    axes: tuple[str, str] = ("x", "y")
    unit: str = "m/s2"
    sensitivity: float | None = None

    def __post_init__(self) -> None:
        axes = tuple(_spec(str(a)) for a in self.axes)
        if (len(axes) != 2 or any(a not in _SPECS for a in axes)
                or axes[0].lstrip("-") == axes[1].lstrip("-")):
            raise ValueError(f"axes {self.axes!r}: two different log axes x, y or z, each with "
                             "an optional '-'")
        if self.unit not in ACCEL_UNITS:
            raise ValueError(f"unit {self.unit!r}: one of {', '.join(ACCEL_UNITS)}")
        sens = self.sensitivity if self.unit == "counts" else None
        if self.unit == "counts" and not (isinstance(sens, (int, float))
                                          and math.isfinite(sens) and sens > 0):
            raise ValueError(f"sensitivity {sens!r}: raw counts need a positive number of "
                             "counts per g")
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "sensitivity", None if sens is None else float(sens))

    @property
    def to_m_s2(self) -> float:
        """m/s² per unit of the log (1, g, g/1000, g/sensitivity with g = 9.80665 m/s²): the
        reader's own factor (:func:`calib.logs.reader.accel_factor`)."""
        return accel_factor(self.unit, STANDARD_GRAVITY, self.sensitivity, "readings")

    @property
    def normal_axis(self) -> str:
        """The log's signed axis that is the third axis (``â × b̂``): the six-face z."""
        return tilt_axis(self.axes)

    def log_axes(self, three: bool = False) -> tuple[str, ...]:
        """The log's signed axis of each calibrated axis: ``(a, b)``, with ``three`` also
        ``â × b̂``."""
        return (*self.axes, self.normal_axis) if three else self.axes

    def describe(self) -> str:
        """``"axes -y,z in g"``, ``"axes x,y in counts (1024 counts/g)"``."""
        unit = (f"counts ({self.sensitivity:g} counts/g)" if self.unit == "counts"
                else self.unit)
        return f"axes {','.join(self.axes)} in {unit}"

    def to_dict(self) -> dict[str, Any]:
        """The ``readings`` object of a calibration file."""
        return {"axes": list(self.axes), "unit": self.unit,
                "sensitivity_counts_per_g": self.sensitivity, "to_m_s2": self.to_m_s2}


COURSE_READINGS = LogReadings()
"""The course files' readings: axes x, y in m/s² (and what a version-2 file means)."""
READINGS_UNITS = {"readings.sensitivity_counts_per_g": "counts/g",
                  "readings.to_m_s2": "m/s² per unit of the log"}
"""Units of the numbers of the ``readings`` object (docs/units.md)."""


def readings_of(log: ImuLog) -> LogReadings:
    """The readings of ``log`` as its reader recorded them (``provenance``: ``axes`` and
    ``units``); a course file, or a log built in Python without provenance, reads axes x, y
    in m/s² (:data:`COURSE_READINGS`)."""
    prov = log.provenance or {}
    units = prov.get("units") or {}
    axes = tuple(prov.get("axes") or COURSE_READINGS.axes)
    unit = units.get("acc") or "m/s2"
    return LogReadings(axes, unit, units.get("sensitivity_counts_per_g"))  # type: ignore[arg-type]


def readings_from_document(v: Any, path: Any) -> LogReadings:
    """The ``readings`` object of a file, checked (one line naming the field); its
    ``to_m_s2`` must be the one its unit and sensitivity give."""
    if not isinstance(v, dict) or set(v) != {"axes", "unit", "sensitivity_counts_per_g",
                                             "to_m_s2"}:
        raise fail(path, "readings", "must be {\"axes\", \"unit\", \"sensitivity_counts_per_g\", "
                   f"\"to_m_s2\"}}, got {short(v)}")
    axes = v["axes"]
    if (not isinstance(axes, list) or len(axes) != 2 or not all(isinstance(a, str) and a in _SPECS
                                                                for a in axes)
            or axes[0].lstrip("-") == axes[1].lstrip("-")):
        raise fail(path, "readings.axes", "must be two different log axes such as [\"x\", \"y\"] "
                   f"or [\"-y\", \"z\"], got {short(axes)}")
    if v["unit"] not in ACCEL_UNITS:
        raise fail(path, "readings.unit", f"is {short(v['unit'])}, expected one of "
                   f"{', '.join(ACCEL_UNITS)}")
    sens = v["sensitivity_counts_per_g"]
    if v["unit"] == "counts":
        if number(sens, "readings.sensitivity_counts_per_g", path) <= 0:
            raise fail(path, "readings.sensitivity_counts_per_g", f"is {sens!r}: counts per g "
                       "must be positive")
    elif sens is not None:
        raise inconsistent(path, "readings.sensitivity_counts_per_g", f"is {short(sens)} for "
                           f"readings in {v['unit']} (null unless the unit is counts)")
    readings = LogReadings((axes[0], axes[1]), v["unit"], sens)
    factor = number(v["to_m_s2"], "readings.to_m_s2", path)
    if factor != readings.to_m_s2:
        raise inconsistent(path, "readings.to_m_s2", f"is {factor!r}, not the "
                           f"{readings.to_m_s2!r} m/s² per {v['unit']} its unit gives")
    return readings


@dataclass(frozen=True)
class GravitySource:
    """Where a calibration's g came from (module docstring).

    Attributes
    ----------
    source : ``"given"``, ``"latitude"`` or ``"assumed"``.
    latitude : geodetic latitude, degrees (north +), with ``"latitude"``; else None.
    height : height above the WGS84 ellipsoid, m, with ``"latitude"``; else None.
    """

    source: str = "given"
    latitude: float | None = None
    height: float | None = None

    def __post_init__(self) -> None:
        if self.source not in GRAVITY_SOURCES:
            raise ValueError(f"gravity source {self.source!r}: one of "
                             f"{', '.join(GRAVITY_SOURCES)}")
        if self.source == "latitude":
            lat, h = float(self.latitude), float(0.0 if self.height is None else self.height)
            normal_gravity(lat, h)  # ValueError outside [-90, 90] deg, [-1e4, 1e5] m
            object.__setattr__(self, "latitude", lat)
            object.__setattr__(self, "height", h)
        elif self.latitude is not None or self.height is not None:
            raise ValueError(f"latitude/height are for the source 'latitude', not "
                             f"{self.source!r}")

    def g(self) -> float | None:
        """The g this source fixes, m/s²: the normal gravity, the course's :data:`G`, or None
        (given: any value)."""
        if self.source == "latitude":
            return normal_gravity(self.latitude, self.height)  # type: ignore[arg-type]
        return G if self.source == "assumed" else None

    def describe(self) -> str:
        if self.source == "latitude":
            return (f"WGS84 normal gravity at latitude {self.latitude:g} deg, height "
                    f"{self.height:g} m")
        return {"given": "given", "assumed": "assumed (the course value)"}[self.source]

    def to_dict(self) -> dict[str, Any]:
        """The ``gravity`` object of a calibration file."""
        return {"source": self.source, "latitude": self.latitude, "height": self.height}


GRAVITY_UNITS = {"gravity.latitude": "deg", "gravity.height": "m"}
"""Units of the numbers of the ``gravity`` object (docs/units.md)."""


def gravity_from_document(v: Any, g: float, path: Any) -> GravitySource:
    """The ``gravity`` object of a file, checked against the file's ``g``: the normal gravity
    of its latitude and height (to 10⁻¹² relative: the sine of another libm may differ in
    its last bit), or the course's 9.8 m/s² when assumed."""
    if not isinstance(v, dict) or set(v) != {"source", "latitude", "height"}:
        raise fail(path, "gravity", "must be {\"source\", \"latitude\", \"height\"}, got "
                   f"{short(v)}")
    if v["source"] not in GRAVITY_SOURCES:
        raise fail(path, "gravity.source", f"is {short(v['source'])}, expected one of "
                   f"{', '.join(GRAVITY_SOURCES)}")
    if v["source"] == "latitude":
        lat = number(v["latitude"], "gravity.latitude", path)
        h = number(v["height"], "gravity.height", path)
        try:
            out = GravitySource("latitude", lat, h)
        except ValueError as exc:
            raise fail(path, "gravity", f"is implausible ({exc})") from None
        want = out.g()
        if abs(g - want) > 1e-12 * want:  # type: ignore[operator]
            raise inconsistent(path, "g", f"is {g!r} m/s² but the WGS84 normal gravity of "
                               f"gravity.latitude {lat:g} deg, height {h:g} m is {want!r}")
        return out
    for key in ("latitude", "height"):
        if v[key] is not None:
            raise inconsistent(path, f"gravity.{key}", f"is {short(v[key])} for g "
                               f"{v['source']} (null unless the source is latitude)")
    out = GravitySource(v["source"])
    if out.source == "assumed" and g != G:
        raise inconsistent(path, "g", f"is {g!r} m/s² but gravity.source 'assumed' means the "
                           f"course value {G} m/s²")
    return out


__all__ = ["COURSE_READINGS", "GRAVITY_SOURCES", "GRAVITY_UNITS", "READINGS_UNITS",
           "GravitySource", "LogReadings", "gravity_from_document", "readings_from_document",
           "readings_of"]
