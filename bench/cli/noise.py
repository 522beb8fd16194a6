"""``tiltbench noise STATIC_LOG``: Allan deviation and noise terms of every axis of a static log
(:mod:`calib.noise.allan`): the accelerometer's tilt-plane x, y (course signs after ``--axes``)
and its third axis z, and the gyro's x, y, z when the log has them (IEEE Std 952 terms; SI units
beside the datasheet units µg/√Hz, µg, °/√h, °/h). A log–log figure, one panel per sensor kind
(``--plot``); the sensor profile (``--save sensor.json``,
:func:`calib.noise.sensor_profile.save_profile`: the loader's checks, nothing written when they
fail) with a calibration's bias/scale if given (``--calibration cal.json``); the twin closure
(``--twin``: the profile simulated by the bench for the log's length and rate, its Allan
deviation tested against the log's, :mod:`calib.noise.closure`). ``--json`` prints one object:
the :class:`calib.noise.allan.NoiseCharacterization` with its ``units``, the closure per axis
(``twin``), plus the files written. A log whose readings went through an export's low-pass
filter (:mod:`calib.noise.shaping`: its rule) is fitted with that filter in the model; the
summary says so per axis, the JSON holds its taps (``export_filter``) and ``--save`` writes
them to ``sensor.json`` for the twin.

``--datasheet SPEC|FILE`` (repeatable; :mod:`calib.noise.datasheet`) compares each datasheet
value — ``N=60ug/rtHz,B=20ug,ARW=0.2deg/rth,BI=5deg/h`` (``x.N=…`` for one axis) or a JSON
file — with the measured term's interval on every axis it applies to: meets, exceeds by …×,
inconclusive, or not measured, one line each in the datasheet's units (``--json``:
``datasheet``, in SI and in the datasheet's units). A spec it cannot read is refused in one
line before the log is read.

Refused before any fit, in one line naming the file, the axis and the fix
(:func:`calib.logs.static_log.check_static`): θ varying or several labelled poses, a stuck
tilt-plane axis, a window shift or variance, a gyro rate, scatter beyond the sample-to-sample
noise (a log that is not still). A stuck z or gyro axis (a phone that exports zeros) is left
out with a note. ``--save`` refuses, in one line, a profile of an axis that no model of the
rule describes (``fit_ok`` false), unless ``--save-failed-fit``, which writes it with
``fit_ok: false`` (``generate --sensor`` and ``gap --sensor`` then refuse it unless
``--allow-failed-fit``).

A log with gaps in time (a step longer than 5 median steps, the reader's rule) is read as it
is, without ``--allow-gaps``: it is split at its gaps and said so on stderr in one line, the
Allan variance pooled over the segments as independent records (:mod:`calib.noise.allan`: Logs
with gaps; a gap is never filled); the JSON holds the ``segments`` and the text summary says
it. The static check lays its windows inside the segments (none straddles a gap) and compares
all of them; ``--twin`` simulates the twin with the log's segment lengths. Refused in one line
when no segment holds the 5 octaves a fit needs (naming the longest), or when the segments are
sampled at different rates.
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
from bench.cli.progress import Progress
from bench.cli.vocabulary import add_option

DESCRIPTION = """\
Overlapping Allan deviation of every axis (accelerometer x, y, z; gyro x, y, z) with χ²
intervals from its equivalent degrees of freedom; white-noise density (angle random walk),
bias instability and rate random walk — and, when the curve needs them by the stated rule,
quantization noise and a Gauss–Markov term — fitted by GLS with score-type intervals, each
with the τ range it was read from, in SI and datasheet units (docs/noise.md). A log with gaps
in time is split at them (never filled) and its Allan variance pooled over the segments.
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


def read_static_log(args: argparse.Namespace):
    """The log, read with the command's log options; no pose detection (the static check is
    the stillness rule here, and a held log is one pose); gaps allowed (this command splits the
    log at them, :func:`calib.logs.static_log.log_segments`)."""
    return read_log_from_args(args, args.log, detect=False, allow_gaps=True)


