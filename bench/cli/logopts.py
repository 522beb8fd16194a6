"""The log-reading options shared by every command that reads readings (``calibrate``,
``gap``, ``trajectory``, ``fuse``, ``noise``, ``import``): parse them into a
:class:`calib.logs.reader.LogOptions` and read the log with :func:`calib.logs.reader.read_log`.

``--format`` picks the reader (default: recognized from the content); ``--columns`` names the
columns (``t=…,x=…,y=…,z=…,theta=…,label=…,gyro=…``, ``topic=…`` for a bag); ``--axes`` picks
and signs the log's two axes that form the tilt plane (``x,y``; ``-y,z``); ``--units`` states
the acceleration unit (``m/s2``, ``g``, ``mg``, ``counts`` with ``--sensitivity`` counts per
g); ``--gyro-unit`` the gyro's; ``--time-unit`` a CSV time column's (``s``, ``ms``, ``us``,
``ns``: nanosecond stamps need no header edit); ``--angle-unit`` states θ's unit; ``--map``
maps course variable names to a ``.mat`` file's (``tita=angle,datos=acc``); ``--poses`` gives
each held pose's angle in order, ``--label-angles`` each label's; ``--static-window`` and
``--min-hold`` tune the pose detector; ``--theta-source gyro`` integrates the gyro about the
tilt axis for θ(t) of every sample, anchored to the poses' angles; ``--allow-gaps`` /
``--allow-saturation`` accept what is refused by default. The command's ``--g`` (when it has
one) converts g, mg and counts.

Reading a long log shows its progress on stderr (:func:`bench.cli.progress.log_progress`: a
bar on a terminal, lines for a log of 64 MiB or more otherwise), never on stdout.
"""

from __future__ import annotations

import argparse
from typing import Any

from bench.cli.options import OptionError, parse_floats
from bench.cli.vocabulary import add_option

FORMATS = ("auto", "course", "csv", "phyphox", "sensorlogger", "rosbag", "mat")
ACCEL_UNITS = ("m/s2", "g", "mg", "counts")
GYRO_UNITS = ("rad/s", "deg/s")
TIME_UNITS = ("s", "ms", "us", "ns")
THETA_SOURCES = ("poses", "gyro")
OUT_OF_PLANE = "-"
"""The ``--poses`` mark of a held pose outside the tilt plane (its samples are set aside)."""


def parse_pose_angles(text: str) -> tuple[float, ...]:
    """``--poses``: finite angles, or ``-`` (:data:`OUT_OF_PLANE`) for a pose outside the
    tilt plane, which becomes NaN (:class:`calib.logs.reader.LogOptions` ``poses``)."""
    cells = [c.strip() for c in text.split(",")]
    if OUT_OF_PLANE not in cells:
        return tuple(parse_floats(text, "--poses"))
    if all(c == OUT_OF_PLANE for c in cells):
        raise OptionError("--poses: every pose is marked '-' (outside the tilt plane); give "
                          "the angle of at least two")
    angles = [c for c in cells if c != OUT_OF_PLANE]
    values = iter(parse_floats(",".join(angles), "--poses"))
    return tuple(float("nan") if c == OUT_OF_PLANE else next(values) for c in cells)


def add_log_options(p: argparse.ArgumentParser, poses: bool = True,
                    splits_gaps: bool = False) -> None:
    """Add the log options (module docstring) to a command's parser; ``splits_gaps``: the
    command reads a log with gaps on its own (it splits the log at them: ``noise``), and
    ``--allow-gaps`` is kept for scripts but changes nothing."""
    # the command's name, for the progress of reading a long log (reading_progress)
    p.set_defaults(log_command=p.prog.split(" ", 1)[-1])
    g = p.add_argument_group("reading a measured log (docs/real-data.md)")
    add_option(g, "--format", dest="log_format", choices=FORMATS, default="auto")
    add_option(g, "--columns")
    add_option(g, "--axes", default="x,y")
    add_option(g, "--units", choices=ACCEL_UNITS, help="acceleration unit of the log "
               "(if not given: recognized from the header, else refused)")
    add_option(g, "--sensitivity", type=float)
    add_option(g, "--gyro-unit", choices=GYRO_UNITS, help="unit of the gyro columns "
               "(if not given: recognized from the header)")
    add_option(g, "--time-unit", choices=TIME_UNITS, help="unit of a CSV log's time column "
               "(if not given: recognized from the header, else s)")
    add_option(g, "--angle-unit", choices=("rad", "deg"), help="unit of θ, --poses and "
               "label angles (if not given: rad, with the data-based degrees check)")
    add_option(g, "--map")
    add_option(g, "--allow-gaps", help=(
        "accepted, changes nothing: this command splits a log at its gaps in time (> 5 "
        "median steps) and never fills them" if splits_gaps else
        "read a log with gaps in time (> 5 median steps; refused by default, listed in the "
        "provenance)"))
    add_option(g, "--allow-saturation", help="read a log with stretches at a column's extreme "
               "value (refused by default as saturated)")
    if poses:
        add_option(g, "--poses", help="angle of each held pose, in order (e.g. 0,90,180,270 "
                   "--angle-unit deg; - for a pose outside the tilt plane, e.g. a six-face "
                   "log's ±z faces: 0,-,90,-); without it, poses found in the log keep θ "
                   "unknown")
        add_option(g, "--label-angles", help="angle of each value of the label column, e.g. "
                   "1=0,2=90 (in --angle-unit)")
        add_option(g, "--theta-source", choices=THETA_SOURCES, default="poses",
                   help="θ from the poses' angles (poses: the held samples only) or from "
                   "the gyro about the tilt axis integrated over time and anchored to "
                   "them (gyro: every sample, a timed sweep; closure errors printed)")
        add_option(g, "--static-window", type=float, help="the pose detector's window, s "
                   "(samples if the log has no times; if not given 0.5 s / 25)")
        add_option(g, "--min-hold", type=float, help="shortest held pose, s (samples if the "
                   "log has no times; if not given 1 s / 100)")


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


