"""Inputs of ``trajectory`` and ``nmin``: the course files and the initial state.

Without ``--datos`` the noise variances are estimated from the calibration residuals and P0,
V0 are the course's (0, 0), (1, 3); a note says so on stderr.

``--calibration cal.json`` (``calibrate --save``, docs/calibration-file.md) replaces
``--ensayo``: the calibration is read, not re-fitted, and its method and g are the file's
(``--method`` / ``--g`` given with it must agree). ``--datos`` then gives P0, V0 and the
vehicle's noise variances only. A six-face (3-axis) file, or one fitted on other log axes
(``--axes``) or another unit than ``--acel`` reads, is refused in one line
(:func:`calib.calibration.calfile.check_applies`).

``--ensayo`` and ``--acel`` may be measured logs (CSV, phyphox, Sensor Logger, ROS bag,
``.mat`` with ``--map``): the shared log options (:mod:`bench.cli.logopts`, docs/real-data.md)
apply to each input that is not a course ``.mat`` (``--poses`` and label angles to the
ensayo only); course files are read exactly as before.
"""

from __future__ import annotations

import argparse
import sys

from bench.cli.logopts import add_log_options, read_log_from_args
from bench.cli.options import (
    GRAVITY,
    Deferred,
    OptionError,
    add_json,
    check_positive,
    parse_pair,
)
from bench.cli.vocabulary import add_option


class _Given(argparse.Action):
    """Store the value and remember that the option was given (``args.given``): with
    ``--calibration``, an explicit ``--method`` / ``--g`` is checked against the file."""

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        setattr(namespace, self.dest, values)
        namespace.given = {*getattr(namespace, "given", ()), self.dest}


def _integrators() -> tuple[str, ...]:
    from calib.vehicle.trajectory import (
        INTEGRATORS,  # imports scipy: read when needed (start-up time)
    )

    return INTEGRATORS


def add_course_inputs(p: argparse.ArgumentParser, calibration: bool = True) -> None:
    """The course inputs; ``calibration``: ``--calibration`` may replace ``--ensayo``."""
    if calibration:
        src = p.add_mutually_exclusive_group(required=True)
        add_option(src, "--ensayo")
        add_option(src, "--calibration", help="calibration file cal.json (calibrate --save) "
                   "instead of re-fitting on --ensayo")
    else:
        add_option(p, "--ensayo", required=True)
    add_option(p, "--acel", required=True)
    add_option(p, "--puntos", required=True)
    add_option(p, "--datos")
    add_option(p, "--p0", help="initial position x,y in m (overrides datos.txt)")
    add_option(p, "--v0", help="initial velocity x,y in m/s (overrides datos.txt)")
    add_option(p, "--level", type=float, default=0.997,
               help="confidence level of the arrival region (χ², 2 dof)")
    add_option(p, "--method", choices=["ols", "wls"], default="ols", action=_Given,
               help="calibration: per-axis OLS (course) or joint WLS")
    # an explicit metavar (the term's): argparse would list the choices (and import scipy)
    add_option(p, "--integrator", choices=Deferred(_integrators), default="trapezoid",
               help="double integration rule: %(choices)s")
    add_option(p, "--g", type=float, default=GRAVITY, action=_Given)
    add_json(p)
    add_log_options(p)


def read_course_inputs(args: argparse.Namespace):
    """Read the files; return ensayo, acel, candidates, p0, v0, noise_var (None = estimate)."""
    import numpy as np

    from calib.files.course import read_datos, read_puntos
    from calib.vehicle.trajectory import COURSE_P0, COURSE_V0

    check_positive(args.g, "--g")
    # course .mat files are read as before; measured logs through the shared log options
    ensayo = (read_log_from_args(args, args.ensayo, expect="ensayo").to_ensayo()
              if args.ensayo else None)
    acel_log = read_log_from_args(args, args.acel, expect="acel")
    calfile = getattr(args, "calibration_file", None)
    if calfile is not None:  # --calibration: fitted on the readings of this log's axes/unit
        from calib.calibration.calfile import check_applies

        check_applies(calfile, acel_log)
    acel = acel_log.to_acel()
    candidates = read_puntos(args.puntos)
    p0, v0, nv = np.array(COURSE_P0), np.array(COURSE_V0), None
    if args.datos:
        d = read_datos(args.datos)
        p0, v0, nv = d.p0, d.v0, d.noise_var
    if args.p0:
        p0 = parse_pair(args.p0, "--p0")
    if args.v0:
        v0 = parse_pair(args.v0, "--v0")
    if not args.datos:
        p0_src, v0_src = ("given" if opt else "course value" for opt in (args.p0, args.v0))
        print("note: no --datos: noise variances estimated from the calibration residuals; "
              f"P0 = {p0.tolist()} m ({p0_src}), V0 = {v0.tolist()} m/s ({v0_src})",
              file=sys.stderr)
    return ensayo, acel, candidates, p0, v0, nv


def read_calibration_file(args: argparse.Namespace):
    """The :class:`calib.Calibration` of ``--calibration`` (None without it); sets
    ``args.method`` and ``args.g`` to the file's, refusing an explicit one that differs, and
    keeps the checked file as ``args.calibration_file``: :func:`read_course_inputs` refuses a
    vehicle log whose axes or unit differ from the calibration's
    (:func:`calib.calibration.calfile.check_applies`, which refuses a six-face file here)."""
    path = getattr(args, "calibration", None)
    if not path:
        return None
    from calib.calibration.calfile import check_applies, load_calibration_file

    calfile = load_calibration_file(path)
    check_applies(calfile)  # a tilt-plane calibration
    args.calibration_file = calfile
    cal = calfile.calibration
    given = getattr(args, "given", set())
    if "method" in given and args.method != cal.method:
        raise OptionError(f"--method {args.method} but {path} holds a {cal.method} "
                          "calibration; drop --method (the file's is used)")
    if "g" in given and args.g != cal.g:
        raise OptionError(f"--g {args.g} but {path} was fitted with g = {cal.g} m/s²; drop "
                          "--g (the file's is used)")
    args.method, args.g = cal.method, cal.g
    return cal
