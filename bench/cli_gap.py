"""``tiltbench gap``: the discrepancy workflow (which catalog effect is the model missing?).

::

    tiltbench gap ENSAYO.mat [--noise-var 0.25,0.64 | --datos datos.txt] [--rate HZ]
                  [--g 9.8] [--json] [--report DIR] [--rrd FILE] [--force]

``--json`` prints exactly one JSON object on stdout (see :meth:`bench.gap.GapReport.to_dict`);
progress goes to stderr. Without ``--json`` a readable report is printed.
"""

from __future__ import annotations

import argparse
import sys

from bench.cli import RawDescriptionHelpFormatter
from calib.io import DataError, check_positive, dumps, read_ensayo

EPILOG = """\
effects and their timing needs (docs/effects.md):
  needs timing (t in the file or --rate): lowpass_lag, lever_arm
  per second with timing, per sample without: bias_drift, bias_random_walk
  not identifiable on one table: gravity_mismatch (absorbed by the scale factors)
"""


def _cmd_gap(args: argparse.Namespace) -> int:
    from bench.cli_calibrate import noise_var_from_args
    from bench.gap import run_gap

    ensayo = read_ensayo(args.ensayo)
    nv = noise_var_from_args(args)
    if nv is None:
        raise DataError(f"{args.ensayo}: the gap is measured against the stated noise; give "
                        "--noise-var σx²,σy² or --datos datos.txt")
    if args.rate is not None and ensayo.t is not None:
        print(f"warning: {args.ensayo} has sample times 't'; --rate {args.rate} is ignored",
              file=sys.stderr)
    check_positive(args.g, "--g")
    report = run_gap(ensayo, nv, g=args.g, rate=None if ensayo.t is not None else args.rate,
                     report_dir=args.report, rrd=args.rrd, force=args.force,
                     progress=lambda msg: print(f"[gap] {msg}", file=sys.stderr, flush=True))
    if args.json:
        print(dumps(report.to_dict()), end="")
    else:
        print(args.ensayo)
        print(report.summary())
    return 0


def register(sub) -> None:
    p = sub.add_parser("gap", help="find the effect the model is missing (discrepancy "
                       "workflow)", epilog=EPILOG,
                       formatter_class=RawDescriptionHelpFormatter)
    p.add_argument("ensayo", help="ensayo.mat with tita (N×1, rad), datos (N×2, m/s²), "
                   "optional t (N×1, s)")
    p.add_argument("--noise-var", help="stated noise variances x,y in (m/s²)², e.g. 0.25,0.64")
    p.add_argument("--datos", help="course datos.txt (noise variances are read from it)")
    p.add_argument("--rate", type=float, help="sample rate in Hz of a file without t "
                   "(samples in time order)")
    p.add_argument("--g", type=float, default=9.8, help="gravity, m/s²")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--report", help="write gap.json, gap.md, gap.png, gap.svg and "
                   "model_after.xml into this directory")
    p.add_argument("--rrd", help="write a rerun recording of the residuals before/after")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.set_defaults(handler=_cmd_gap)


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use the tiltbench command")
