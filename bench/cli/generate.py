"""``tiltbench generate calibration|vehicle|course|class``: options → configuration objects of
the library, the run, the files it wrote on stdout (``--json``: one object).

The library (:mod:`bench.tilt`, :mod:`bench.vehicle`, :mod:`bench.course`,
:mod:`bench.classset`) knows no options; the ``*_config`` functions here turn parsed options
into its configuration objects, naming the option in every error. A recording (``--rrd``) is
made here, after the set is written (the library does not import :mod:`bench.record`).
"""

from __future__ import annotations

import argparse
import math

from bench.cli.options import (
    DEFAULT_BIAS,
    DEFAULT_NOISE,
    DEFAULT_SCALE,
    FULL_TURN,
    VARIANCE_RANGE,
    Deferred,
    OptionError,
    add_command,
    add_generate_common,
    add_gravity,
    add_sensor_options,
    add_sweep_options,
    check_count,
    check_number,
    check_positive,
    integer,
    mapper_from_args,
    parse_floats,
    parse_pair,
    parse_variances,
)
from bench.cli.output import check_finite, print_summary, refuse_overwrite
from bench.cli.progress import Progress
from bench.cli.vocabulary import add_option


# ---------------------------------------------------------------- option values → config
# Domain imports inside the functions, not at module level: start-up time of `tiltbench --help`.
def sensor_model(args: argparse.Namespace, rate: float | None = None):
    """:class:`bench.sensors.SensorErrorModel` from ``--bias``, ``--scale``, ``--noise-var``,
    or from ``--sensor sensor.json`` (:func:`bench.sensor_twin.twin_sensor` at ``rate`` Hz,
    default the profile's own rate)."""
    from bench.sensors import SensorErrorModel

    bias, scale = parse_pair(args.bias, "--bias"), parse_pair(args.scale, "--scale")
    profile = sensor_profile(args)
    if profile is not None:
        from bench.sensor_twin import twin_sensor

        return twin_sensor(profile, rate, bias, scale)
    return SensorErrorModel.from_pairs(bias, scale,
                                       parse_variances(args.noise_var, allow_zero=True))


def sensor_profile(args: argparse.Namespace):
    """The :class:`calib.noise.sensor_profile.SensorProfile` of ``--sensor``, or None."""
    path = getattr(args, "sensor", None)
    if not path:
        return None
    from calib.noise.sensor_profile import load_profile, require_fit_ok

    profile = load_profile(path)
    require_fit_ok(profile, path, getattr(args, "allow_failed_fit", False), axes=("x", "y", "z"))
    return profile


def twin_record(args: argparse.Namespace, rate: float):
    """What ``truth.json`` records of ``--sensor`` (None without it)."""
    profile = sensor_profile(args)
    if profile is None:
        return None
    from pathlib import Path

    from bench.sensor_twin import twin_truth

    return twin_truth(profile, rate, Path(args.sensor).name)


def calibration_config(args: argparse.Namespace):
    """:class:`bench.tilt.CalibrationConfig` from the options of ``generate calibration``."""
    from bench.model import TableEdits
    from bench.tilt import CalibrationConfig, SweepProfile, ThetaDesign

    # a measured sensor (--sensor) runs at the sweep's rate, or, held poses having no sample
    # times, at its own rate (consecutive samples)
    profile = sensor_profile(args)
    run_rate = (args.rate if args.mode == "sweep" or profile is None
                else profile.sample_rate)
    check_positive(args.rate, "--rate")
    sensor = sensor_model(args, run_rate)
    # Any finite angle in radians is valid (several turns, negative, past 2π): no range
    # check here — without readings there is nothing to tell degrees by (calib.files.angles).
    start, stop = parse_pair(args.theta_range, "--theta-range")
    if args.theta_list is not None and args.theta_from is not None:
        raise OptionError("give --theta-list or --theta-from, not both")
    if args.theta_from is not None:
        theta = ThetaDesign(kind="list", values=_theta_of(args.theta_from))
    elif args.theta_list is not None:
        values = parse_floats(args.theta_list, "--theta-list")
        theta = ThetaDesign(kind="list", values=values)
    elif args.positions is not None:
        theta = ThetaDesign(kind="positions", start=start, stop=stop,
                            positions=check_count(args.positions, "--positions"),
                            per_position=check_count(args.per_position, "--per-position"))
    else:
        theta = ThetaDesign(kind="range", start=start, stop=stop,
                            count=check_count(args.count, "--count", 3))
    sweep = SweepProfile(kind=args.sweep_profile, start=start, stop=stop,
                         duration=check_positive(args.duration, "--duration"),
                         rate=check_positive(args.rate, "--rate"),
                         cycles=check_positive(args.cycles, "--cycles"))
    check_positive(args.g, "--g")
    if args.mode == "sweep":
        _check_sweep(sweep)
    config = CalibrationConfig(mode=args.mode, theta=theta, sweep=sweep, sensor=sensor,
                               table=TableEdits(g=args.g), twin=twin_record(args, run_rate))
    if args.effect:  # effect catalog (docs/effects.md), bench/effects.py
        from bench.effects import apply_effects, parse_effect_option

        config = apply_effects(config, [parse_effect_option(e) for e in args.effect])
    return config


def _theta_of(path: str) -> tuple[float, ...]:
    """``--theta-from``: the θ schedule (rad, every sample in order) of a course-format
    ``ensayo.mat`` — a measured run imported with ``tiltbench import`` — so that its twin holds
    the same poses for the same number of samples (docs/real-data.md, the twin loop)."""
    from calib.files.course import read_ensayo

    return tuple(float(v) for v in read_ensayo(path).tita)


