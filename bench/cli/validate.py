"""``tiltbench validate``: estimates from any tool against the truth of a generated set.

The estimates are ``--estimates est.json`` (any tool, docs/validate.md) or
``--calibration cal.json`` (``calibrate --save``: read and checked by
:func:`calib.calibration.calfile.load_calibration_file`, the reader of every command, and graded
through its ``calibrate --json`` object; with ``--ensayo`` too, that file must be the one the
calibration was fitted on, by SHA-256). A generated set reads the course's axes x, y in m/s²:
a calibration of other log axes or units, or a six-face one, is refused
(:func:`calib.calibration.calfile.check_applies`).
"""

from __future__ import annotations

import argparse
import sys

from bench.cli.options import OptionError, add_command, add_json
from bench.cli.output import print_json
from bench.cli.vocabulary import add_option

DESCRIPTION = """\
Per-parameter z-scores of bias and scale against truth.json and a joint chi-square test at the
level (pass probability = level for an honest estimator); a reported std outside [1/2, 2]× the
std the design implies also fails (the interval widens for N < 30). Exit code 0: pass, 1: fail,
2: bad input. Formats: docs/validate.md.
"""
"""What ``--help`` says before the options (argparse reflows it)."""


def _cmd_validate(args: argparse.Namespace) -> int:
    # domain imports here, not at module level: start-up time of `tiltbench --help`
    from bench.validate import check_answer_key, load_json, validate

    truth = load_json(args.truth, "truth file")
    truth_name = str(args.truth)
    if isinstance(truth, dict) and "students" in truth:  # a class answer key
        from bench.classset import student_truth

        if not args.student:
            raise OptionError(f"{args.truth}: a class answer key; name the student with "
                              "--student (e.g. student_001)")
        check_answer_key(truth, truth_name)
        idx = next((i for i, s in enumerate(truth["students"])
                    if s["student"] == args.student), None)
        truth = student_truth(truth, args.student)
        truth_name = f"{args.truth} (students[{idx}].truth)"
    if args.calibration:
        from calib.calibration.calfile import check_applies, file_sha256, load_calibration_file
        from calib.calibration.readings import COURSE_READINGS

        # the one reader of every command: validate grades the numbers trajectory, nmin and
        # fuse use (the calibrate --json object of the checked calibration, not a copy)
        cf = load_calibration_file(args.calibration)
        # a generated set (and its ensayo.mat) reads the course's axes x, y in m/s²
        check_applies(cf, COURSE_READINGS, log_name=str(args.ensayo or args.truth))
        est, est_name = cf.calibration.to_dict(), str(args.calibration)
        ref = cf.source
        if args.ensayo and ref and file_sha256(args.ensayo) != ref.get("sha256"):
            raise OptionError(f"--ensayo {args.ensayo} is not the file {args.calibration} was "
                              f"fitted on ({ref.get('name')}, SHA-256 {ref.get('sha256')})")
    else:
        est, est_name = load_json(args.estimates, "estimates file"), str(args.estimates)
    theta, src = None, None
    if args.ensayo:
        from calib.files.course import read_ensayo

        theta, src = read_ensayo(args.ensayo).tita, str(args.ensayo)
    result = validate(truth, est, args.level, args.std, theta, src,
                      truth_name=truth_name, est_name=est_name)
    if result.std_passed is None and result.std_source == "reported":
        print(f"note: {est_name}: the reported std was not checked against the design "
              f"({args.truth} has no noise variances or θ design)", file=sys.stderr)
    if args.json:
        print_json(result.to_dict())
    else:
        print(f"{est_name} against {args.truth} at level {args.level:g}")
        print(result.summary())
    return 0 if result.passed else 1


def register(sub) -> None:
    p = add_command(sub, "validate", _cmd_validate, description=DESCRIPTION, help="check "
                    "estimates against the truth (exit 0 pass, 1 fail, 2 bad input)")
    add_option(p, "--truth", required=True,
               help="truth.json of the generated set, or a class answer_key.json")
    add_option(p, "--student", help="student folder name when --truth is a class "
               "answer_key.json (e.g. student_001)")
    est = p.add_mutually_exclusive_group(required=True)
    add_option(est, "--estimates")
    add_option(est, "--calibration",
               help="calibration file cal.json (calibrate --save) instead of --estimates")
    add_option(p, "--level", type=float, default=0.99,
               help="level of the test: an honest estimator passes with this probability")
    add_option(p, "--std", choices=["auto", "reported", "design"], default="auto",
               help="standard deviations: reported in est.json, or recomputed from the "
               "design with the true noise variances (auto: reported if present)")
    add_option(p, "--ensayo", help="ensayo.mat the estimates came from (θ for the design "
               "std; refused when its N or θ does not match the truth or the estimates)")
    add_json(p)