def _static_reading(args: argparse.Namespace):
    """(log, rate Hz, static-check numbers, columns (N, k), axis names, kinds, notes, the
    log's :class:`calib.logs.static_log.LogSegments`) of the log, refused when it is not one
    held pose; a log with gaps is split at them."""
    import numpy as np

    from calib.input_rules import DataError
    from calib.logs.static_log import log_segments, stuck_axis
    from calib.noise.allan import check_static

    log = read_static_log(args)
    if args.rate is not None and not (np.isfinite(args.rate) and args.rate > 0):
        raise OptionError(f"--rate must be a positive number of Hz, got {args.rate}")
    if log.theta is not None and np.ptp(log.theta) > 1e-6:
        raise DataError(f"{log.source}: θ varies over the log ({np.min(log.theta):.4g} to "
                        f"{np.max(log.theta):.4g} rad): not one held pose; cut the log to a "
                        "still stretch")
    if log.pose is not None and np.unique(log.pose[log.pose >= 0]).size > 1:
        raise DataError(f"{log.source}: the log holds {np.unique(log.pose[log.pose >= 0]).size}"
                        " held poses; `tiltbench noise` needs one (cut the log)")
    split = log_segments(log.t, args.rate, log.source)
    rate = split.rate
    labels = _axis_labels(log.provenance.get("axes"))
    columns, names, kinds, notes = [log.acc[:, 0], log.acc[:, 1]], ["x", "y"], [
        "accelerometer"] * 2, []
    if split.missing_note():
        notes.append(split.missing_note())
    shown = list(labels)
    extra = []
    if log.acc_normal is not None:
        src = log.provenance.get("normal_axis")
        extra.append((log.acc_normal, "z", "accelerometer",
                      "z" if src in (None, "z") else f"z (the log's {src})"))
    if log.gyro_s is not None:
        for k, a in enumerate("xyz"):
            extra.append((log.gyro_s[:, k], f"gyro_{a}", "gyro", f"gyro_{a}"))
    for y, name, kind, label in extra:
        value = stuck_axis(y)
        if value is not None:
            notes.append(f"axis {label} reads {value:.6g} "
                         f"{'rad/s' if kind == 'gyro' else 'm/s²'} in every sample: left out "
                         "(a stuck, dead or absent channel)")
            continue
        columns.append(y)
        names.append(name)
        kinds.append(kind)
        shown.append(label)
    # the stillness rules read the tilt plane, as before the third axis was characterized
    # (a held sensor that moves moves in x or y; z and the gyro are checked for a stuck
    # channel above)
    segmented = split.count > 1
    checked = check_static(log.acc, rate, log.source, window=args.static_window,
                           shift=args.static_shift, var_ratio=args.static_var_ratio,
                           gyro=log.gyro, axes=labels,
                           segments=split.bounds if segmented else None,
                           t=log.t if segmented else None)
    return (log, rate, checked, np.column_stack(columns), tuple(names), tuple(kinds), notes,
            split)


def _axis_labels(mapped: list[str] | None) -> tuple[str, str]:
    """The tilt plane's axes as the messages name them: ``x``, ``y``, with the log's own
    axis when ``--axes`` mapped another one (``y (the log's -z)``)."""
    labels = []
    for name, src in zip(("x", "y"), mapped or ("x", "y"), strict=False):
        labels.append(name if src == name else f"{name} (the log's {src})")
    return tuple(labels) if len(labels) == 2 else ("x", "y")


def _failed_fit_line(result, save: str) -> str:
    """The one-line refusal of ``--save`` for a fit no model describes."""
    bad = [a for a in result.axes if not a.fit_ok]
    worst = bad[0]
    return (f"{save} not written: no model of the rule describes the Allan curve of axis "
            f"{', '.join(a.axis for a in bad)} (axis {worst.axis}: best χ² = "
            f"{worst.chi2:.1f} on {worst.dof} dof, p = {worst.p_fit:.2g}, on τ "
            f"{worst.fit_range[0]:.3g}–{worst.fit_range[1]:.3g} s); read the figure (--plot), "
            "restrict --tau-range, or write it anyway with --save-failed-fit (fit_ok: false; "
            "generate/gap --sensor then refuse it unless --allow-failed-fit)")


LONG_FIT_SAMPLES = 100_000
"""Logs at least this long report their fit's progress on stderr (seconds per axis)."""


