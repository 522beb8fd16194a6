"""``tiltbench calibrate``: parse, call :func:`calib.calibration.calibrate`, print."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bench.cli.options import (
    OptionError,
    add_force,
    add_gravity,
    add_json,
    add_noise_inputs,
    check_level,
    check_positive,
    noise_var_from_args,
)
from bench.cli.output import (
    check_finite,
    print_files,
    print_json,
    refuse_overwrite,
    warnings_to_stderr,
)


def _cmd_calibrate(args: argparse.Namespace) -> int:
    # domain imports here, not at module level: start-up time of `tiltbench --help`
    from calib.calibration import calibrate
    from calib.io import read_ensayo

    check_level(args.level)
    check_positive(args.g, "--g")
    if args.save and Path(args.save).suffix.lower() not in (".json", ".mat"):
        raise OptionError(f"--save {args.save}: the name must end in .json (the calibration "
                          "file) or .mat (the MATLAB/Octave export)")
    refuse_overwrite([args.plot, args.rrd, args.save], args.force)
    ensayo = read_ensayo(args.ensayo)
    nv = noise_var_from_args(args)
    cal = warnings_to_stderr(lambda: calibrate(ensayo, nv, args.method, args.g))
    if args.save:
        check_finite(cal.to_dict(), "the estimates")  # a file of finite numbers only
        _save(args, cal)
    if args.plot:
        from bench.figures import save_calibration_plot

        save_calibration_plot(args.plot, cal, ensayo, force=args.force, level=args.level)
    if args.rrd:
        from bench.record import record_calibration

        record_calibration(cal, ensayo, args.rrd, force=args.force)
    if args.json:
        print_json(cal.to_dict())
        return 0
    check_finite(cal.to_dict(), "the estimates")  # the readable output too: no nan/inf
    if nv is None:
        print("note: noise variances not given; estimated from the residuals "
              "(intervals use Student t)", file=sys.stderr)
    print(f"{args.ensayo}")
    print(cal.summary(args.level))
    print_files([args.save, args.plot, args.rrd])
    return 0


def _save(args: argparse.Namespace, cal) -> None:
    """``--save``: the calibration file (docs/calibration-file.md), or its .mat export."""
    from bench.version import __version__
    from calib.calfile import save_calibration

    source = ("given" if args.noise_var is not None else
              "datos.txt" if args.datos else "estimated")
    save_calibration(args.save, cal, source=args.ensayo, sigma2_source=source,
                     noise_file=args.datos, tool_version=__version__, force=args.force)


def register(sub) -> None:
    p = sub.add_parser("calibrate", help="estimate bias and scale from a calibration run")
    p.add_argument("ensayo", help="ensayo.mat with tita (N×1, rad) and datos (N×2, m/s²)")
    add_noise_inputs(p)
    p.add_argument("--method", choices=["ols", "wls"], default="ols",
                   help="ols: per axis (course method); wls: joint 4-parameter WLS")
    add_gravity(p)
    p.add_argument("--level", type=float, default=0.95, help="confidence level of intervals")
    add_json(p)
    p.add_argument("--rrd", help="write a rerun recording of the fit to this file")
    p.add_argument("--plot", help="write the fit figure (.png or .svg)")
    p.add_argument("--save", metavar="CAL", help="write the calibration file (cal.json, read "
                   "by trajectory/validate --calibration) or its MATLAB/Octave export (cal.mat)")
    add_force(p, "an existing --save / --rrd / --plot file")
    p.set_defaults(handler=_cmd_calibrate)