def _positive(value, name: str):
    import math

    if value is not None and not (math.isfinite(value) and value > 0):
        raise OptionError(f"{name} {value}: must be a positive number")
    return value


def _label_angles(text: str | None) -> dict[str, float] | None:
    if not text:
        return None
    out = {}
    for key, value in _pairs(text, "--label-angles").items():
        (out[key],) = parse_floats(value, f"--label-angles {key}")
    return out


def log_options_from_args(args: argparse.Namespace):
    """The parsed options as a :class:`calib.logs.reader.LogOptions`."""
    from calib.logs.reader import LogOptions

    sens = getattr(args, "sensitivity", None)
    if sens is not None and not sens > 0:
        raise OptionError(f"--sensitivity {sens}: counts per g must be positive")
    if getattr(args, "units", None) == "counts" and sens is None:
        raise OptionError("--units counts needs --sensitivity (counts per g)")
    poses = getattr(args, "poses", None)
    return LogOptions(
        fmt=getattr(args, "log_format", "auto"),
        columns=_pairs(getattr(args, "columns", None), "--columns"),
        axes=_axes(getattr(args, "axes", "x,y")),
        units=getattr(args, "units", None), sensitivity=sens,
        angle_unit=getattr(args, "angle_unit", None),
        mapping=_pairs(getattr(args, "map", None), "--map"),
        poses=None if poses is None else parse_pose_angles(poses),
        label_angles=_label_angles(getattr(args, "label_angles", None)),
        g=getattr(args, "g", None),
        gyro_unit=getattr(args, "gyro_unit", None),
        time_unit=getattr(args, "time_unit", None),
        allow_gaps=bool(getattr(args, "allow_gaps", False)),
        allow_saturation=bool(getattr(args, "allow_saturation", False)),
        theta_source=getattr(args, "theta_source", "poses"),
        window=_positive(getattr(args, "static_window", None), "--static-window"),
        min_hold=_positive(getattr(args, "min_hold", None), "--min-hold"))


def reading_progress(args: argparse.Namespace, path: str) -> dict:
    """``read_log``'s keyword ``progress`` for reading the log ``path`` in the command
    ``args`` came from (:func:`bench.cli.progress.log_progress`: stderr only), or no keyword
    when nothing would be shown."""
    from bench.cli.progress import log_progress

    progress = log_progress(getattr(args, "log_command", "tiltbench"), path,
                            quiet=bool(getattr(args, "quiet", False)))
    return {} if progress is None else {"progress": progress}


def read_log_from_args(args: argparse.Namespace, path: str, expect: str | None = None,
                       **option_changes: Any):
    """:func:`calib.logs.reader.read_log` of ``path`` with the command's log options (with
    ``option_changes``, e.g. ``detect=False``, replacing fields of
    :class:`calib.logs.reader.LogOptions`); ``expect`` (``"ensayo"``/``"acel"``) keeps a course
    ``.mat`` input on its course reader.

    How the log was read goes to stderr in one line (:func:`calib.logs.reader.provenance_line`)
    and into the command's ``--json`` output under ``provenance``
    (:func:`bench.cli.output.note_log_read`). When the log's held poses were detected, a note
    on stderr says how many and the thresholds used (stdout stays the command's own: one JSON
    object with ``--json``)."""
    import sys
    from dataclasses import replace

    from bench.cli.output import note_log_read
    from calib.logs.reader import provenance_line, read_log

    options = log_options_from_args(args)
    if option_changes:
        options = replace(options, **option_changes)
    log = read_log(path, options, expect=expect, **reading_progress(args, path))
    note_log_read(expect or "log", log.provenance)
    line = provenance_line(log.provenance)
    if line:  # how the log was read: which column became what, units, factors
        print(f"note: {line}", file=sys.stderr)
    poses = log.provenance.get("poses") or {}
    if poses.get("source") == "detected":
        count = len(poses["detection"]["segments"])
        kept = log.provenance.get("held_samples_only")
        print(f"note: {path}: {count} held pose(s) detected; {poses['thresholds']}"
              f"{'; ' + kept if kept else ''}", file=sys.stderr)
    if "theta_from_gyro" in log.provenance:
        print(f"note: {path}: θ {log.provenance['theta']}", file=sys.stderr)
    return log
