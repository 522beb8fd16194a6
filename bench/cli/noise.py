"""``tiltbench noise STATIC_LOG``: Allan deviation and noise terms of a static log
(:mod:`calib.noise.allan`), a log–log figure (``--plot``), the sensor profile (``--save
sensor.json``, :func:`calib.noise.sensor_profile.save_profile`: the loader's checks, nothing
written when they fail) with a calibration's bias/scale if given (``--calibration cal.json``).
``--json`` prints one object: the :class:`calib.noise.allan.NoiseCharacterization` with its
``units``, plus the files written.

Refused before any fit, in one line naming the file, the axis and the fix
(:func:`calib.logs.static_log.check_static`): θ varying or several poses, a stuck axis, a
window shift or variance, a gyro rate, scatter beyond the sample-to-sample noise (a log that
is not still).
"""

from __future__ import annotations

import argparse

from bench.cli.logopts import add_log_options, read_log_from_args
from bench.cli.options import (
    OptionError,
    add_command,
    add_force,
    add_json,
    check_level,
    parse_pair,
)
from bench.cli.output import check_finite, print_files, print_json, refuse_overwrite
from bench.cli.vocabulary import add_option

DESCRIPTION = """\
Overlapping Allan deviation per axis with χ² intervals from its equivalent degrees of freedom;
white-noise density, bias instability and rate random walk fitted by GLS with score-type
intervals, each with the τ range it was read from (docs/noise.md).
"""
"""What ``--help`` says before the options (argparse reflows it)."""


def _calibration_entry(path: str) -> dict:
    """The profile's ``calibration`` from a ``cal.json``: bias/scale with covariance and the
    file's name and sha256."""
    from pathlib import Path

    from calib.calibration.calfile import file_sha256, load_calibration

    cal = load_calibration(path)
    return {"param_names": ["bias_x", "scale_x", "bias_y", "scale_y"],
            "params": [float(v) for v in cal.params], "cov": cal.cov.tolist(),
            "method": cal.method, "g": float(cal.g),
            "source": {"name": Path(path).name, "sha256": file_sha256(path)}}


def _static_reading(args: argparse.Namespace):
    """(readings (N, 2) m/s², rate Hz, static-check numbers) of the log, refused when it is
    not one held pose."""
    import numpy as np

    from calib.input_rules import DataError
    from calib.noise.allan import check_static, sample_rate_of

    log = read_log_from_args(args, args.log)
    if args.rate is not None and not (np.isfinite(args.rate) and args.rate > 0):
        raise OptionError(f"--rate must be a positive number of Hz, got {args.rate}")
    if log.theta is not None and np.ptp(log.theta) > 1e-6:
        raise DataError(f"{log.source}: θ varies over the log ({np.min(log.theta):.4g} to "
                        f"{np.max(log.theta):.4g} rad): not one held pose; cut the log to a "
                        "still stretch")
    if log.pose is not None and np.unique(log.pose[log.pose >= 0]).size > 1:
        raise DataError(f"{log.source}: the log holds {np.unique(log.pose[log.pose >= 0]).size}"
                        " held poses; `tiltbench noise` needs one (cut the log)")
    rate = sample_rate_of(log.t, args.rate, log.source)
    checked = check_static(log.acc, rate, log.source, window=args.static_window,
                           shift=args.static_shift, var_ratio=args.static_var_ratio,
                           gyro=log.gyro, axes=_axis_labels(log.provenance.get("axes")))
    return log, rate, checked


def _axis_labels(mapped: list[str] | None) -> tuple[str, str]:
    """The tilt plane's axes as the messages name them: ``x``, ``y``, with the log's own
    axis when ``--axes`` mapped another one (``y (the log's -z)``)."""
    labels = []
    for name, src in zip(("x", "y"), mapped or ("x", "y"), strict=False):
        labels.append(name if src == name else f"{name} (the log's {src})")
    return tuple(labels) if len(labels) == 2 else ("x", "y")