def _check_sweep(sweep) -> None:
    """A sweep that moves: at least 3 samples, start ≠ stop, and (up-down, sine) at least two
    samples per cycle — else the run would hold θ still (θ ≡ start)."""
    samples = sweep.duration * sweep.rate
    if samples < 2:
        raise OptionError(f"--duration {sweep.duration:g} s at --rate {sweep.rate:g} Hz gives "
                          f"{int(samples) + 1} sample(s); a sweep needs at least 3 "
                          "(duration × rate >= 2)")
    if sweep.start == sweep.stop:
        raise OptionError(f"--theta-range: start and stop are both {sweep.start:g} rad; a "
                          "sweep between them would never move")
    if sweep.kind in ("updown", "sine") and sweep.cycles > samples / 2:
        raise OptionError(f"--cycles {sweep.cycles:g}: at most duration × rate / 2 = "
                          f"{samples / 2:g} (two samples per cycle), or the samples do not "
                          "follow the motion")


def _check_calibration_size(config) -> float:
    """Refuse a run too large for this machine (:mod:`bench.limits`) before simulating it;
    return the estimated peak, bytes."""
    from bench import limits

    if config.mode == "static":
        th = config.theta
        n = {"range": th.count, "list": len(th.values),
             "positions": th.positions * th.per_position}[th.kind]
        what = {"range": f"--count {th.count}", "list": f"--theta-list of {n} values",
                "positions": f"--positions {th.positions} --per-position {th.per_position}"
                }[th.kind]
        return limits.check_memory(limits.static_run_bytes(n), what)
    else:
        from bench.model import tilt_table

        dt = tilt_table(config.table)[0].opt.timestep
        sw = config.sweep
        return limits.check_memory(limits.sweep_run_bytes(sw.duration, dt),
                            f"--duration {sw.duration:g} s (sweep, {dt:g} s physics steps)")


def _check_vehicle_size(cfg, extra: float = 0.0, what: str = "") -> float:
    """Refuse a vehicle run (plus ``extra`` bytes, named by ``what``) too large for this
    machine before its time grid is built; return the estimated peak, bytes."""
    from bench import limits

    return limits.check_memory(limits.vehicle_run_bytes(cfg.duration * cfg.rate) + extra,
                        f"--duration {cfg.duration:g} s at --rate {cfg.rate:g} Hz{what}")


def parse_profile(text: str):
    """``"20:0.5,0;20:0,-0.2;20:-0.5,0"`` → :class:`bench.vehicle.Segment` s (duration s :
    ax, ay m/s²); ``"course"`` → :data:`bench.vehicle.COURSE_PROFILE`."""
    from bench.vehicle import COURSE_PROFILE, Segment

    if text.strip().lower() == "course":
        return COURSE_PROFILE
    segs = []
    for part in filter(None, (p.strip() for p in text.split(";"))):
        try:
            dur, acc = part.split(":")
            seconds = float(dur)
            accel = tuple(parse_pair(acc, "--profile"))
        except OptionError:
            raise
        except ValueError:
            raise OptionError(f"--profile: segment {part!r} must be 'duration:ax,ay' "
                              "(s : m/s²), segments separated by ';'") from None
        if not (math.isfinite(seconds) and seconds >= 0):
            raise OptionError(f"--profile: segment {part!r}: the duration must be a finite "
                              "number of seconds >= 0")
        segs.append(Segment(seconds, accel))
    if not segs:
        raise OptionError("--profile: no segments given")
    return tuple(segs)


def vehicle_config(args: argparse.Namespace, sensor, profile, extra: float = 0.0,
                   extra_what: str = ""):
    """:class:`bench.vehicle.VehicleConfig` from ``--duration``, ``--rate``, ``--p0``, ``--v0``,
    ``--g`` and the given sensor model and profile."""
    from bench.vehicle import VehicleConfig

    check_positive(args.g, "--g")
    check_positive(args.duration, "--duration")
    check_positive(args.rate, "--rate")
    cfg = VehicleConfig(duration=args.duration, rate=args.rate,
                        p0=tuple(parse_pair(args.p0, "--p0")),
                        v0=tuple(parse_pair(args.v0, "--v0")), profile=profile,
                        sensor=sensor, g=args.g, **_turning_options(args))
    _check_vehicle_size(cfg, extra, extra_what)  # before the grid is built
    cfg.command()  # validate the grid now, with a clear message
    return cfg


def _turning_options(args: argparse.Namespace) -> dict:
    """``--turning`` / ``--gyro-sigma`` → VehicleConfig keywords (empty: the default vehicle)."""
    if not getattr(args, "turning", False):
        if getattr(args, "gyro_sigma", None) is not None:
            raise OptionError("--gyro-sigma needs --turning")
        return {}
    kw = {"turning": True}
    if args.gyro_sigma is not None:
        kw["gyro_sigma"] = _check_nonnegative(args.gyro_sigma, "--gyro-sigma")
    return kw


