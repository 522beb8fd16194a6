"""``tiltbench fuse``: the vehicle's accelerometers fused with a receiver's position fixes.

    tiltbench fuse --acel acel.mat --gps gps.mat --puntos puntos.mat
                   (--calibration cal.json | --ensayo ensayo.mat) [--datos datos.txt]
                   [--gps-sigma M] [--gps-vel-sigma MPS] [--p0-std M] [--v0-std MPS]
                   [--smoother] [--level L] [--json] [--plot F.png] [--rrd F.rrd]
                   [--truth truth.json] [--gate-alpha A] [--consistency-alpha A]
                   [--nis-window K] [--force]

The calibration comes from ``--calibration`` or is fitted on ``--ensayo`` (as
``trajectory``); P0, V0 and the noise variances come from ``--datos`` (else the course
values, the noise estimated). With a ``gyro`` variable in acel.mat (``generate vehicle
--turning``) the extended filter :func:`calib.fusion.turning.fuse_turning` runs instead
(``--gyro-sigma``, ``--psi0``, ``--psi0-sigma``); its ``--plot``/``--rrd`` dead reckoning is
:func:`calib.vehicle.turning_trajectory.turning_dead_reckoning` with its level-L region (the no-fix
extended filter's covariance, :func:`calib.vehicle.turning_trajectory.turning_arrival_region`), with
the heading added; the text output then prints the dead reckoning's decision too. The
work is :func:`calib.vehicle.arrival.fuse_arrival` (this module parses and prints); the
filter is :func:`calib.fusion.linear.fuse` (docs/fusion.md): Q from
the stated noise and the calibration covariance, R from the receiver's σ, P0 from the
calibration covariance and the initial position/velocity σ of ``--p0-std`` / ``--v0-std``
(default 0: the course gives P0 and V0 exactly; datos.txt states no uncertainty), no
tuning. The arrival decision uses the fused final position and its covariance.

A filter that doubts its inputs (issue 23, docs/fusion.md "Doubting the inputs"): the fixes
are first compared with the dead-reckoned path (km, swapped columns, a time or constant
offset, a gyro in °/s: one line, exit 2); a fix whose NIS reaches χ²₂⁻¹(1 − ``--gate-alpha``)
is rejected (counted and shown); the windowed NIS is tested at ``--consistency-alpha``. An
inconsistent run prints its result with ``consistent: false`` and no region, and exits with
**3** (:data:`EXIT_INCONSISTENT`), distinct from an input error (2).
"""

from __future__ import annotations

import argparse

from bench.cli.inputs import add_course_inputs, read_calibration_file, read_course_inputs
from bench.cli.options import (
    OptionError,
    add_command,
    add_force,
    check_initial_state,
    check_level,
    check_positive,
    integer,
)
from bench.cli.output import check_finite, print_files, print_json, refuse_overwrite
from bench.cli.vocabulary import add_option

EXIT_INCONSISTENT = 3
"""Exit status of a fused run whose windowed NIS is out of its band (no region printed)."""

GATE_ALPHA = 0.001  # = calib.fusion.innovation_check.GATE_ALPHA (not imported: start-up time)
CONSISTENCY_ALPHA = 0.01  # = calib.fusion.innovation_check.CONSISTENCY_ALPHA
NIS_WINDOW = 10  # = calib.fusion.innovation_check.NIS_WINDOW
NIS_WINDOW_MAX = 1000  # = calib.fusion.innovation_check.NIS_WINDOW_MAX
CONSISTENCY_ALPHA_MIN = 1e-6  # = calib.fusion.innovation_check.ALPHA_MIN


def _check_nonnegative(value: float, name: str) -> float:
    import math

    if not math.isfinite(value) or value < 0:
        raise OptionError(f"{name} must be a finite number >= 0, got {value:g}")
    return float(value)


def _check_alpha(value: float, name: str, *, lowest: float) -> float:
    """A rate in [lowest, 1) (the gate: 0 allowed, no gate; the consistency: ≥ 1e-6)."""
    import math

    if not (math.isfinite(value) and lowest <= value < 1.0):
        raise OptionError(f"{name} must be in [{lowest:g}, 1), e.g. 0.01, got {value:g}")
    return float(value)


