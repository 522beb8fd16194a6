"""``tiltbench apply LOG --calibration cal.json --out corrected.csv``: parse, call the library,
print.

The log is read with the log options of ``calibrate`` (:mod:`bench.cli.logopts`; not the
pose options: every sample is corrected) and corrected with the calibration file by
:func:`calib.calibration.corrected_log.correct_log`: ``A_r = (A_m − bias)/(1 + scale)`` for a
tilt-plane file, ``a = K⁻¹(m − b)`` for a six-face one. A file whose axes (``--axes``) or unit
differ from the log's is refused in one line (:func:`calib.calibration.calfile.check_applies`).
The corrected log is a CSV written atomically (t, the corrected axes in m/s², comment lines
naming the log and the calibration file with their SHA-256); an existing ``--out`` needs
``--force``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bench.cli.logopts import add_log_options
from bench.cli.options import OptionError, add_command, add_force, add_json
from bench.cli.output import print_files, print_json, refuse_overwrite
from bench.cli.vocabulary import add_option


def _cmd_apply(args: argparse.Namespace) -> int:
    # domain imports here, not at module level: start-up time of `tiltbench --help`
    from bench.cli.logopts import read_log_from_args
    from calib.calibration.calfile import load_calibration_file
    from calib.calibration.corrected_log import correct_log, save_corrected_log

    if Path(args.out).suffix.lower() != ".csv":
        raise OptionError(f"--out {args.out}: the corrected log is a CSV file; give a name "
                          "ending in .csv")
    refuse_overwrite([args.out], args.force)
    calfile = load_calibration_file(args.calibration)
    # every sample as read (no pose detection); the log's physics check (a still sensor
    # reads about 1 g) with the calibration's g
    log = read_log_from_args(args, args.log, g=calfile.calibration.g, detect=False)
    corrected = correct_log(calfile, log)
    save_corrected_log(args.out, corrected, force=args.force)
    if args.json:
        print_json({**corrected.to_dict(), "out": str(args.out)})
        return 0
    c = corrected
    frame = ", ".join(f"{a} = log {s}" for a, s in zip(c.axes, c.log_axes, strict=True))
    method = c.calibration["method"]
    print(f"{args.log}: {c.n} samples corrected with {args.calibration} ({c.kind}"
          f"{'' if method == c.kind else ', ' + method})")
    print(f"  {c.equation}; axes {frame}; m/s²")
    print_files([args.out])
    return 0


def register(sub) -> None:
    p = add_command(sub, "apply", _cmd_apply,
                    help="correct a log with a calibration file; write the corrected CSV")
    p.add_argument("log", help="the log to correct (the log options below; a course "
                   "ensayo.mat or acel.mat)")
    add_option(p, "--calibration", required=True,
               help="calibration file cal.json or cal.mat (calibrate --save): tilt-plane or "
               "six-face")
    add_option(p, "--out", required=True, metavar="CSV",
               help="the corrected log to write (.csv)")
    add_force(p, "an existing --out file")
    add_json(p)
    add_log_options(p, poses=False)
