"""``tiltbench gap``: the discrepancy workflow (which catalog effect is the model missing?).

::

    tiltbench gap ENSAYO.mat [--noise-var 0.25,0.64 | --datos datos.txt] [--rate HZ]
                  [--g G] [--json] [--report DIR] [--rrd FILE] [--force] [log options]

ENSAYO may be a measured log with θ (a θ column, ``--poses`` or label angles): the shared log
options of :mod:`bench.cli.logopts` (docs/real-data.md); a course ``.mat`` is read as before.

``--json`` prints exactly one JSON object on stdout (see :meth:`bench.gap.GapReport.to_dict`);
progress goes to stderr. Without ``--json`` a readable report is printed, the verdict first
("explained", "unexplained" with the signatures that remain, or "nothing detected at α").
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bench.cli.logopts import add_log_options, read_log_from_args
from bench.cli.options import (
    OptionError,
    RawDescriptionHelpFormatter,
    add_command,
    add_force,
    add_gravity,
    add_json,
    add_noise_inputs,
    check_positive,
    noise_var_from_args,
)
from bench.cli.output import print_files, print_json
from bench.cli.progress import Progress
from bench.cli.vocabulary import add_option
from bench.gap.files import REPORT_FILES  # the names alone: no domain import at start-up

EPILOG = """\
the report starts with the verdict: explained | UNEXPLAINED (each signature that remains:
axis, description, size, statistic, p) | nothing detected at α; then per axis whether the
gap shrank and, if not, why (docs/gap.md). An effect that changes the fit by less than 1 % of
σ (e.g. the lattice of a log in raw counts) is reported, not named; an addition that makes
the gap worse, or a replay off its tracking limit, is not an explanation. A timed run whose
θ moves is replayed dynamically (stops included); static poses only without timing, when θ
never moves or only jumps between held positions.

effects and their timing needs (docs/effects.md):
  needs timing (t in the file or --rate): lowpass_lag, lever_arm
  per second with timing, per sample without: bias_drift, bias_random_walk
  not identifiable on one table: gravity_mismatch (absorbed by the scale factors)
"""


def _cmd_gap(args: argparse.Namespace) -> int:
    # domain imports here, not at module level: start-up time of `tiltbench --help`
    from bench.gap import run_gap

    check_positive(args.g, "--g")
    if args.rate is not None:
        check_positive(args.rate, "--rate")
    # a course ensayo.mat is read as before; a measured log through the log options
    log = read_log_from_args(args, args.ensayo, expect="ensayo")
    if log.theta is None:  # a six-face log: its holds on faces in the tilt plane, θ per face
        from calib.calibration.plane_faces import tilt_plane_faces

        plane = tilt_plane_faces(log)
        if plane is not None:
            print(f"note: {args.ensayo}: {plane.provenance['held_samples_only']}",
                  file=sys.stderr)
            log = plane
    ensayo = log.to_ensayo()
    nv = noise_var_from_args(args)
    if nv is None:  # held poses repeat θ: their scatter is the noise (pure error)
        from calib.calibration.lackoffit import groups_from, pure_error_variance

        if groups_from(ensayo.tita) is None:
            raise OptionError(f"{args.ensayo}: the gap is measured against the stated noise; "
                              "give --noise-var σx²,σy² or --datos datos.txt (or hold poses: "
                              "the scatter within repeated θ is then the noise)")
        s2, dof = pure_error_variance(ensayo.datos, groups_from(ensayo.tita))
        nv = (float(s2[0]), float(s2[1]))
        print(f"note: no --noise-var/--datos: the noise is the scatter within the held poses, "
              f"σ² = {nv[0]:.4g}, {nv[1]:.4g} (m/s²)² (pure error, dof {dof})", file=sys.stderr)
    if args.rate is not None and ensayo.t is not None:
        print(f"warning: {args.ensayo} has sample times 't'; --rate {args.rate} is ignored",
              file=sys.stderr)
    sensor = None
    if args.sensor is not None:
        from calib.noise.sensor_profile import load_profile, require_fit_ok

        sensor = load_profile(args.sensor)
        require_fit_ok(sensor, args.sensor, args.allow_failed_fit, axes=("x", "y"))
    report = run_gap(ensayo, nv, g=args.g, rate=None if ensayo.t is not None else args.rate,
                     report_dir=args.report, rrd=args.rrd, force=args.force, sensor=sensor,
                     progress=Progress("gap"))
    if args.json:
        print_json(report.to_dict())
        return 0
    print(args.ensayo)
    print(report.summary())
    written = [Path(args.report) / f for f in REPORT_FILES] if args.report else []
    print_files([p for p in written if p.exists()] + [args.rrd])
    return 0


def register(sub) -> None:
    p = add_command(sub, "gap", _cmd_gap, help="find the effect the model is missing "
                    "(discrepancy workflow)", epilog=EPILOG,
                    formatter_class=RawDescriptionHelpFormatter)
    p.add_argument("ensayo", help="ensayo.mat with tita (N×1, rad), datos (N×2, m/s²), "
                   "optional t (N×1, s); or a measured log with θ (log options below)")
    add_noise_inputs(p, stated=True)
    add_option(p, "--rate", type=float, help="sample rate in Hz of a file without t "
               "(samples in time order)")
    add_gravity(p)
    add_json(p)
    add_option(p, "--report", help="write " + ", ".join(REPORT_FILES[:-1]) + " and "
               f"{REPORT_FILES[-1]} into this folder")
    add_option(p, "--rrd", help="write a rerun recording of the residuals before/after")
    add_option(p, "--sensor", help="sensor.json (tiltbench noise): the bias "
               "random walk's intensity q is taken from its rate_random_walk (within its "
               "interval, charged no parameter; no walk where it is null); needs sample times")
    add_option(p, "--allow-failed-fit")  # with --sensor (calib.noise.sensor_profile)
    add_force(p)
    add_log_options(p)