def _check_window(value: int) -> int:
    if not 1 <= value <= NIS_WINDOW_MAX:
        raise OptionError(f"--nis-window must be 1 to {NIS_WINDOW_MAX} fixes, got {value}")
    return int(value)


def _cmd_fuse(args: argparse.Namespace) -> int:
    # domain imports here, not at module level: start-up time of `tiltbench --help`
    from calib.calibration.tilt_plane import calibrate
    from calib.files.course import read_gps
    from calib.vehicle.arrival import dead_reckoning_region, fixes_inside, fuse_arrival

    level = check_level(args.level)
    doubt = dict(gate_alpha=_check_alpha(args.gate_alpha, "--gate-alpha", lowest=0.0),
                 consistency_alpha=_check_alpha(args.consistency_alpha, "--consistency-alpha",
                                                lowest=CONSISTENCY_ALPHA_MIN),
                 nis_window=_check_window(args.nis_window))
    check_initial_state(args)
    sigma_pos = check_positive(args.gps_sigma, "--gps-sigma")
    p0_std = _check_nonnegative(args.p0_std, "--p0-std")
    v0_std = _check_nonnegative(args.v0_std, "--v0-std")
    sigma_vel = (None if args.gps_vel_sigma is None
                 else check_positive(args.gps_vel_sigma, "--gps-vel-sigma"))
    refuse_overwrite([args.plot, args.rrd], args.force)
    fixes = read_gps(args.gps)
    cal = read_calibration_file(args)  # None: fit on --ensayo
    ensayo, acel, candidates, p0, v0, nv = read_course_inputs(args)
    if cal is None:
        cal = calibrate(ensayo, nv, args.method, args.g)
    turning = acel.gyro is not None  # a turning vehicle: the extended filter
    if turning:
        _check_turning_options(args)
    initial = dict(p0=p0, v0=v0, level=level, noise_var=nv, gyro_var=args.gyro_sigma ** 2,
                   psi0=float(args.psi0), psi0_var=float(args.psi0_sigma) ** 2,
                   p0_std=p0_std, v0_std=v0_std)
    if args.plot or args.rrd:  # a malformed truth file: refused before any work
        truth, true_path, true_heading = _truth(args)
    res = fuse_arrival(acel, fixes, cal, candidates, sigma_pos=sigma_pos, sigma_vel=sigma_vel,
                       smoother=args.smoother, **initial, **doubt)
    out = res.to_dict()
    check_finite(out, "the result")
    status = 0 if res.consistent else EXIT_INCONSISTENT
    if args.plot or args.rrd:
        traj, region = dead_reckoning_region(acel, cal, candidates, **initial)
        # the true path (truth.json beside the data) on the figure; a turning run: its heading
        extra = {"true_heading": true_heading} if turning else {}
    fused_pos = fixes.pos[fixes_inside(acel, fixes)]  # the fixes the filter saw
    if args.plot:
        from bench.figures.fusion import save_fusion_plot

        save_fusion_plot(args.plot, traj, region, res.fusion, fused_pos, level,
                         res.decision.letter, force=args.force, true_path=true_path,
                         consistency=res.consistency, **extra)
    if args.rrd:
        from bench.record.fusion import record_fusion

        record_fusion(args.rrd, traj, region, res.fusion, fused_pos, out["decision"], level,
                      force=args.force, truth=truth, true_path=true_path,
                      consistency=res.consistency, **extra)
    if args.json:
        print_json(out)
        return status
    print(res.summary())
    if (args.plot or args.rrd) and turning and res.consistent:
        print(region.summary())
    print_files([args.plot, args.rrd])
    return status