def course_config(args: argparse.Namespace):
    """:class:`bench.course.CourseConfig` from the options of ``generate course``."""
    from bench import limits
    from bench.course import CourseConfig
    from bench.sensors import SensorErrorModel
    from bench.tilt import ThetaDesign
    from bench.vehicle import COURSE_PROFILE

    nv = parse_variances(args.noise_var)
    if (args.bias is None) != (args.scale is None):
        raise OptionError("give both --bias and --scale, or neither (drawn from the seed)")
    sensor = None
    if args.bias is not None:
        sensor = SensorErrorModel.from_pairs(parse_pair(args.bias, "--bias"),
                                             parse_pair(args.scale, "--scale"), nv)
    profile = parse_profile(args.profile) if args.profile else COURSE_PROFILE
    check_count(args.count, "--count", 3)
    check_positive(args.min_separation, "--min-separation")
    vcfg = vehicle_config(args, sensor or SensorErrorModel(), profile,
                          limits.static_run_bytes(args.count), f" and --count {args.count}")
    return CourseConfig(vehicle=vcfg, random_profile=args.profile is None, sensor=sensor,
                        noise_var=tuple(nv), theta=ThetaDesign(count=args.count),
                        min_separation=args.min_separation, g=args.g)


GPS_MAGNITUDE_LIMITS = {"--gps-sigma": 1e7, "--gps-vel-sigma": 1e7, "--gps-latency": 1e9,
                        "--gps-outage": 1e9}
"""Largest magnitudes of the receiver options (m, m/s, s, s): results stay finite."""


def _check_nonnegative(value: float, what: str) -> float:
    """``value`` if finite, >= 0 and within :data:`GPS_MAGNITUDE_LIMITS`, else
    :class:`OptionError` naming ``what`` (0: a noiseless receiver, no latency)."""
    if not (math.isfinite(value) and value >= 0):
        raise OptionError(f"{what} must be a finite number >= 0, got {value}")
    if value > GPS_MAGNITUDE_LIMITS[what]:
        raise OptionError(f"{what}: magnitude at most {GPS_MAGNITUDE_LIMITS[what]:g} (a sane "
                          f"value keeps every result finite), got {value:g}")
    return float(value)


def gps_receiver(args: argparse.Namespace, t=None):
    """:class:`bench.gnss.Receiver` from ``--gps`` / ``--gps-*``, or None when none is given
    (no ``gps.mat``; every other output unchanged). With ``t`` (the IMU sample times) the fix
    grid is checked too, before the run is simulated."""
    given = (args.gps or args.gps_rate is not None or args.gps_sigma is not None
             or args.gps_vel_sigma is not None or args.gps_latency is not None
             or bool(args.gps_outage))
    if not given:
        return None
    from bench.gnss import Receiver, fix_epochs

    kw = {}
    if args.gps_rate is not None:
        kw["rate_hz"] = check_positive(args.gps_rate, "--gps-rate")
    if args.gps_sigma is not None:
        kw["pos_sigma_m"] = _check_nonnegative(args.gps_sigma, "--gps-sigma")
    if args.gps_vel_sigma is not None:
        kw["vel_sigma_mps"] = _check_nonnegative(args.gps_vel_sigma, "--gps-vel-sigma")
    if args.gps_latency is not None:
        kw["latency_s"] = _check_nonnegative(args.gps_latency, "--gps-latency")
    outages = []
    for text in args.gps_outage or ():
        a, b = parse_pair(text, "--gps-outage")
        for v in (a, b):
            _check_nonnegative(float(v), "--gps-outage")
        if a > b:
            raise OptionError(f"--gps-outage: start must be <= end (s), got {text!r}")
        outages.append((float(a), float(b)))
    receiver = Receiver(outages=tuple(outages), **kw)
    if t is not None:
        try:
            fix_epochs(receiver, t)
        except ValueError as exc:
            raise OptionError(f"--gps-rate/--gps-latency/--gps-outage with --rate "
                              f"{args.rate:g}: {exc}") from None
    return receiver


# ---------------------------------------------------------------- handlers
BIG_RUN_BYTES = 512 * 2**20
"""Runs estimated above this (seconds to minutes) say on stderr that they started."""


def _announce(command: str, need: float) -> None:
    """A progress line on stderr for a big run that fits (:mod:`bench.limits`): it starts
    and says how big it is; a small run prints nothing (outputs unchanged)."""
    if need >= BIG_RUN_BYTES:
        from bench.limits import gib

        Progress(command)(f"a large run (about {gib(need)} of memory): simulating")


def _cmd_calibration(args: argparse.Namespace) -> int:
    from bench.tilt import generate_calibration, write_calibration

    if args.faces is not None:
        return _cmd_six_face(args)
    given = [_option(d) for d in SIX_FACE_ONLY if getattr(args, d) is not None]
    if given:
        raise OptionError(f"{given[0]} is an option of the six-face twin: give --faces too "
                          "(docs/six-face-twin.md)")
    refuse_overwrite([args.rrd], args.force)  # before writing the set: nothing half-written
    config = calibration_config(args)
    _announce("generate calibration", _check_calibration_size(config))
    run = generate_calibration(config, args.seed)
    check_finite({"tita": run.tita, "datos": run.datos, "truth": run.truth()},
                 f"{args.out}: the run")
    paths = write_calibration(run, args.out, force=args.force)
    if args.rrd:
        from bench.record import record_calibration_truth

        paths["rrd"] = str(record_calibration_truth(run, args.rrd, force=args.force))
    print_summary(args, f"generate calibration: {run.tita.shape[0]} samples ({run.config.mode}), "
                  f"seed {args.seed}",
                  {"n": int(run.tita.shape[0]), "mode": run.config.mode, "files": paths},
                  {"n": "count"})
    return 0


