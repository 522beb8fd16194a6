"""The log-reading options shared by every command that reads readings (``calibrate``,
``gap``, ``trajectory``, ``fuse``, ``noise``, ``import``): parse them into a
:class:`calib.logs.LogOptions` and read the log with :func:`calib.logs.read_log`.

``--format`` picks the reader (default: recognized from the content); ``--columns`` names the
columns (``t=…,x=…,y=…,z=…,theta=…,label=…,gyro=…``); ``--axes`` picks and signs the log's
two axes that form the tilt plane (``x,y``; ``-y,z``); ``--units`` states the acceleration unit
(``m/s2``, ``g``, ``mg``, ``counts`` with ``--sensitivity`` counts per g); ``--angle-unit``
states θ's unit; ``--map`` maps course variable names to a ``.mat`` file's (``tita=angle,
datos=acc``); ``--poses`` gives each held pose's angle in order.
"""

from __future__ import annotations

import argparse

from bench.cli.options import OptionError, parse_floats

FORMATS = ("auto", "course", "csv", "phyphox", "sensorlogger", "rosbag", "mat")
ACCEL_UNITS = ("m/s2", "g", "mg", "counts")


def add_log_options(p: argparse.ArgumentParser, poses: bool = True) -> None:
    """Add the log options (module docstring) to a command's parser."""
    g = p.add_argument_group("reading a measured log (docs/real-data.md)")
    g.add_argument("--format", dest="log_format", choices=FORMATS, default="auto",
                   help="log format (default: recognized from the content)")
    g.add_argument("--columns", help="column names by role: t=…,x=…,y=…,z=…,theta=…,label=…,"
                   "gyro=…")
    g.add_argument("--axes", default="x,y", help="the log's axes that are the tilt plane's x,y, "
                   "with signs (e.g. -y,z)")
    g.add_argument("--units", choices=ACCEL_UNITS, help="acceleration unit of the log "
                   "(if not given: recognized from the header, else refused)")
    g.add_argument("--sensitivity", type=float, help="counts per g (with --units counts)")
    g.add_argument("--angle-unit", choices=("rad", "deg"), help="unit of θ, --poses and "
                   "label angles (if not given: rad, with the data-based degrees check)")
    g.add_argument("--map", help=".mat variable names: tita=NAME,datos=NAME,t=NAME")
    if poses:
        g.add_argument("--poses", help="angle of each held pose, in order (e.g. 0,90,180,270 "
                       "--angle-unit deg); without it, poses found in the log keep θ unknown")


def _pairs(text: str | None, what: str) -> dict[str, str]:
    if not text:
        return {}
    out = {}
    for part in text.split(","):
        key, sep, value = part.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise OptionError(f"{what} {text}: expected ROLE=NAME pairs separated by commas")
        out[key.strip()] = value.strip()
    return out


def _axes(text: str) -> tuple[str, str]:
    parts = tuple(p.strip() for p in text.split(","))
    if len(parts) != 2 or any(p.lstrip("+-") not in ("x", "y", "z") for p in parts):
        raise OptionError(f"--axes {text}: expected two of x, y, z with optional signs, "
                          "e.g. x,y or -y,z")
    if parts[0].lstrip("+-") == parts[1].lstrip("+-"):
        raise OptionError(f"--axes {text}: the two axes must differ")
    return parts


def log_options_from_args(args: argparse.Namespace):
    """The parsed options as a :class:`calib.logs.LogOptions`."""
    from calib.logs import LogOptions

    sens = getattr(args, "sensitivity", None)
    if sens is not None and not sens > 0:
        raise OptionError(f"--sensitivity {sens}: counts per g must be positive")
    poses = getattr(args, "poses", None)
    return LogOptions(
        fmt=getattr(args, "log_format", "auto"),
        columns=_pairs(getattr(args, "columns", None), "--columns"),
        axes=_axes(getattr(args, "axes", "x,y")),
        units=getattr(args, "units", None), sensitivity=sens,
        angle_unit=getattr(args, "angle_unit", None),
        mapping=_pairs(getattr(args, "map", None), "--map"),
        poses=None if poses is None else tuple(parse_floats(poses, "--poses")))


def read_log_from_args(args: argparse.Namespace, path: str, expect: str | None = None):
    """:func:`calib.logs.read_log` of ``path`` with the command's log options; ``expect``
    (``"ensayo"``/``"acel"``) keeps a course ``.mat`` input on its course reader."""
    from calib.logs import read_log

    return read_log(path, log_options_from_args(args), expect=expect)