def _check_turning_options(args: argparse.Namespace) -> None:
    """A turning run (acel.mat has ``gyro``): position fixes only, σ_g from ``--gyro-sigma``,
    the initial heading's σ from ``--psi0-sigma``."""
    if args.gps_vel_sigma is not None:
        raise OptionError("--gps-vel-sigma: the turning filter (acel.mat with 'gyro') uses "
                          "position fixes only")
    import math

    check_positive(args.gyro_sigma, "--gyro-sigma")
    if not (math.isfinite(args.psi0_sigma) and args.psi0_sigma >= 0.0):
        raise OptionError(f"--psi0-sigma must be a finite number >= 0 rad, got "
                          f"{args.psi0_sigma}")
    if not math.isfinite(args.psi0):
        raise OptionError(f"--psi0 must be a finite heading in rad, got {args.psi0}")
    if abs(args.psi0) > 2 * math.pi:  # more than a turn: degrees, most likely
        hint = (f" (degrees? {args.psi0:g}° = {math.radians(args.psi0):.6g} rad)"
                if abs(args.psi0) <= 360 else "")
        raise OptionError(f"--psi0 {args.psi0:g}: a heading in rad is within ±2π{hint}")


def _truth(args: argparse.Namespace):
    """``--truth``, else ``truth.json`` beside ``--acel`` (None if absent): the manifest, its
    true path (the samples every second, m) and, turning, its heading (t s, ψ rad); a
    malformed file is one line (:func:`bench.fusion_truth.read_fusion_truth`)."""
    from pathlib import Path

    from bench.fusion_truth import read_fusion_truth

    path = Path(args.truth) if args.truth else Path(args.acel).parent / "truth.json"
    if not path.exists():
        if args.truth:
            raise OptionError(f"--truth {args.truth}: file not found")
        return None, None, None
    return read_fusion_truth(path)


def register(sub) -> None:
    p = add_command(sub, "fuse", _cmd_fuse, help="fuse the vehicle's accelerometers with "
                    "position fixes (Kalman filter, docs/fusion.md)")
    add_course_inputs(p)
    add_option(p, "--gps", required=True)
    add_option(p, "--gps-sigma", type=float, default=3.0)
    add_option(p, "--gps-vel-sigma", type=float,
               help="velocity fix noise std per axis, m/s (velocity fixes used only when given)")
    turning = p.add_argument_group("a turning run (acel.mat with 'gyro')")
    add_option(turning, "--gyro-sigma", type=float, default=0.005,
               help="white gyro noise std, rad/s (the bench's)")
    add_option(turning, "--psi0", type=float, default=0.0)
    add_option(turning, "--psi0-sigma", type=float, default=0.0,
               help="std of the initial heading, rad (0: known)")
    add_option(p, "--p0-std", type=float, default=0.0,
               help="σ of the initial position per axis, m; 0: the course gives P0 "
                    "exactly in datos.txt, which states no uncertainty")
    add_option(p, "--v0-std", type=float, default=0.0, help="σ of the initial velocity per "
               "axis, m/s; 0 as --p0-std")
    add_option(p, "--smoother")
    add_option(p, "--plot", help="write a figure (.png or .svg): dead reckoning, fixes, the "
               "fused path and both arrival regions (turning run: also the truth and a "
               "heading panel)")
    add_option(p, "--rrd", help="write a rerun recording: truth (if known), dead reckoning, "
               "fixes, the fused path with its ellipses, the innovations, the rejected fixes, "
               "the NIS and its windowed test (INCONSISTENT: no fused region), the heading of "
               "a turning run (docs/recordings.md)")
    add_option(p, "--truth", help="truth.json for the recording and a turning run's figure "
               "(default: truth.json beside --acel, if there is one)")
    add_option(p, "--gate-alpha", type=float, default=GATE_ALPHA,
               help="innovation gate: a fix with NIS >= chi2_d(1 - A) is rejected, a right "
                    "fix with probability A (0: no gate)")
    add_option(p, "--consistency-alpha", type=float, default=CONSISTENCY_ALPHA,
               help="false-alarm rate of the windowed NIS test of the whole run; "
                    "inconsistent: no region, exit 3")
    add_option(p, "--nis-window", type=integer, default=NIS_WINDOW,
               help=f"fixes per window of the NIS test (at most {NIS_WINDOW_MAX})")
    add_force(p, "an existing --plot / --rrd file")
