"""``tiltbench demo [--out DIR] [--seed S] [--force] [--course-data DIR]``."""

from __future__ import annotations

import argparse


def _cmd_demo(args: argparse.Namespace) -> int:
    from bench.demo import run_demo

    formats = ("png", "svg") if args.figures == "both" else (args.figures,)
    res = run_demo(args.out, args.seed, args.force, args.course_data, args.level,
                   args.coverage_runs, args.quiet, formats=formats)
    print(res.summary())
    ok = res.recovered is not False and (res.validation is None or res.validation.passed)
    return 0 if ok else 1


def register(sub) -> None:
    from bench.demo import COVERAGE_RUNS, DEFAULT_LEVEL, DEFAULT_SEED

    p = sub.add_parser(
        "demo", help="the whole job end to end: generate, calibrate, decide, validate, "
        "figures, report, recording",
        description="Generates a course set with the MuJoCo bench (or uses --course-data), "
        "calibrates, corrects and integrates the vehicle run, decides the arrival point, "
        "validates against the truth, writes figures, a Markdown report and a rerun "
        "recording, and prints truth beside estimates. Exit code 1 if the validation fails "
        "or the recording does not give the numbers back.")
    p.add_argument("--out", default="demo-out", help="output directory")
    p.add_argument("--seed", type=int, default=DEFAULT_SEED, help="seed of the course set")
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
    p.add_argument("--course-data", metavar="DIR",
                   help="use the course files in DIR (ensayo.mat, acel.mat, puntos.mat, "
                   "datos.txt) instead of generating a set")
    p.add_argument("--level", type=float, default=DEFAULT_LEVEL,
                   help="confidence level of the arrival region")
    p.add_argument("--coverage-runs", type=int, default=COVERAGE_RUNS,
                   help="fresh synthetic calibrations in the coverage check (0: skip)")
    p.add_argument("--figures", choices=["png", "svg", "both"], default="both",
                   help="figure format(s) written to OUT/figures")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.set_defaults(handler=_cmd_demo)