def _cmd_noise(args: argparse.Namespace) -> int:
    from bench import __version__
    from calib.noise.allan import characterize_noise
    from calib.noise.sensor_profile import save_profile

    level = check_level(args.level)
    alpha = args.alpha
    if not 0.0 < alpha < 0.5:
        raise OptionError(f"--alpha must be in (0, 0.5) (a one-sided significance, e.g. 0.05), "
                          f"got {alpha}")
    tau_range = None
    if args.tau_range:
        tau_range = tuple(parse_pair(args.tau_range, "--tau-range"))
        if not 0 < tau_range[0] < tau_range[1]:
            raise OptionError(f"--tau-range {args.tau_range}: expected 0 < min < max (s)")
    for name in ("static_window", "static_shift", "static_var_ratio"):
        if not getattr(args, name) > 0:
            raise OptionError(f"--{name.replace('_', '-')} must be positive")
    refuse_overwrite([args.plot, args.save], args.force)
    cal = _calibration_entry(args.calibration) if args.calibration else None
    log, rate, checked = _static_reading(args)
    result = characterize_noise(log.acc, rate, level=level, alpha=alpha, tau_range=tau_range,
                                source=log.provenance.get("source"), static_check=checked)
    out = result.to_dict()
    check_finite(out, "the result")
    written = {}
    if args.save:  # the saver runs the loader's checks and writes nothing when they fail
        profile = result.to_profile(calibration=cal, tool_version=__version__)
        written["profile"] = str(save_profile(args.save, profile, force=args.force))
    if args.plot:
        from bench.figures.allan import save_allan_plot

        written["plot"] = str(save_allan_plot(args.plot, result, force=args.force,
                                              title=f"Allan deviation of {log.source}"))
    if args.json:
        print_json({**out, "files": written})
        return 0
    print(result.summary())
    c = checked
    excess = ", ".join(f"{a} {e:.3g} (limit {lim:.3g})" for a, e, lim in
                       zip("xy", c["excess_std"], c["excess_limit"], strict=False))
    print(f"static check: {c['window']:g} s windows, largest mean shift {c['max_shift']:.3g} "
          f"m/s² (limit {max([c['shift'], *c.get('shift_noise_floor', [])]):.3g} m/s²: "
          f"{c['shift']:g} or the noise floor), largest variance ratio {c['max_var_ratio']:.3g} "
          f"(limit {c['var_ratio']:g}); scatter beyond the sample-to-sample noise {excess} "
          "m/s²")
    print_files(written.values())
    return 0


def register(sub) -> None:
    p = add_command(sub, "noise", _cmd_noise, description=DESCRIPTION,
                    help="Allan deviation and noise terms of a static log (sensor.json)")
    p.add_argument("log", metavar="STATIC_LOG", help="a log of one held pose")
    add_log_options(p, poses=False)
    add_option(p, "--rate", type=float, help="sample rate, Hz (required when the log has no "
               "sample times; overrides them otherwise)")
    add_option(p, "--level", type=float, default=0.683,
               help="two-sided level of every interval, the figure's error bars included "
                    "(one sigma: the Allan-deviation convention, and the interval sensor.json "
                    "hands to gap --sensor)")
    add_option(p, "--alpha", type=float, default=0.05,
               help="one-sided significance for calling a term resolved")
    add_option(p, "--tau-range", help="fit only the octave τ within MIN,MAX s (e.g. to leave "
               "out a filter's τ)")
    add_option(p, "--static-window", type=float, default=1.0,
               help="window of the static check, s (longer than the pose detector's 0.5 s: "
                    "each window's variance needs a few samples even at 5 Hz)")
    add_option(p, "--static-shift", type=float, default=0.3)
    add_option(p, "--static-var-ratio", type=float, default=9.0)
    add_option(p, "--calibration", help="a cal.json whose bias/scale (with covariance) go "
               "into --save")
    add_option(p, "--plot", help="write the Allan deviation figure (.png or .svg)")
    add_option(p, "--save", metavar="SENSOR_JSON", help="write the sensor profile")
    add_json(p)
    add_force(p, "an existing --plot / --save file")
