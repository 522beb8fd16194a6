"""``tiltbench calibrate``: parse, call :func:`calib.calibration.calibrate`, print."""

from __future__ import annotations

import argparse
import sys
import warnings

from calib.calibration import calibrate
from calib.io import (
    DataError,
    check_positive,
    dumps,
    parse_variances,
    read_datos,
    read_ensayo,
    refuse_overwrite,
)


def noise_var_from_args(args: argparse.Namespace):
    """σ² from --noise-var or --datos; None means 'estimate from the residuals'."""
    if getattr(args, "noise_var", None) is not None and getattr(args, "datos", None):
        raise DataError("give either --noise-var or --datos, not both")
    if getattr(args, "noise_var", None) is not None:
        return parse_variances(args.noise_var)
    if getattr(args, "datos", None):
        return read_datos(args.datos).noise_var
    return None


def _cmd_calibrate(args: argparse.Namespace) -> int:
    if not 0.0 < args.level < 1.0:
        raise DataError(f"--level must be in (0, 1), e.g. 0.95, got {args.level}")
    check_positive(args.g, "--g")
    refuse_overwrite([args.plot, args.rrd], args.force)
    ensayo = read_ensayo(args.ensayo)
    nv = noise_var_from_args(args)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cal = calibrate(ensayo, nv, args.method, args.g)
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    if args.plot:
        from bench.figures import save_calibration_plot

        save_calibration_plot(args.plot, cal, ensayo, force=args.force, level=args.level)
    if args.rrd:
        from bench.record import record_calibration

        record_calibration(cal, ensayo, args.rrd, force=args.force)
    if args.json:
        print(dumps(cal.to_dict()), end="")
    else:
        if nv is None:
            print("note: noise variances not given; estimated from the residuals "
                  "(intervals use Student t)", file=sys.stderr)
        print(f"{args.ensayo}")
        print(cal.summary(args.level))
    return 0


def register(sub) -> None:
    p = sub.add_parser("calibrate", help="estimate bias and scale from a calibration run")
    p.add_argument("ensayo", help="ensayo.mat with tita (N×1, rad) and datos (N×2, m/s²)")
    p.add_argument("--noise-var", help="noise variances x,y in (m/s²)², e.g. 0.25,0.64")
    p.add_argument("--datos", help="course datos.txt (noise variances are read from it)")
    p.add_argument("--method", choices=["ols", "wls"], default="ols",
                   help="ols: per axis (course method); wls: joint 4-parameter WLS")
    p.add_argument("--g", type=float, default=9.8, help="gravity, m/s²")
    p.add_argument("--level", type=float, default=0.95, help="confidence level of intervals")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--rrd", help="write a rerun recording of the fit to this file")
    p.add_argument("--plot", help="write the fit figure (.png or .svg)")
    p.add_argument("--force", action="store_true",
                   help="overwrite an existing --rrd / --plot file")
    p.set_defaults(handler=_cmd_calibrate)
