"""``tiltbench generate calibration|vehicle|course|class``: parse, call the library, print."""

from __future__ import annotations

import argparse
import importlib
import sys

import numpy as np

from bench.model import TableEdits
from bench.sensors import SensorErrorModel
from bench.tilt import (
    CalibrationConfig,
    SweepProfile,
    ThetaDesign,
    generate_calibration,
    write_calibration,
)
from calib.io import DataError, check_positive, dumps, parse_pair, refuse_overwrite

DEFAULT_BIAS = "0.08,-0.02"
DEFAULT_SCALE = "-0.03,0.01"
DEFAULT_NOISE = "0.25,0.64"


def _theta_list(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise DataError(f"--theta-list: expected comma-separated radians, got {text!r}") from None
    if not np.all(np.isfinite(values)):
        raise DataError(f"--theta-list: values must be finite, got {text!r}")
    return values


def calibration_config(args: argparse.Namespace) -> CalibrationConfig:
    """Build the run configuration from the command-line options (validated)."""
    sensor = SensorErrorModel.from_pairs(parse_pair(args.bias, "--bias"),
                                         parse_pair(args.scale, "--scale"),
                                         parse_pair(args.noise_var, "--noise-var"))
    start, stop = parse_pair(args.theta_range, "--theta-range")
    for v in (start, stop):
        if abs(v) > 2 * np.pi * (1 + 1e-9):
            raise DataError(f"--theta-range: {v} exceeds 2π; angles are in radians "
                            "(degrees? multiply by π/180)")
    if args.theta_list is not None:
        theta = ThetaDesign(kind="list", values=_theta_list(args.theta_list))
        if np.max(np.abs(theta.values)) > 2 * np.pi * (1 + 1e-9):
            raise DataError("--theta-list: values exceed 2π; angles are in radians")
    elif args.positions is not None:
        theta = ThetaDesign(kind="positions", start=start, stop=stop, positions=args.positions,
                            per_position=args.per_position)
    else:
        theta = ThetaDesign(kind="range", start=start, stop=stop, count=args.count)
    sweep = SweepProfile(kind=args.profile, start=start, stop=stop, duration=args.duration,
                         rate=args.rate, cycles=args.cycles)
    check_positive(args.g, "--g")
    config = CalibrationConfig(mode=args.mode, theta=theta, sweep=sweep, sensor=sensor,
                               table=TableEdits(g=args.g))
    if getattr(args, "effect", None):  # effect catalog (docs/effects.md), bench/effects.py
        from bench.effects import apply_effects, parse_effect_option

        config = apply_effects(config, [parse_effect_option(e) for e in args.effect])
    return config


def _cmd_calibration(args: argparse.Namespace) -> int:
    refuse_overwrite([getattr(args, "rrd", None)], args.force)
    run = generate_calibration(calibration_config(args), args.seed)
    paths = write_calibration(run, args.out, force=args.force)
    if getattr(args, "rrd", None):
        from bench.record import record_calibration_truth  # recordings feature

        paths["rrd"] = str(record_calibration_truth(run, args.rrd, force=args.force))
    print_summary(args, f"generate calibration: {run.tita.shape[0]} samples ({run.config.mode}), "
                  f"seed {args.seed}",
                  {"n": int(run.tita.shape[0]), "mode": run.config.mode, "files": paths})
    return 0


def _delegate(module: str, func: str):
    """Handler that calls a library CLI function living beside its feature."""

    def handler(args: argparse.Namespace) -> int:
        return getattr(importlib.import_module(module), func)(args)

    return handler


def add_common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--seed", type=int, default=0, help="random seed")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--force", action="store_true", help="overwrite existing files")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def print_summary(args: argparse.Namespace, title: str, summary: dict) -> None:
    """What a generate command wrote: one JSON object with ``--json``, else readable lines
    (the title, scalar entries as ``key: value``, nested mappings one entry per line)."""
    if getattr(args, "json", False):
        print(dumps(summary), end="")
        return
    lines = [title]
    for key, value in summary.items():
        if isinstance(value, dict):
            lines.append(f"{key}:")
            width = max(map(len, value), default=0)
            lines += [f"  {k:<{width}}  {v}" for k, v in value.items()]
        else:
            lines.append(f"{key}: {value}")
    print("\n".join(lines))


def add_sensor_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--bias", default=DEFAULT_BIAS, help="true bias x,y in m/s²")
    p.add_argument("--scale", default=DEFAULT_SCALE, help="true scale-factor error x,y")
    p.add_argument("--noise-var", default=DEFAULT_NOISE, help="noise variances x,y (m/s²)²")
    p.add_argument("--g", type=float, default=9.8, help="gravity, m/s²")


def register(sub) -> None:
    gen = sub.add_parser("generate", help="generate datasets with the simulated bench")
    kinds = gen.add_subparsers(dest="kind", required=True, metavar="KIND")

    p = kinds.add_parser("calibration", help="a tilt-table calibration run (ensayo.mat)")
    add_common(p)
    add_sensor_options(p)
    p.add_argument("--mode", choices=["static", "sweep"], default="static",
                   help="static: held poses; sweep: servo-driven rotation, θ from the encoder")
    p.add_argument("--theta-range", default=f"0,{2 * np.pi!r}",
                   help="θ range start,stop in rad (static range/positions; sweep)")
    p.add_argument("--count", type=int, default=20001, help="static: samples over the range")
    p.add_argument("--theta-list", help="static: explicit θ values in rad, comma separated")
    p.add_argument("--positions", type=int, help="static: number of discrete held positions")
    p.add_argument("--per-position", type=int, default=100,
                   help="static: samples held at each position")
    p.add_argument("--profile", choices=["constant", "accel", "updown", "sine"],
                   default="constant", help="sweep: commanded angle profile")
    p.add_argument("--duration", type=float, default=20.0, help="sweep: duration, s")
    p.add_argument("--rate", type=float, default=100.0, help="sweep: sample rate, Hz")
    p.add_argument("--cycles", type=float, default=1.0, help="sweep: up-down/sine cycles")
    p.add_argument("--effect", action="append", metavar="NAME:AXIS:KEY=VALUE[,KEY=VALUE]",
                   help="add a catalog effect (repeatable), e.g. misalignment:x:delta=0.02, "
                        "tilt_offset:both:delta=0.01, lever_arm:x:pos_x=0.2 (docs/effects.md)")
    p.add_argument("--rrd", help="also record the truth to this rerun file")
    p.set_defaults(handler=_cmd_calibration)

    for kind, module, func, text in (
        ("vehicle", "bench.vehicle", "cli_generate_vehicle", "a planar vehicle run (acel.mat)"),
        ("course", "bench.course", "cli_generate_course", "a full course set"),
        ("class", "bench.classset", "cli_generate_class", "K unique course sets + answer key"),
    ):
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as exc:
            if exc.name == module:
                continue
            raise
        if not hasattr(mod, "add_cli_options"):
            continue
        p = kinds.add_parser(kind, help=text)
        mod.add_cli_options(p)
        p.set_defaults(handler=_delegate(module, func))


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use the tiltbench command")