def _twin(result, profile, columns, rate: float, seed: int, progress=None) -> dict:
    """The closure test of every axis (:mod:`calib.noise.closure`): the profile's axis
    simulated by the bench (:func:`bench.sensor_twin.simulate_axis`) for the log's length and
    rate around the log's mean, seeded by ``seed`` (one stream per axis). A log with gaps: one
    simulated record per segment, of the segment's length, drawn in order from the axis's
    stream (the segments as the fit took them: independent records)."""
    import numpy as np

    from bench.sensor_twin import simulate_axis, twin_axis
    from calib.noise.closure import closure_test, twin_adev

    out = {}
    seeds = np.random.SeedSequence(int(seed)).spawn(len(result.axes))
    lengths = [b - a for a, b in result.segments] or [columns.shape[0]]
    for k, fit in enumerate(result.axes):
        errors = twin_axis(profile, fit.axis, rate)
        rng = np.random.default_rng(seeds[k])
        pieces = [simulate_axis(errors, n, rate, rng, level=fit.mean) for n in lengths]
        y = pieces[0] if len(pieces) == 1 else pieces
        out[fit.axis] = closure_test(fit, twin_adev(fit, y, rate))
        if progress is not None:
            progress(f"twin axes {k + 1}/{len(result.axes)}")
    return out


def _datasheet(texts: list[str]):
    """The :class:`calib.noise.datasheet.Datasheet` of the ``--datasheet`` values, merged in
    order; a spec or file it cannot read is an :class:`OptionError` naming the option."""
    from calib.noise.datasheet import read_datasheets

    try:
        return read_datasheets(texts)
    except ValueError as exc:  # DataError (the file) included
        raise OptionError(f"--datasheet: {exc}") from None


def _cmd_noise(args: argparse.Namespace) -> int:
    import sys

    from bench import __version__
    from calib.input_rules import DataError
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
    if args.save_failed_fit and not args.save:
        raise OptionError("--save-failed-fit writes the profile of a failed fit: give --save")
    refuse_overwrite([args.plot, args.save], args.force)
    sheet = _datasheet(args.datasheet) if args.datasheet else None
    cal = _calibration_entry(args.calibration) if args.calibration else None
    log, rate, checked, columns, names, kinds, notes, split = _static_reading(args)
    progress = Progress("noise") if columns.shape[0] >= LONG_FIT_SAMPLES else None
    result = characterize_noise(columns, rate, level=level, alpha=alpha, tau_range=tau_range,
                                axes=names, kinds=kinds, source=log.provenance.get("source"),
                                static_check=checked, notes=tuple(notes),
                                segments=split.bounds if split.count > 1 else None, t=log.t,
                                progress=progress)
    line = split.line(log.source)
    if line:  # said once the split log was characterized (a refusal stays one line)
        print(f"note: {line}", file=sys.stderr)
    out = result.to_dict()
    check_finite(out, "the result")
    if args.save and not result.fit_ok and not args.save_failed_fit:
        raise DataError(_failed_fit_line(result, args.save))
    profile = None
    if args.save or args.twin:
        profile = result.to_profile(calibration=cal, tool_version=__version__)
    closure = {}
    if args.twin:
        closure = _twin(result, profile, columns, rate, args.seed, progress)
        out["twin"] = {a: c.to_dict() for a, c in closure.items()}
        out["twin_seed"] = int(args.seed)
        out["units"] = {**out["units"], "twin.*.taus": "s",
                        "twin.*.adev": "the axis's reading unit",
                        "twin.*.twin_adev": "the axis's reading unit", "twin.*.z": "1",
                        "twin.*.statistic": "1", "twin.*.dof": "count", "twin.*.p": "1",
                        "twin.*.alpha": "1", "twin.*.parted": "index into twin.*.taus"}
    check = None
    if sheet is not None:
        from calib.noise.datasheet import check_datasheet, json_units

        check = check_datasheet(result, sheet)
        out["datasheet"] = check.to_dict()
        out["units"] = {**out["units"], **json_units("datasheet.")}
    written = {}
    if args.save:  # the saver runs the loader's checks and writes nothing when they fail
        written["profile"] = str(save_profile(args.save, profile, force=args.force))
    if args.plot:
        from bench.figures.allan import save_allan_plot

        written["plot"] = str(save_allan_plot(args.plot, result, force=args.force,
                                              title=f"Allan deviation of {log.source}"))
    if args.json:
        print_json({**out, "files": written})
        return 0
    print(result.summary())
    for c in closure.values():
        print(c.summary())
    c = checked
    excess = ", ".join(f"{a} {e:.3g} (limit {lim:.3g})" for a, e, lim in
                       zip(names, c["excess_std"], c["excess_limit"], strict=False))
    from calib.logs.static_log import WINDOW_CORR

    longer = (f" ({WINDOW_CORR:g} correlation times of {c['correlation_time']:.3g} s: a "
              "filtered log)" if c["window"] > args.static_window * 1.5 else "")
    print(f"static check: {c['window']:.3g} s windows{longer}, largest mean shift "
          f"{c['max_shift']:.3g} "
          f"m/s² (limit {max([c['shift'], *c.get('shift_noise_floor', [])]):.3g} m/s²: "
          f"{c['shift']:g} or the noise floor), largest variance ratio {c['max_var_ratio']:.3g} "
          f"(limit {c['var_ratio']:g}); scatter beyond the sample-to-sample noise {excess} "
          "m/s²")
    if check is not None:
        print(check.summary())
    if args.save and not result.fit_ok:
        print(f"warning: {args.save} written with fit_ok: false (--save-failed-fit)")
    print_files(written.values())
    return 0


