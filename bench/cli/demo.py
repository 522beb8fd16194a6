"""``tiltbench demo [--out DIR] [--seed S] [--force] [--course-data DIR] [--json]``."""

from __future__ import annotations

import argparse
import sys

from bench.cli.options import (
    Deferred,
    add_command,
    add_force,
    add_json,
    add_sweep_options,
    check_count,
    check_level,
    integer,
    mapper_from_args,
)
from bench.cli.output import print_json
from bench.cli.progress import Progress
from bench.cli.vocabulary import add_option


# The demo's defaults live in bench.demo, which imports scipy: read when needed (start-up time).
def _seed() -> int:
    from bench.demo import DEFAULT_SEED

    return DEFAULT_SEED


def _level() -> float:
    from bench.demo import DEFAULT_LEVEL

    return DEFAULT_LEVEL


def _coverage_runs() -> int:
    from bench.demo import COVERAGE_RUNS

    return COVERAGE_RUNS


def _demo_units() -> dict[str, str]:
    """The ``units`` of the ``demo --json`` object (docs/units.md): the estimates' (a
    calibration), the validation's (bias m/s², scale 1, test statistics 1), the coverage's."""
    from calib.calibration.tilt_plane import Calibration
    from calib.units import nest

    units = nest("estimates", Calibration._JSON_UNITS)
    for name in ("bias_x", "scale_x", "bias_y", "scale_y"):
        u = "m/s²" if name.startswith("bias") else "1"
        units.update({f"validation.parameters.{name}.{k}": u
                      for k in ("estimate", "truth", "std")})
    units.update({"validation.parameters.*.z": "1", "validation.std_check.*": "1",
                  "validation.std_check.ratio.*": "1", "validation.*": "1",
                  "coverage.runs": "count", "coverage.n": "count", "coverage.seed": "—",
                  "coverage.pass_rate_each.*": "1", "coverage.*": "1", "elapsed_s": "s"})
    from bench.demo import FUSION_UNITS

    units.update(FUSION_UNITS)
    return units


def _result_json(res, ok: bool) -> dict:
    """The ``--json`` object: what was written and the numbers of the summary, and
    ``units`` (:func:`_demo_units`)."""
    from calib.units import with_units

    r = res.analysis.region
    return with_units({"out": str(res.out), "source": res.source, "passed": ok,
            "files": {k: str(p) for k, p in sorted(res.files.items())},
            "estimates": res.analysis.cal.to_dict(),
            "decision": r.decision, "answer": (res.truth or {}).get("answer"),
            "validation": None if res.validation is None else res.validation.to_dict(),
            "coverage": res.coverage, "recovered": res.recovered, "fusion": res.fusion,
            "elapsed_s": res.elapsed}, _demo_units())


def _cmd_demo(args: argparse.Namespace) -> int:
    from bench import limits
    from bench.demo import recording_available, run_demo  # start-up time

    check_level(args.level)
    check_count(args.coverage_runs, "--coverage-runs", 0)
    # the coverage check spawns one seed stream per run up front, then redraws the design's
    # readings (the course's 20001 samples) once per run
    limits.check_memory(limits.SEED_STREAM_BYTES * args.coverage_runs
                        + limits.synthetic_runs_bytes(20001, 0),
                        f"--coverage-runs {args.coverage_runs}")
    formats = ("png", "svg") if args.figures == "both" else (args.figures,)
    if not args.no_rrd and not recording_available():  # said before the work, not after it
        # one line within 100 columns: the rest of the reason is in the summary and report
        print('tiltbench demo: note: no demo.rrd (pip install "tiltbench[rrd]"; --no-rrd: '
              'no note)', file=sys.stderr)
    res = run_demo(args.out, args.seed, args.force, args.course_data, args.level,
                   args.coverage_runs, None if args.quiet else Progress("demo"),
                   formats=formats, mapper=mapper_from_args(args), record=not args.no_rrd)
    ok = res.recovered is not False and (res.validation is None or res.validation.passed)
    if args.json:
        print_json(_result_json(res, ok))
    else:
        print(res.summary())
    return 0 if ok else 1


def register(sub) -> None:
    p = add_command(
        sub, "demo", _cmd_demo, help="the whole job end to end: generate, calibrate, decide, "
        "validate, figures, report, recording",
        description="Generates a course set with the MuJoCo bench (or uses --course-data), "
        "calibrates, corrects and integrates the vehicle run, decides the arrival point, "
        "validates against the truth, writes figures, a Markdown report and a rerun "
        "recording, and prints truth beside estimates. Exit code 1 if the validation fails "
        "or the recording does not give the numbers back.")
    add_option(p, "--out", default="demo-out")
    add_option(p, "--seed", type=int, default=Deferred(_seed), help="seed of the course set")
    add_force(p)
    add_option(p, "--course-data", help="use the course files in DIR (ensayo.mat, acel.mat, "
               "puntos.mat, datos.txt) instead of generating a set")
    add_option(p, "--level", type=float, default=Deferred(_level),
               help="confidence level of the arrival region")
    add_option(p, "--coverage-runs", type=integer, default=Deferred(_coverage_runs),
               help="fresh synthetic calibrations in the coverage check (0: skip)")
    add_option(p, "--figures", choices=["png", "svg", "both"], default="both",
               help="figure format(s) written to OUT/figures")
    add_option(p, "--no-rrd", help="do not write the rerun recording demo.rrd (without "
               "rerun-sdk, the rrd extra, it is skipped anyway, with a one-line note)")
    add_sweep_options(p)
    add_json(p)
    add_option(p, "--quiet")