def _refuse_stale_gps(args: argparse.Namespace, receiver) -> None:
    """Without ``--gps``, a ``gps.mat`` already in ``--out`` belongs to an earlier run: the new
    set would sit beside fixes of another path. Refused (OptionError, before anything is
    written) instead of deleted behind the user's back."""
    from pathlib import Path

    stale = Path(args.out) / "gps.mat"
    if receiver is None and stale.exists():
        raise OptionError(f"--out {args.out}: gps.mat there holds the fixes of an earlier run "
                          "and would no longer match the new files; pass --gps to write new "
                          "fixes, or remove gps.mat")


def _cmd_vehicle(args: argparse.Namespace) -> int:
    from bench.vehicle import make_vehicle_run, write_vehicle

    refuse_overwrite([args.rrd], args.force)  # before writing the set: nothing half-written
    cfg = vehicle_config(args, sensor_model(args, check_positive(args.rate, "--rate")),
                         parse_profile(args.profile))
    receiver = gps_receiver(args, cfg.t)
    _refuse_stale_gps(args, receiver)
    _announce("generate vehicle", _check_vehicle_size(cfg))
    run = make_vehicle_run(cfg, args.seed)
    gps = _fixes(receiver, run.truth, args.seed)
    check_finite({"t": run.t, "Aerr": run.aerr, "truth": run.truth_dict(),
                  **({} if run.gyro is None else {"gyro": run.gyro}),
                  **({} if gps is None else {"gps.mat": gps.mat_variables()})},
                 f"{args.out}: the run")
    paths = write_vehicle(run, args.out, force=args.force, gps=gps)
    if args.rrd:
        from bench.record import record_vehicle_truth

        paths["rrd"] = str(record_vehicle_truth(run, args.rrd, force=args.force))
    summary = {"n": int(run.t.shape[0]), "files": paths,
               "final_position": run.truth.final_position.tolist()}
    if gps is not None:
        summary["n_gps"] = gps.n
    print_summary(args, f"generate vehicle: {run.t.shape[0]} samples, seed {args.seed}"
                  + _gps_title(gps), summary,
                  {"n": "count", "final_position": "m", "n_gps": "count"} if gps is not None
                  else {"n": "count", "final_position": "m"})
    return 0


def _cmd_course(args: argparse.Namespace) -> int:
    from bench import limits
    from bench.course import make_course_set, write_course

    refuse_overwrite([args.rrd], args.force)  # before writing the set: nothing half-written
    config = course_config(args)
    receiver = gps_receiver(args, config.vehicle.t)
    _refuse_stale_gps(args, receiver)
    _announce("generate course", limits.vehicle_run_bytes(config.vehicle.n_samples)
              + limits.static_run_bytes(args.count))
    try:
        course = make_course_set(config, args.seed)
    except RuntimeError as exc:  # bench.course.place_candidates: no room for the decoys
        raise OptionError(f"--min-separation {args.min_separation:g}: {exc}") from None
    if receiver is not None:
        from dataclasses import replace

        course = replace(course, gps=_fixes(receiver, course.vehicle.truth, args.seed))
    check_finite({"ensayo.mat": course.calibration.datos, "acel.mat": course.vehicle.aerr,
                  "truth.json": course.truth(),
                  **({} if course.gps is None else {"gps.mat": course.gps.mat_variables()})},
                 f"{args.out}: the course set")
    paths = write_course(course, args.out, force=args.force)
    if args.rrd:
        from bench.record import record_course_truth

        paths["rrd"] = str(record_course_truth(course, args.rrd, force=args.force))
    summary = {"files": paths, "n_calibration": int(course.calibration.tita.shape[0]),
               "n_vehicle": int(course.vehicle.t.shape[0])}
    units = {"n_calibration": "count", "n_vehicle": "count"}
    if course.gps is not None:
        summary["n_gps"] = course.gps.n
        units["n_gps"] = "count"
    print_summary(args, f"generate course: a course set, seed {args.seed} (the answer is in "
                  "truth.json only)" + _gps_title(course.gps), summary, units)
    return 0


def _cmd_class(args: argparse.Namespace) -> int:
    from bench import limits
    from bench.classset import generate_class
    from bench.course import CourseConfig

    nv = parse_variances(args.noise_var)
    check_count(args.students, "--students")
    what = f"--students {args.students}"
    limits.check_memory(limits.CLASS_STUDENT_BYTES * args.students
                        + limits.vehicle_run_bytes(6000) + limits.static_run_bytes(20001), what)
    limits.check_disk(limits.COURSE_SET_DISK_BYTES * args.students, args.out, what)
    if args.seed < 0:
        raise OptionError(f"--seed must be >= 0, got {args.seed}")
    if not args.prefix or "/" in args.prefix or "\\" in args.prefix:
        raise OptionError(f"--prefix must be a plain name, got {args.prefix!r}")
    progress = Progress("generate class", quiet=args.quiet)
    res = generate_class(args.out, args.students, args.seed, args.force,
                         CourseConfig(noise_var=(float(nv[0]), float(nv[1]))), args.prefix,
                         lambda done, total: progress.count(done, total, "course sets"),
                         mapper=mapper_from_args(args))
    files = {f"{name}/{p.name}": str(p) for name, folder in res.folders.items()
             for p in sorted(folder.iterdir())}
    summary = {"count": len(res.folders),
               "folders": {k: str(v) for k, v in res.folders.items()},
               "answer_key": {"csv": str(res.key_csv), "json": str(res.key_json)},
               "note": "keep answer_key.* private; hand out the student folders"}
    title = f"generate class: {len(res.folders)} course sets, seed {args.seed}"
    if args.json:  # the JSON object is unchanged; the readable output lists every file
        print_summary(args, title, summary, {"count": "count"})
    else:
        print_summary(args, title, {**summary, "files": files}, {"count": "count"})
    return 0


