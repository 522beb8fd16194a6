"""``tiltbench nmin``: how many calibration samples are needed to decide the arrival point
(:mod:`calib.vehicle.nmin`). ``--json`` prints exactly one JSON object on stdout; progress goes to
stderr.

``--calibration cal.json|cal.mat`` replaces ``--ensayo``: the estimates, σ² and N come from
the file. The course subsampling (``--steps``) re-fits every k-th sample of the calibration
run, which a calibration file does not hold: it is skipped, and a progress line says so.
"""

from __future__ import annotations

import argparse

from bench import limits
from bench.cli.inputs import add_course_inputs, read_calibration_file, read_course_inputs
from bench.cli.options import (
    Deferred,
    OptionError,
    add_command,
    add_sweep_options,
    check_count,
    check_initial_state,
    check_level,
    integer,
    mapper_from_args,
    parse_ints,
)
from bench.cli.output import check_finite, print_json
from bench.cli.progress import Progress
from bench.cli.vocabulary import add_option


def _course_steps() -> str:
    from calib.vehicle.nmin import COURSE_STEPS  # imports scipy: read when needed (start-up time)

    return ",".join(map(str, COURSE_STEPS))


def _cmd_nmin(args: argparse.Namespace) -> int:
    from calib.vehicle.nmin import (  # start-up time of `tiltbench --help`
        CONFIRM_N_MAX,
        analyze_nmin,
    )
    from calib.vehicle.turning_trajectory import refuse_turning

    level = check_level(args.level)
    check_initial_state(args)
    steps = parse_ints(args.steps, "--steps")
    mc_n = parse_ints(args.mc_n, "--mc-n")
    if any(s < 1 for s in steps) or any(n < 3 for n in mc_n):
        raise OptionError("--steps must be >= 1 and --mc-n values >= 3")
    check_count(args.runs, "--runs", 0)
    check_count(args.draws, "--draws", 0)
    check_count(args.confirm_runs, "--confirm-runs", 0)
    if 0 < args.draws < 10**5:
        raise OptionError(f"--draws {args.draws}: the fixed-run N needs at least 100000 draws "
                          "(0 skips it)")
    limits.check_memory(args.draws * 16 * 8, f"--draws {args.draws}")  # ~16 floats a draw
    if args.confirm_runs > 0:
        limits.check_memory(limits.synthetic_runs_bytes(CONFIRM_N_MAX, args.confirm_runs),
                            f"--confirm-runs {args.confirm_runs}")
    if mc_n:  # one synthetic run in memory at a time, all seeds up front (checked even
        # with --runs 0, so an absurd --mc-n is refused whatever the run count)
        limits.check_memory(limits.synthetic_runs_bytes(max(mc_n), args.runs),
                            f"--mc-n {max(mc_n)} --runs {args.runs}")
    cal = read_calibration_file(args)  # None: fit on --ensayo
    ensayo, acel, candidates, p0, v0, nv = read_course_inputs(args)
    refuse_turning(acel, "nmin")  # the turning check: its N would be for the wrong path
    prog = Progress("nmin", quiet=args.quiet)
    if cal is not None and ensayo is None and steps:
        prog(f"no --ensayo: the course subsampling (--steps) re-fits the calibration run's "
             f"samples, which {args.calibration} does not hold; skipped")
    res = analyze_nmin(ensayo, acel, candidates, p0=p0, v0=v0, noise_var=nv, level=level,
                       method=args.method, integrator=args.integrator, g=args.g, steps=steps,
                       mc_n=mc_n, runs=args.runs, seed=args.seed, progress=prog,
                       draws=args.draws, confirm_runs=args.confirm_runs,
                       mapper=mapper_from_args(args) if args.confirm_runs else None,
                       count=lambda done, total: prog.count(done, total, "regeneration chunks"),
                       calibration=cal)
    if args.json:
        print_json(res.to_dict())
    else:
        check_finite(res.to_dict(), "the result")  # the readable output too: no nan/inf
        print(res.summary())
    return 0


def register(sub) -> None:
    q = add_command(sub, "nmin", _cmd_nmin,
                    help="calibration samples needed to decide the arrival point")
    add_course_inputs(q)
    add_option(q, "--steps", default=Deferred(_course_steps),
               help="subsampling steps of the course experiment (every k-th sample)")
    add_option(q, "--draws", type=integer, default=100_000,
               help="draws from the calibration's sampling law for the fixed-run N "
                    "(this vehicle run given; >= 100000, 0: skip)")
    add_option(q, "--confirm-runs", type=integer, default=1000,
               help="regenerated calibrations at the fixed-run N (0: none); the output "
                    "says what the count supports")
    add_option(q, "--mc-n", default="20001,1539,1429",
               help="calibration sizes N for fresh synthetic runs with the vehicle noise "
                    "redrawn (the design N is added)")
    add_option(q, "--runs", type=integer, default=0,
               help="synthetic runs per --mc-n N, vehicle noise redrawn (0: none)")
    add_option(q, "--seed", type=int, default=0, help="seed of the draws and synthetic runs")
    add_option(q, "--quiet")
    add_sweep_options(q)