def register(sub) -> None:
    p = add_command(sub, "noise", _cmd_noise, description=DESCRIPTION,
                    help="Allan deviation and noise terms of a static log (sensor.json)")
    p.add_argument("log", metavar="STATIC_LOG", help="a log of one held pose")
    add_log_options(p, poses=False, splits_gaps=True)
    add_option(p, "--rate", type=float, help="sample rate, Hz (required when the log has no "
               "sample times; overrides them otherwise)")
    add_option(p, "--level", type=float, default=0.683,
               help="two-sided level of every interval, the figure's error bars included "
                    "(one sigma: the Allan-deviation convention, and the interval sensor.json "
                    "hands to gap --sensor)")
    add_option(p, "--alpha", type=float, default=0.05,
               help="one-sided significance for calling a term resolved")
    add_option(p, "--tau-range", help="fit only the octave τ within MIN,MAX s (e.g. to leave "
               "out a feature no term has; an export's low-pass filter is in the model)")
    add_option(p, "--static-window", type=float, default=1.0,
               help="window of the static check, s (longer than the pose detector's 0.5 s: "
                    "each window's variance needs a few samples even at 5 Hz)")
    add_option(p, "--static-shift", type=float, default=0.3)
    add_option(p, "--static-var-ratio", type=float, default=9.0)
    add_option(p, "--calibration", help="a cal.json whose bias/scale (with covariance) go "
               "into --save")
    add_option(p, "--plot", help="write the Allan deviation figure (.png or .svg)")
    add_option(p, "--save", metavar="SENSOR_JSON", help="write the sensor profile")
    add_option(p, "--save-failed-fit")
    add_option(p, "--twin")
    add_option(p, "--seed", type=int, default=0, help="seed of the twin's draws (--twin)")
    add_option(p, "--datasheet", action="append",
               help="the sensor's datasheet, each value with its unit as the datasheet prints "
                    "it (converted to SI): comma-separated [SCOPE.]TERM=VALUE UNIT items, TERM "
                    "N (noise density; ARW: a gyro's, VRW: an accelerometer's), B or BI (bias "
                    "instability), K or RRW (rate random walk); SCOPE acc, gyro or an axis (x, "
                    "y, z, gyro_x, …) — without one, the unit tells the kind and the value "
                    "applies to every axis of that kind; e.g. "
                    "'N=60ug/rtHz,B=20ug,ARW=0.2deg/rth,BI=5deg/h,x.N=45ug/rtHz'. Or a JSON "
                    "file {\"accelerometer\": {\"white_noise_density\": {\"value\": 60, "
                    "\"unit\": \"µg/√Hz\"}, …}, \"gyro\": {…}}. Repeatable: a later value "
                    "replaces an earlier one. Each value D is a maximum, checked against the "
                    "term's interval at --level: meets (interval ≤ D), exceeds (interval > D), "
                    "inconclusive (it holds D) or not measured (docs/noise.md)")
    add_json(p)
    add_force(p, "an existing --plot / --save file")