def _cmd_static(args: argparse.Namespace) -> int:
    from bench import limits
    from bench.sensor_twin import make_static_run, static_samples, write_static

    profile = sensor_profile(args)
    rate = args.rate if args.rate is not None else (
        profile.sample_rate if profile is not None else 100.0)
    check_positive(rate, "--rate")
    check_positive(args.duration, "--duration")
    check_positive(args.g, "--g")
    if not math.isfinite(args.theta):
        raise OptionError(f"--theta must be a finite angle in rad, got {args.theta}")
    n = static_samples(args.duration, rate)
    # the readings, their truth copy and the flicker's 2N draws: ~ 8 arrays of N doubles
    limits.check_memory(limits.static_run_bytes(n) + 64 * n,
                        f"--duration {args.duration:g} s at --rate {rate:g} Hz")
    sensor = sensor_model(args, rate)
    run = make_static_run(sensor, args.duration, rate, args.theta, args.seed, g=args.g,
                          twin=twin_record(args, rate))
    check_finite({"datos": run.datos, "truth": run.truth()}, f"{args.out}: the run")
    paths = write_static(run, args.out, force=args.force)
    print_summary(args, f"generate static: {n} samples at {rate:g} Hz, θ = {args.theta:g} rad, "
                  f"seed {args.seed}", {"n": n, "rate": rate, "files": paths},
                  {"n": "count", "rate": "Hz"})
    return 0


def _fixes(receiver, truth, seed: int):
    """The receiver's fixes on the run's MuJoCo truth (own seed stream), or None."""
    if receiver is None:
        return None
    from bench.gnss import fixes_for_seed

    return fixes_for_seed(receiver, truth, seed)


def _gps_title(gps) -> str:
    return "" if gps is None else f", {gps.n} GNSS fixes"


# ---------------------------------------------------------------- the six-face twin (--faces)
SIX_FACE_DEFAULTS: dict[str, object] = {
    "bias": "0.1,-0.05,0.2", "scale": "0.01,-0.01,0.02", "noise_var": "0.0016,0.0016,0.0025",
    "misalignment": "0.004,-0.002,0.001,0.003,0.002,-0.001", "holds_per_face": 2,
    "hold_seconds": 5.0, "between_hold_std": 0.002, "gyro_sigma": 0.005,
}
"""``generate calibration --faces`` when an option is not given: a MEMS-grade 3-axis sensor
(σ 0.04, 0.04, 0.05 m/s² at 100 Hz, about 400–500 µg/√Hz; bias m/s², scale 1, misalignment rad)
placed by hand (a tilt of 0.002 rad ≈ 0.1° per hold), each face held twice, 5 s, and a gyro
with 0.005 rad/s of white noise."""

SIX_FACE_ONLY = ("holds_per_face", "hold_seconds", "misalignment", "between_hold_std",
                 "gyro_sigma")
"""Destinations of the options that only the six-face twin has (default None: not given)."""

TILT_DEFAULTS: dict[str, object] = {
    "mode": "static", "theta_range": FULL_TURN, "count": 20001, "theta_list": None,
    "theta_from": None, "positions": None, "per_position": 100, "sweep_profile": "constant",
    "duration": 20.0, "cycles": 1.0, "effect": None, "rrd": None,
}
"""The tilt table's options of ``generate calibration`` and their defaults (the parser's);
the six-face twin refuses any of them set otherwise."""

SIX_FACE_SAMPLE_BYTES = 600
"""Peak per sample of a six-face run: the MuJoCo rows (specific force, rate, hinge angles),
the readings and the CSV text (≈ 75 B a row) built in memory."""


