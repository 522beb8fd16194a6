"""``tiltbench trajectory``: calibrate on the ensayo (or read ``--calibration cal.json``),
correct and integrate the vehicle run, decide the arrival point with its confidence region
(:mod:`calib.vehicle.region`).

``--json`` prints exactly one JSON object on stdout (the tree of
``calib.vehicle.report.trajectory_tree``).
"""

from __future__ import annotations

import argparse

from bench.cli.inputs import add_course_inputs, read_calibration_file, read_course_inputs
from bench.cli.options import add_command, add_force, check_initial_state, check_level
from bench.cli.output import (
    check_finite,
    print_files,
    print_json,
    refuse_overwrite,
    warnings_to_stderr,
)
from bench.cli.vocabulary import add_option


def _cmd_trajectory(args: argparse.Namespace) -> int:
    # domain imports here, not at module level: start-up time of `tiltbench --help`
    from calib.calibration.tilt_plane import calibrate
    from calib.vehicle.region import arrival_region
    from calib.vehicle.report import trajectory_tree
    from calib.vehicle.trajectory import compute_trajectory
    from calib.vehicle.turning_trajectory import refuse_turning

    level = check_level(args.level)
    check_initial_state(args)
    refuse_overwrite([args.plot, args.rrd], args.force)
    cal = read_calibration_file(args)  # None: fit on --ensayo
    ensayo, acel, candidates, p0, v0, nv = read_course_inputs(args)
    refuse_turning(acel, "trajectory")  # no silent answer hundreds of metres off
    if cal is None:
        cal = warnings_to_stderr(lambda: calibrate(ensayo, nv, args.method, args.g))
    traj = compute_trajectory(acel, cal, p0, v0, args.integrator)
    region = arrival_region(traj, cal, candidates, nv, level)
    if args.plot:
        from bench.figures import save_trajectory_plot

        save_trajectory_plot(args.plot, traj, region, force=args.force)
    out = trajectory_tree(traj, region, cal, args.method,
                          "given" if nv is not None else "estimated")
    if args.rrd:
        from bench.record import record_trajectory

        record_trajectory(traj, region, cal, args.rrd, force=args.force, tree=out)
    if args.json:
        print_json(out)
        return 0
    check_finite(out, "the result")  # the readable output too: no nan/inf
    print(traj.summary())
    print(region.summary())
    print_files([args.plot, args.rrd])
    return 0


def register(sub) -> None:
    p = add_command(sub, "trajectory", _cmd_trajectory,
                    help="correct, integrate and decide the arrival point")
    add_course_inputs(p)
    add_option(p, "--plot")
    add_option(p, "--rrd", help="write a rerun recording of the run to this file")
    add_force(p, "an existing --plot / --rrd file")
