"""Readers for the logs people have: one entry point, :func:`read_log`, for every command that
reads readings (``calibrate``, ``gap``, ``trajectory``, ``fuse``, ``noise``, ``import``).

A log becomes an :class:`ImuLog`: the two tilt-plane axes in m/s² (after ``--axes`` picked and
signed them from a 3-axis IMU), optional sample times, optional table angle θ (rad), optional
held-pose labels and optional gyro rate about the tilt axis, plus a provenance record (source
name and sha256, format, column mapping, units, detected segments) that ``tiltbench import``
writes beside the course files.

Conventions: SI units; the tilt plane's ``x`` and ``y`` follow the course signs
``A_rx = -g sin θ``, ``A_ry = -g cos θ`` once ``--axes`` has mapped the log's axes onto them.
Units are stated or recognized from headers, never guessed silently.

This module currently reads the course MATLAB files (``ensayo.mat``: tita/datos[/t];
``acel.mat``: t/Aerr[/gyro]); the other formats (CSV/TSV, phyphox, phone sensor-logger
exports, ROS 1/2 bags, ``.mat`` with ``--map``) are added behind the same interface.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from calib.input_rules import DataError


@dataclass(frozen=True)
class LogOptions:
    """How to read a log (the command line's ``--format --columns --axes --units
    --sensitivity --angle-unit --map --poses``). Every field may be left at its default: the
    reader then recognizes the format and columns from the content, or refuses with a message
    that names the option to give.

    Attributes
    ----------
    fmt : "auto" | "course" | "csv" | "phyphox" | "sensorlogger" | "rosbag" | "mat".
    columns : role → column name, roles ``t``, ``x``, ``y``, ``z``, ``theta``, ``label``,
        ``gyro`` (``--columns t=time,x=ax,y=ay``).
    axes : the log's axis (``x``, ``y`` or ``z``, each with an optional leading ``-``) that
        becomes the tilt plane's x and y (``--axes x,y``; ``--axes -y,z``).
    units : acceleration unit: None (recognized from the header, else refused), ``m/s2``,
        ``g``, ``mg`` or ``counts`` (needs ``sensitivity``).
    sensitivity : counts per g, for raw counts.
    angle_unit : None (the data-based degrees check decides, :mod:`calib.angles`), ``rad``
        or ``deg``.
    mapping : ``.mat`` variable mapping, course name → file name (``--map tita=angle``).
    poses : angle of each held pose in the order they occur, in ``angle_unit`` (rad if
        None), or None: poses found in the log stay with unknown θ.
    label_angles : label value → angle (``angle_unit``), for a label column.
    """

    fmt: str = "auto"
    columns: dict[str, str] = field(default_factory=dict)
    axes: tuple[str, str] = ("x", "y")
    units: str | None = None
    sensitivity: float | None = None
    angle_unit: str | None = None
    mapping: dict[str, str] = field(default_factory=dict)
    poses: tuple[float, ...] | None = None
    label_angles: dict[str, float] | None = None


@dataclass(frozen=True)
class ImuLog:
    """Readings of one log, in the tilt plane.

    Attributes
    ----------
    acc : (N, 2) float, m/s² — ``[A_mx, A_my]`` (course signs after ``--axes``).
    t : (N,) float, s, strictly increasing, or None.
    theta : (N,) float, rad, table angle per sample, or None when unknown.
    pose : (N,) int, held-pose label per sample (0, 1, …; -1 while moving), or None when no
        poses were given or detected.
    gyro : (N,) float, rad/s, rate about the tilt axis, or None.
    source : str — the file name, for messages.
    provenance : dict — source name and sha256, format, mapping, units, segments (JSON-able).
    """

    acc: np.ndarray
    t: np.ndarray | None = None
    theta: np.ndarray | None = None
    pose: np.ndarray | None = None
    gyro: np.ndarray | None = None
    source: str = "<memory>"
    provenance: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("acc", "t", "theta", "gyro"):
            value = getattr(self, name)
            if value is not None:
                arr = np.array(value, dtype=float)
                arr.setflags(write=False)
                object.__setattr__(self, name, arr)
        if self.pose is not None:
            arr = np.array(self.pose, dtype=int)
            arr.setflags(write=False)
            object.__setattr__(self, "pose", arr)

    @property
    def n(self) -> int:
        return int(self.acc.shape[0])

    def to_ensayo(self):
        """The course :class:`calib.io.Ensayo` (θ known); DataError when θ is unknown."""
        from calib.io import validate_ensayo

        if self.theta is None:
            raise DataError(f"{self.source}: the table angle is unknown; give the poses' "
                            "angles (--poses …) or a θ column (--columns theta=…)")
        return validate_ensayo(self.theta, self.acc, self.t, self.source)


def file_sha256(path: str | os.PathLike) -> str:
    """sha256 of a file's bytes (hex), for provenance records."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def read_log(path: str | os.PathLike, options: LogOptions | None = None,
             expect: str | None = None) -> ImuLog:
    """Read a measured log into an :class:`ImuLog` (module docstring).

    ``expect="ensayo"`` (or ``"acel"``): a course ``.mat`` goes through that course reader
    only, with its checks and messages.

    Raises
    ------
    DataError : a format not recognized, a missing column, units neither stated nor
        recognized, non-monotone time, NaN/Inf; the message names the file, the line or
        column and what to do.
    """
    from calib.io import read_acel, read_ensayo

    options = options or LogOptions()
    path = Path(path)
    if expect is not None and options.fmt in ("auto", "course"):
        # a course input goes through its course reader unchanged (same checks, messages)
        prov = {"source": {"name": path.name}, "format": "course"}
        if expect == "acel":
            a = read_acel(path)
            return ImuLog(acc=a.aerr, t=a.t, gyro=a.gyro, source=str(path), provenance=prov)
        e = read_ensayo(path)
        return ImuLog(acc=e.datos, t=e.t, theta=e.tita, source=str(path), provenance=prov)
    if options.fmt not in ("auto", "course") or path.suffix.lower() != ".mat":
        raise DataError(f"{path}: only the course .mat files are read so far")
    prov = {"source": {"name": path.name, "sha256": file_sha256(path)}, "format": "course"}
    try:
        e = read_ensayo(path)
        return ImuLog(acc=e.datos, t=e.t, theta=e.tita, source=str(path), provenance=prov)
    except DataError:
        a = read_acel(path)
        return ImuLog(acc=a.aerr, t=a.t, gyro=a.gyro, source=str(path), provenance=prov)


__all__ = ["ImuLog", "LogOptions", "file_sha256", "read_log"]