def _option(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def _given(args: argparse.Namespace, dest: str) -> bool:
    """Whether an option whose default is :class:`Deferred` was on the command line."""
    return dest not in getattr(args, "deferred_defaults", frozenset())


def _six_face_value(args: argparse.Namespace, dest: str):
    value = getattr(args, dest)
    return SIX_FACE_DEFAULTS[dest] if value is None or not _given(args, dest) else value


def _numbers(text: str, dest: str, count: int, names: str):
    """``count`` finite numbers of option ``dest`` (comma-separated), within the option's
    magnitude limit; OptionError naming the option and the values expected."""
    import numpy as np

    what = _option(dest)
    values = parse_floats(text, what)
    if len(values) != count:
        raise OptionError(f"{what}: the six-face twin's sensor has three axes: give {count} "
                          f"values {names}, got {text!r}")
    for v in values:
        check_number(v, what)
    return np.array(values)


def six_face_sensor(args: argparse.Namespace, rate: float):
    """:class:`bench.six_face.ThreeAxisSensor` and the profile's record (or None) from
    ``--bias``, ``--scale``, ``--misalignment``, ``--noise-var`` or ``--sensor``,
    ``--gyro-sigma``."""
    from bench.sensors import AxisErrors
    from bench.six_face import MAX_TILT, ThreeAxisSensor, twin_axes
    from calib.input_rules import DataError

    bias = _numbers(_six_face_value(args, "bias"), "bias", 3, "x,y,z in m/s²")
    scale = _numbers(_six_face_value(args, "scale"), "scale", 3, "x,y,z")
    if any(s <= -1 for s in scale):
        raise OptionError(f"--scale: each scale error must be > -1 (the gain 1 + scale is "
                          f"positive), got {_six_face_value(args, 'scale')}")
    mis = _numbers(_six_face_value(args, "misalignment"), "misalignment", 6,
                   "m_xy,m_xz,m_yx,m_yz,m_zx,m_zy in rad")
    if any(abs(m) > MAX_TILT for m in mis):
        raise OptionError(f"--misalignment: small angles, at most {MAX_TILT:g} rad each "
                          f"(K = (I + S)(I + M) is the small-angle model), got "
                          f"{args.misalignment}")
    gyro_sigma = float(_six_face_value(args, "gyro_sigma"))
    if not (math.isfinite(gyro_sigma) and gyro_sigma >= 0):
        raise OptionError(f"--gyro-sigma must be a finite number >= 0 rad/s, got {gyro_sigma}")
    twin = None
    profile = sensor_profile(args)  # calib.noise.sensor_profile.load_profile
    if profile is not None:
        if _given(args, "noise_var"):
            raise OptionError("give --sensor or --noise-var, not both: the profile's white "
                              "noise is the sensor's noise")
        try:
            axes, axis_map = twin_axes(profile, rate)
        except (KeyError, IndexError, TypeError) as exc:
            raise DataError(f"{args.sensor}: the profile's noise terms do not fit its axes "
                            f"({exc})") from None
        twin = dict(twin_record(args, rate), axis_map=axis_map)
    else:
        nv = _numbers(_six_face_value(args, "noise_var"), "noise_var", 3,
                      "x,y,z in (m/s²)²")
        lo, hi = VARIANCE_RANGE
        if any(v != 0 and not lo <= v <= hi for v in nv):  # 0: a noiseless axis
            raise OptionError(f"--noise-var: variances must be 0 or between {lo:g} and {hi:g} "
                              f"(m/s²)², got {_six_face_value(args, 'noise_var')}")
        axes = tuple(AxisErrors(noise_var=float(v)) for v in nv)
    sensor = ThreeAxisSensor(bias=tuple(bias), scale=tuple(scale), misalignment=tuple(mis),
                             axes=axes, gyro_sigma=gyro_sigma)
    return sensor, twin


def six_face_config(args: argparse.Namespace):
    """:class:`bench.six_face.SixFaceConfig` from the options of ``generate calibration
    --faces``; OptionError naming the option for anything the run cannot use."""
    from bench.model import six_face_fixture
    from bench.six_face import (
        MAX_TILT,
        MIN_HOLD_SECONDS,
        SixFaceConfig,
        check_faces,
        check_identifiable,
        sample_stride,
    )

    tilt = [_option(d) for d, v in TILT_DEFAULTS.items() if getattr(args, d) != v]
    if tilt:
        raise OptionError(f"{tilt[0]} is an option of the tilt table; the six-face twin "
                          "(--faces) does not use it")
    try:
        faces = check_faces([f.strip() for f in args.faces.split(",")])
    except ValueError as exc:
        raise OptionError(f"--faces {args.faces}: {exc}") from None
    holds = check_count(int(_six_face_value(args, "holds_per_face")), "--holds-per-face")
    hold_s = check_positive(float(_six_face_value(args, "hold_seconds")), "--hold-seconds")
    if hold_s < MIN_HOLD_SECONDS:
        raise OptionError(f"--hold-seconds {hold_s:g}: at least {MIN_HOLD_SECONDS:g} s, so that "
                          "the pose detector finds each hold (it ignores holds under 1 s and "
                          "trims half a 0.5 s window at each edge)")
    wobble = float(_six_face_value(args, "between_hold_std"))
    if not (math.isfinite(wobble) and 0 <= wobble <= MAX_TILT):
        raise OptionError(f"--between-hold-std: a placement tilt in [0, {MAX_TILT:g}] rad "
                          f"(beyond, a hold is no longer on a face), got {wobble:g}")
    check_positive(args.g, "--g")
    rate = check_positive(args.rate, "--rate")
    try:
        sample_stride(rate, six_face_fixture(args.g)[0].opt.timestep)
    except ValueError as exc:
        raise OptionError(f"--rate: {exc}") from None
    sensor, twin = six_face_sensor(args, rate)
    config = SixFaceConfig(faces=faces, holds_per_face=holds, hold_seconds=hold_s, rate=rate,
                           g=args.g, sensor=sensor, wobble_std=wobble, twin=twin)
    try:  # the message the six-face fit (tiltbench calibrate) gives on such holds
        check_identifiable(config.schedule(), config.g, source=f"--faces {args.faces}")
    except ValueError as exc:
        raise OptionError(str(exc)) from None
    return config


def _cmd_six_face(args: argparse.Namespace) -> int:
    """``generate calibration --faces``: the six-face test of a 3-axis sensor on the MuJoCo
    tumble fixture (:mod:`bench.six_face`): ``log.csv`` and ``truth.json``."""
    from bench import limits
    from bench.six_face import (
        SETTLE_SECONDS,
        TUMBLE_SECONDS,
        generate_six_face,
        run_samples,
        write_six_face,
    )

    config = six_face_config(args)
    n = run_samples(config)
    holds = len(config.schedule())
    what = (f"--hold-seconds {config.hold_seconds:g} × {holds} holds at --rate "
            f"{config.rate:g} Hz")
    longest = max(config.hold_seconds, TUMBLE_SECONDS + SETTLE_SECONDS)
    _announce("generate calibration", limits.check_memory(
        limits.sweep_run_bytes(longest, 0.001) + SIX_FACE_SAMPLE_BYTES * n, what))
    limits.check_disk(80.0 * n, args.out, what)
    run = generate_six_face(config, args.seed)
    check_finite({"acc": run.acc, "gyro": run.gyro, "truth": run.truth()},
                 f"{args.out}: the run")
    paths = write_six_face(run, args.out, force=args.force)
    faces = ", ".join(config.faces)
    print_summary(args, f"generate calibration: six-face twin, {holds} holds on the faces "
                  f"{faces} ({config.holds_per_face}×), {n} samples at {config.rate:g} Hz, "
                  f"seed {args.seed} (the truth is in truth.json only)",
                  {"n": n, "holds": holds, "rate": config.rate, "files": paths},
                  {"n": "count", "holds": "count", "rate": "Hz"})
    return 0


# ---------------------------------------------------------------- options
def _add_gps_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group(
        "GNSS receiver (gps.mat: t_gps M×1 s, pos M×2 m, vel M×2 m/s; docs/gnss.md)",
        "Any of these writes gps.mat and the receiver into truth.json; without them the "
        "outputs are unchanged. Fixes fall on the IMU grid: --rate a whole multiple of "
        "--gps-rate, --gps-latency whole IMU periods.")
    add_option(g, "--gps", action="store_true",
               help="write gps.mat with the default receiver (1 Hz, 3 m, no velocity)")
    add_option(g, "--gps-rate", type=float, help="fix rate, Hz (1 if not given)")
    add_option(g, "--gps-sigma", type=float,
               help="position fix noise std per axis, m (3 if not given)")
    add_option(g, "--gps-vel-sigma", type=float,
               help="also velocity fixes with this noise std per axis, m/s (thesis: 0.1)")
    add_option(g, "--gps-latency", type=float,
               help="the fix at t reports the state at t - S, s (0 if not given)")
    add_option(g, "--gps-outage", action="append",
               help="no fixes for A <= t <= B, s (repeatable)")


def _add_vehicle_options(p: argparse.ArgumentParser, profile_default: str | None) -> None:
    add_option(p, "--duration", type=float, default=60.0, help="run length, s")
    add_option(p, "--rate", type=float, default=100.0)
    add_option(p, "--p0", default="0,0")
    add_option(p, "--v0", default="1,3")
    add_option(p, "--profile", default=profile_default,
               help="acceleration segments 'dur:ax,ay;dur:ax,ay;…' (s : m/s²) or 'course'"
                    + ("" if profile_default else "; omitted: drawn from the seed"))


def _add_turning_options(p: argparse.ArgumentParser) -> None:
    add_option(p, "--turning", help="free yaw hinge driven by the default yaw profile "
               "(heading turns 143°): body-frame readings and acel.mat 'gyro' M×1, the yaw "
               "rate in rad/s (docs/fusion.md)")
    add_option(p, "--gyro-sigma", type=float,
               help="with --turning: white gyro noise std, rad/s (0.005 if not given)")


def _add_vehicle_run(p: argparse.ArgumentParser, profile_default: str | None, what: str) -> None:
    """The options of the kinds that run the vehicle (``vehicle``, ``course``): its motion,
    the turning hinge, ``--rrd`` (the ``what``, run or set, next to its truth) and the
    receiver."""
    _add_vehicle_options(p, profile_default)
    _add_turning_options(p)
    add_option(p, "--rrd", help=f"also record the {what} next to its truth to this rerun file")
    _add_gps_options(p)


def _add_kind(kinds, name: str, handler, **kwargs) -> argparse.ArgumentParser:
    """A ``generate`` kind: its parser, run by ``handler``, with the options every kind has
    (``--seed``, ``--out``, ``--force``, ``--json``)."""
    p = add_command(kinds, name, handler, **kwargs)
    add_generate_common(p)
    return p


def _register_calibration(kinds) -> None:
    p = _add_kind(kinds, "calibration", _cmd_calibration,
                  help="a tilt-table calibration run (ensayo.mat), or with --faces the "
                  "six-face test of a 3-axis sensor (log.csv)")
    add_sensor_options(p)
    add_option(p, "--allow-failed-fit")  # with --sensor (calib.noise.sensor_profile)
    # --bias/--scale/--noise-var: the tilt table's pairs unless given (Deferred: --faces tells a
    # pair it was not given from one it was, and takes its own x,y,z defaults then)
    p.set_defaults(bias=Deferred(lambda: DEFAULT_BIAS), scale=Deferred(lambda: DEFAULT_SCALE),
                   noise_var=Deferred(lambda: DEFAULT_NOISE))
    t = TILT_DEFAULTS
    add_option(p, "--mode", choices=["static", "sweep"], default=t["mode"],
               help="static: held poses; sweep: servo-driven rotation, θ from the encoder")
    add_option(p, "--theta-range", default=t["theta_range"], help="θ range start,stop in rad, "
               "any finite values (static range/positions; sweep)")
    add_option(p, "--count", type=integer, default=t["count"],
               help="static: samples over the range")
    add_option(p, "--theta-list",
               help="static: explicit θ values in rad (any finite), comma separated")
    add_option(p, "--theta-from", help="static: the θ of every sample of this ensayo.mat (e.g. "
               "a measured run's import), in order: its twin holds the same poses")
    add_option(p, "--positions", type=integer, help="static: number of discrete held positions")
    add_option(p, "--per-position", type=integer, default=t["per_position"],
               help="static: samples held at each position")
    add_option(p, "--sweep-profile", choices=["constant", "accel", "updown", "sine"],
               default=t["sweep_profile"], old="--profile", help="sweep: commanded angle profile")
    add_option(p, "--duration", type=float, default=t["duration"], help="sweep: duration, s")
    add_option(p, "--rate", type=float, default=100.0,
               help="sweep and --faces: sample rate, Hz")
    add_option(p, "--cycles", type=float, default=t["cycles"],
               help="sweep: up-down/sine cycles")
    add_option(p, "--effect", action="append", help="add a catalog effect (repeatable), e.g. "
               "misalignment:x:delta=0.02, tilt_offset:both:delta=0.01, lever_arm:x:pos_x=0.2 "
               "(docs/effects.md)")
    add_option(p, "--rrd", help="also record the truth to this rerun file")
    _add_six_face_options(p)


def _add_six_face_options(p: argparse.ArgumentParser) -> None:
    d = SIX_FACE_DEFAULTS
    g = p.add_argument_group(
        "six-face twin (docs/six-face-twin.md)",
        "--faces runs the six-face test of a 3-axis sensor on a MuJoCo tumble fixture "
        "instead of the tilt table: holds on the faces, tumbles between them; writes log.csv "
        "(t s, acc_x/y/z m/s², gyro_x/y/z rad/s) and truth.json. --bias, --scale and "
        f"--noise-var then take x,y,z (if not given: {d['bias']} m/s², {d['scale']}, "
        f"{d['noise_var']} (m/s²)²); --sensor gives the noise; --rate, --g, --seed, --out, "
        "--force, --json as above.")
    add_option(g, "--faces", help="the faces held, in order, e.g. +x,-x,+y,-y,+z,-z (a list "
               "that starts with '-': --faces=-x,…)")
    add_option(g, "--holds-per-face", type=integer,
               help=f"the list of faces is held K times over ({d['holds_per_face']} if not "
               "given)")
    add_option(g, "--hold-seconds", type=float,
               help=f"length of each hold, s ({d['hold_seconds']:g} if not given)")
    add_option(g, "--misalignment", help="m_xy,m_xz,m_yx,m_yz,m_zx,m_zy in rad: axis a leans "
               f"toward case axis b (K = (I + S)(I + M); {d['misalignment']} if not given)")
    add_option(g, "--between-hold-std", type=float,
               help="std of each hold's placement tilt about each horizontal axis, rad "
               f"({d['between_hold_std']:g} if not given)")
    add_option(g, "--gyro-sigma", type=float,
               help=f"white gyro noise std, rad/s ({d['gyro_sigma']:g} if not given)")


def _register_vehicle(kinds) -> None:
    p = _add_kind(kinds, "vehicle", _cmd_vehicle, help="a planar vehicle run (acel.mat)")
    add_sensor_options(p)
    add_option(p, "--allow-failed-fit")  # with --sensor (calib.noise.sensor_profile)
    _add_vehicle_run(p, "course", "run")


def _register_course(kinds) -> None:
    p = _add_kind(kinds, "course", _cmd_course, help="a full course set",
                  epilog="Without --profile the acceleration profile is drawn from the seed "
                  "(--profile course gives the course's).")
    _add_vehicle_run(p, None, "set")
    add_option(p, "--noise-var", default=DEFAULT_NOISE, help="noise variances x,y (m/s²)²")
    add_option(p, "--bias", help="true bias x,y in m/s²; omitted: drawn from the seed")
    add_option(p, "--scale", help="true scale-factor error x,y; omitted: drawn from the seed")
    add_option(p, "--count", type=integer, default=20001,
               help="calibration samples over [0, 2π]")
    add_option(p, "--min-separation", type=float, default=100.0,
               help="smallest distance between candidate points, m")
    add_gravity(p)


def _register_class(kinds) -> None:
    p = _add_kind(kinds, "class", _cmd_class, help="K unique course sets + answer key",
                  description="K unique course sets (one folder each, no truth inside) and "
                  "the private answer key DIR/answer_key.csv and DIR/answer_key.json.")
    add_option(p, "--students", type=integer, required=True)
    add_option(p, "--prefix", default="student")
    add_option(p, "--noise-var", default=DEFAULT_NOISE,
               help="noise variances x,y (m/s²)² of every set")
    add_option(p, "--quiet")
    add_sweep_options(p)


def _register_static(kinds) -> None:
    p = _add_kind(kinds, "static", _cmd_static, help="a static log of one held pose "
                  "(static.mat), e.g. for `tiltbench noise`",
                  description="The table held at --theta for --duration s sampled at --rate "
                  "Hz: static.mat (t, Aerr: the course acel.mat layout) and truth.json. With "
                  "--sensor, the measured sensor's noise terms.")
    add_sensor_options(p)
    add_option(p, "--allow-failed-fit")  # with --sensor (calib.noise.sensor_profile)
    add_option(p, "--duration", type=float, default=600.0, help="log length, s")
    add_option(p, "--rate", type=float, default=None,
               help="sample rate, Hz (default: the --sensor profile's, else 100)")
    add_option(p, "--theta", type=float, default=0.0)


def register(sub) -> None:
    gen = sub.add_parser("generate", help="generate datasets with the simulated bench")
    kinds = gen.add_subparsers(dest="kind", required=True, metavar="KIND")
    _register_calibration(kinds)
    _register_vehicle(kinds)
    _register_course(kinds)
    _register_class(kinds)
    _register_static(kinds)
