"""``tiltbench calibrate``: parse, call the library, print.

θ known (a course ``ensayo.mat`` or a log with θ): :func:`calib.calibration.tilt_plane.calibrate`
(per-axis OLS or joint WLS), with the lack-of-fit test and the pure-error σ² when poses or θ values
repeat (:mod:`calib.calibration.lackoffit`). θ unknown with held poses, or
``--method multiposition``:
:func:`calib.calibration.multiposition.fit_multiposition`, compared with the least squares when θ is
known; a 3-axis log (``ImuLog.acc_normal``) whose poses turn the normal axis, 7 or more, gets
:func:`calib.calibration.multiposition.fit_multiposition3d` instead (bias and scale of all three
axes; ``--noise-var`` then takes three variances). The log is read with the shared log options
(:mod:`bench.cli.logopts`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bench.cli.logopts import add_log_options
from bench.cli.options import (
    OptionError,
    add_command,
    add_force,
    add_gravity,
    add_json,
    add_noise_inputs,
    check_level,
    check_positive,
    gravity_from_args,
    noise_var_from_args,
    parse_variances,
)
from bench.cli.output import (
    check_finite,
    print_files,
    print_json,
    refuse_overwrite,
    warnings_to_stderr,
)
from bench.cli.vocabulary import add_option


def _cmd_calibrate(args: argparse.Namespace) -> int:
    # domain imports here, not at module level: start-up time of `tiltbench --help`
    from bench.cli.logopts import read_log_from_args
    from calib.calibration.lackoffit import groups_from
    from calib.calibration.tilt_plane import calibrate

    check_level(args.level)
    check_positive(args.g, "--g")
    args.g, args.g_source = gravity_from_args(args)
    if args.save and Path(args.save).suffix.lower() not in (".json", ".mat"):
        raise OptionError(f"--save {args.save}: the name must end in .json (the calibration "
                          "file) or .mat (the MATLAB/Octave export)")
    if args.method == "multiposition" and args.rrd:
        raise OptionError("--rrd records the θ-based fit; it is not available with "
                          "--method multiposition (use --plot)")
    refuse_overwrite([args.plot, args.rrd, args.save], args.force)
    import numpy as np

    nv3 = None
    if args.noise_var is not None and len(args.noise_var.split(",")) == 3:
        # σx²,σy²,σn²: the 3-axis fit's; the tilt plane's two serve the planar fits. Each is
        # checked by the same rules as a pair (positive, within the range the fit handles)
        parts = args.noise_var.split(",")
        what = f"--noise-var {args.noise_var}"
        nv3 = np.concatenate([parse_variances(",".join(parts[:2]), what),
                              parse_variances(f"{parts[2]},{parts[2]}", what)[:1]])
        args.noise_var = ",".join(parts[:2])
    log = read_log_from_args(args, args.ensayo, expect="ensayo")
    nv = noise_var_from_args(args)
    args.nv3 = nv3
    if args.method == "multiposition" or (args.method is None and log.theta is None):
        try:
            return _multiposition(args, log, nv)
        except ValueError as exc:  # too few holds found: say how the detector looked
            hint = detector_hint(log, str(exc))
            if hint is None:
                raise
            raise type(exc)(f"{exc}; {hint}") from None
    if nv3 is not None:
        raise OptionError("--noise-var: three variances are for the 3-axis multi-position fit; "
                          "the θ-based least squares fits the tilt plane: give σx²,σy²")
    if log.theta is None:
        raise OptionError(f"--method {args.method} needs the table angle, which {args.ensayo} "
                          "does not give: use --method multiposition (held poses, θ unknown) "
                          "or give the poses' angles (--poses …)")
    ensayo = log.to_ensayo()
    groups = groups_from(ensayo.tita, log.pose)
    cal = warnings_to_stderr(lambda: calibrate(ensayo, nv, args.method or "ols", args.g,
                                               groups=groups))
    _note_correlated(cal.fits["x"].extra.get("tau_int", 1.0), args.ensayo)
    if args.save:
        check_finite(cal.to_dict(), "the estimates")  # a file of finite numbers only
        _save(args, cal, log)
    if args.plot:
        from bench.figures import save_calibration_plot

        save_calibration_plot(args.plot, cal, ensayo, force=args.force, level=args.level)
    if args.rrd:
        from bench.record import record_calibration

        record_calibration(cal, ensayo, args.rrd, force=args.force)
    for line in cal.lack_of_fit_warnings():
        print(f"warning: {line}", file=sys.stderr)
    _gravity_note(args, log)
    if args.json:
        print_json(cal.to_dict())
        return 0
    check_finite(cal.to_dict(), "the estimates")  # the readable output too: no nan/inf
    if nv is None and cal.fits["x"].extra.get("sigma2_dof") is not None:
        print("note: noise variances not given; estimated from the scatter within the "
              f"repeated poses (pure error, dof {cal.fits['x'].extra['sigma2_dof']}; "
              "intervals use Student t)", file=sys.stderr)
    elif nv is None:
        print("note: noise variances not given; estimated from the residuals "
              "(intervals use Student t)", file=sys.stderr)
    print(f"{args.ensayo}")
    print(cal.summary(args.level))
    print_files([args.save, args.plot, args.rrd])
    return 0


def _gravity_note(args: argparse.Namespace, log) -> None:
    """On a measured log calibrated with neither --g nor --latitude: say what g was assumed
    (printed with the result, so that an error stays one line)."""
    if args.g_source == "assumed" and log.course is None:
        print(f"note: g = {args.g:g} m/s² assumed (the course value); the scale factors "
              f"absorb g_true/{args.g:g} − 1 (−2.0e-3 … +3.3e-3 over the Earth): give "
              "--latitude DEG [--height M] or --g", file=sys.stderr)


def _note_correlated(tau, source) -> None:
    """One stderr line when the holds' noise is correlated (``tau``: the integrated
    autocorrelation time, samples, or the :class:`Poses` that carry it) and counted in the
    intervals."""
    tau = float(getattr(tau, "tau_int", tau))
    if tau > 1.0:
        print(f"note: {source}: the noise within the holds is correlated (integrated "
              f"autocorrelation time {tau:.3g} samples: a filtered or decimated "
              "log); each hold counts its samples / that time as independent readings in the "
              "intervals", file=sys.stderr)


def detector_hint(log, message: str) -> str | None:
    """The pose detector's window and minimum hold, and shorter ones to try, when a refusal
    ``message`` is about too few held poses and the poses were detected (not labelled)."""
    poses = log.provenance.get("poses") or {}
    if poses.get("source") != "detected" or "pose" not in message or (
            "held" not in message and "orientation" not in message):
        return None
    from calib.logs.poses import PoseDetection

    rate = None
    if log.t is not None and log.t.size > 1:
        rate = (log.t.size - 1) / float(log.t[-1] - log.t[0])
    return PoseDetection.from_dict(poses["detection"]).few_poses_hint(rate)


def _multiposition(args: argparse.Namespace, log, nv) -> int:
    """θ unknown (or ``--method multiposition``): the gravity-norm fit on the held poses,
    compared with the θ-based least squares when θ is known."""
    import numpy as np

    from calib.calibration.lackoffit import LOF_ALPHA, groups_from
    from calib.calibration.multiposition import (
        compare_methods,
        fit_multiposition,
        fit_multiposition3d,
        multiposition_document,
        pose_statistics,
        quantization_steps,
        three_axis_applies,
    )
    from calib.calibration.sixface import on_faces
    from calib.calibration.tilt_plane import calibrate
    from calib.input_rules import DataError

    chosen = "given" if args.method == "multiposition" else "automatic: θ unknown"
    pose = log.pose
    if pose is None and log.theta is not None:
        pose = groups_from(log.theta)  # held positions of a course-format run
    if pose is None:
        why = "θ never repeats" if log.theta is not None else "θ unknown, no pose labels"
        raise DataError(f"{args.ensayo}: no held poses to calibrate from ({why}); the "
                        "multi-position method needs the sensor held still in at least 4 "
                        "orientations (a log with held poses, or --poses with their angles)")
    three, why_planar = False, None
    if log.acc_normal is not None:
        acc3 = np.column_stack([log.acc, log.acc_normal])
        poses3 = pose_statistics(acc3, pose, args.ensayo)
        _note_correlated(poses3, args.ensayo)
        if on_faces(poses3):
            return _six_face(args, poses3, log)
        why_planar = three_axis_applies(poses3, args.g)
        three = why_planar is None
    if three:
        if nv is not None and args.nv3 is None:
            raise OptionError("the 3-axis fit needs three noise variances, --noise-var "
                              "σx²,σy²,σn² (or none: estimated within the poses)")
        q = quantization_steps(acc3[pose >= 0])
        fit = warnings_to_stderr(lambda: fit_multiposition3d(
            poses3, args.nv3, args.g, quantization=q, source=args.ensayo))
    else:
        if args.nv3 is not None:
            raise OptionError("--noise-var: three variances are for the 3-axis fit, which does "
                              f"not apply here ({why_planar or 'the log has no third axis'}); "
                              "give σx²,σy² for the planar fit")
        poses = pose_statistics(log.acc, pose, args.ensayo)
        if log.acc_normal is None:
            _note_correlated(poses, args.ensayo)
        fit = warnings_to_stderr(lambda: fit_multiposition(poses, nv, args.g, args.ensayo))
    comparison = None
    if log.theta is not None:
        ls = warnings_to_stderr(lambda: calibrate(log.to_ensayo(), nv, "ols", args.g,
                                                  groups=groups_from(log.theta, log.pose)))
        comparison = compare_methods(fit, ls)
    cal = fit.to_calibration()
    doc = multiposition_document(fit, comparison, chosen)
    check_finite({"fit": doc, "calibration": cal.to_dict()}, "the estimates")
    if args.save:
        _save(args, cal, log)
    if args.plot and three:
        from bench.figures.multiposition3d import save_multiposition3d_plot

        save_multiposition3d_plot(args.plot, fit, force=args.force, level=args.level)
    elif args.plot:
        from bench.figures.multiposition import save_multiposition_plot

        save_multiposition_plot(args.plot, fit, force=args.force, level=args.level)
    lof = fit.lack_of_fit
    if lof is not None and lof.misses(LOF_ALPHA):
        print(f"warning: {lof.warning_line()}", file=sys.stderr)
    if why_planar is not None:
        print(f"note: planar fit of the tilt plane ({', '.join(args.axes.split(','))}); not "
              f"the 3-axis fit: {why_planar}", file=sys.stderr)
    _gravity_note(args, log)
    if args.json:
        print_json(doc)
        return 0
    if (args.nv3 if three else nv) is None:
        print(f"note: noise variances not given; estimated from the scatter within the "
              f"{fit.poses.count} poses (pure error, dof {fit.sigma2_dof}; intervals use "
              "Student t)", file=sys.stderr)
    print(args.ensayo)
    if three:
        normal = log.provenance.get("normal_axis") or "the third axis"
        print(f"method: multiposition, 3 axes ({chosen}); normal axis n = {normal}")
    else:
        print(f"method: multiposition ({chosen})")
    print(fit.summary(args.level))
    if comparison is not None:
        print("-- compared with the θ-based least squares (per-axis OLS, same readings)")
        print(comparison.summary())
    print_files([args.save, args.plot])
    return 0


def _six_face(args: argparse.Namespace, poses, log) -> int:
    """Every hold of a 3-axis log on a face of the case: the six-face test (bias, scale and
    misalignment of the three axes, hold-to-hold repeatability in the intervals)."""
    from calib.calibration.sixface import fit_six_face

    if args.noise_var is not None:
        raise OptionError("--noise-var: the six-face fit measures the scatter within and "
                          "between holds itself; drop --noise-var")
    fit = fit_six_face(poses, g=args.g, g_source=args.g_source, level=args.level,
                       source=args.ensayo)
    check_finite(fit.to_dict(), "the estimates")
    if args.save:
        _save(args, fit, log, poses)
    if args.plot:
        from bench.figures.sixface import save_sixface_plot

        save_sixface_plot(args.plot, fit, force=args.force, level=args.level)
    for axis, p in zip("xyz", fit.lack_of_fit_p, strict=True):
        if p < 0.05:
            print(f"warning: axis {axis}: the linear model misses the hold means beyond their "
                  f"repeatability (lack of fit p = {p:.2g}); a term is missing or a face is "
                  "not flat", file=sys.stderr)
    _gravity_note(args, log)
    if args.json:
        print_json({"method": "six-face", "axes": log.provenance.get("axes"),
                    "normal_axis": log.provenance.get("normal_axis"), "fit": fit.to_dict()})
        return 0
    print(args.ensayo)
    normal = log.provenance.get("normal_axis") or "the third axis"
    print(f"method: six-face test, 3 axes (x, y, n = {normal}); every hold on a face")
    print(fit.summary())
    print_files([args.save, args.plot])
    return 0


def _save(args: argparse.Namespace, cal, log, poses=None) -> None:
    """``--save``: the calibration file (docs/calibration-file.md, version 3), or its .mat
    export, with the log's readings (``--axes``, unit) and where g came from; a six-face fit
    (``poses``: its holds) carries its hold means."""
    from bench.version import __version__
    from calib.calibration.calfile import save_calibration
    from calib.calibration.readings import GravitySource, readings_of

    if args.latitude is not None:
        gravity = GravitySource("latitude", args.latitude, args.height)
    else:
        gravity = GravitySource("given" if args.g_source == "--g" else "assumed")
    if poses is not None:  # six-face: σ measured within and between the holds
        save_calibration(args.save, cal, source=args.ensayo, tool_version=__version__,
                         force=args.force, readings=readings_of(log), gravity=gravity,
                         poses=poses)
        return
    source = ("given" if args.noise_var is not None else
              "datos.txt" if args.datos else "estimated")
    save_calibration(args.save, cal, source=args.ensayo, sigma2_source=source,
                     noise_file=args.datos, tool_version=__version__, force=args.force,
                     readings=readings_of(log), gravity=gravity)


def register(sub) -> None:
    p = add_command(sub, "calibrate", _cmd_calibrate,
                    help="estimate bias and scale from a calibration run")
    p.add_argument("ensayo", help="ensayo.mat with tita (N×1, rad) and datos (N×2, m/s²), or "
                   "a measured log (see the log options below)")
    add_noise_inputs(p)
    add_option(p, "--method", choices=["ols", "wls", "multiposition"], default=None,
               help="ols: per axis (course method; the default when θ is known); wls: "
               "joint 4-parameter WLS; multiposition: θ unknown, from held poses and the "
               "gravity norm (the default when θ is unknown; with θ known it is compared "
               "with the least squares) — docs/poses-calibration.md")
    add_gravity(p, local=True)
    add_option(p, "--level", type=float, default=0.95,
               help="confidence level of every interval (table and figure)")
    add_json(p)
    add_option(p, "--rrd", help="write a rerun recording of the fit to this file")
    add_option(p, "--plot", help="write the fit figure (.png or .svg)")
    add_option(p, "--save", metavar="CAL", help="write the calibration file (cal.json, read "
               "by trajectory/validate --calibration) or its MATLAB/Octave export (cal.mat)")
    add_force(p, "an existing --save / --rrd / --plot file")
    add_log_options(p)
