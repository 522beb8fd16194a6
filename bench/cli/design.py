"""``tiltbench design``: which θ design, N and sweep rate detect the effects, and separate
the look-alike pairs (:mod:`calib.design`). ``--json`` prints one JSON object on stdout;
progress goes to stderr."""

from __future__ import annotations

import argparse

from bench import limits
from bench.cli.options import (
    OptionError,
    add_command,
    add_force,
    add_json,
    add_sweep_options,
    check_count,
    integer,
    mapper_from_args,
    parse_floats,
    parse_ints,
    parse_pair,
    parse_variances,
)
from bench.cli.output import check_finite, print_files, print_json, refuse_overwrite
from bench.cli.progress import Progress
from bench.cli.vocabulary import add_option, deprecated

DEFAULT_DESIGNS = "uniform,sweep,reversal"


def _names(text: str, allowed: tuple[str, ...], what: str) -> list[str]:
    out = [s.strip() for s in text.split(",") if s.strip()]
    bad = [s for s in out if s not in allowed]
    if not out or bad:
        raise OptionError(f"{what} {text!r}: choose from {', '.join(allowed)}")
    return out


def _sizes(items: list[str], allowed: tuple[str, ...]) -> dict[str, float]:
    out = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or name not in allowed:
            raise OptionError(f"--size {item!r}: expected NAME=VALUE with NAME one of "
                              f"{', '.join(allowed)}")
        try:
            v = float(value)
        except ValueError:
            raise OptionError(f"--size {item!r}: {value!r} is not a number") from None
        if not v == v or v in (float("inf"), float("-inf")) or (
                v <= 0 and name in ("saturation", "noise_level", "quantization",
                                    "bias_random_walk", "lowpass_lag")):
            raise OptionError(f"--size {item!r}: must be a finite "
                              f"{'positive ' if v <= 0 else ''}number")
        out[name] = v
    return out


def _scale_of_axis(text: str, axis: str) -> float:
    """``--scale sx,sy``: the scale-factor error of ``axis`` (the one carrying the effects),
    each within (-0.5, 0.5). One number, the former spelling, is that axis's, with a
    deprecation warning."""
    if "," not in text.strip():
        (value,) = parse_floats(text, "--scale")
        pair = {"x": (value, 0.0), "y": (0.0, value)}[axis]
        deprecated(f"--scale with one number ({axis})", f"--scale {pair[0]:g},{pair[1]:g}")
    else:
        pair = tuple(parse_pair(text, "--scale"))
    if not all(-0.5 < s < 0.5 for s in pair):
        raise OptionError(f"--scale {text}: the sensor's scale factors must be within "
                          "(-0.5, 0.5) (gain 1 + scale; e.g. -0.03 for a sensor reading 3 % "
                          "low)")
    return float(pair["xy".index(axis)])


def _cmd_design(args: argparse.Namespace) -> int:
    from calib.design import DESIGNS, Experiment, analyze_design
    from calib.design.analysis import ALPHA_MIN
    from calib.design.experiments import RATE_RANGE
    from calib.design.signals import LINEAR, SIMULATED

    allowed = LINEAR + SIMULATED
    designs = _names(args.designs, DESIGNS, "--designs")
    effects = _names(args.effects, allowed, "--effects") if args.effects else list(allowed)
    ns = parse_ints(args.count, "--count")
    rates = parse_floats(args.sweep_rate, "--sweep-rate")
    if any(n < 16 for n in ns):
        raise OptionError(f"--count {args.count}: every N must be >= 16")
    # each process holds one experiment of the largest N at a time (bench/limits.py)
    limits.check_memory(limits.DESIGN_SAMPLE_BYTES * max(ns), f"--count {max(ns)}")
    lo, hi = RATE_RANGE
    if any(not lo <= r <= hi for r in rates):
        raise OptionError(f"--sweep-rate {args.sweep_rate}: sweep rates must be within "
                          f"[{lo:g}, {hi:g}] rad/s")
    if not ALPHA_MIN <= args.alpha < 1:
        raise OptionError(f"--alpha {args.alpha}: must be in [{ALPHA_MIN:g}, 1)")
    check_count(args.runs, "--runs", 0)
    check_count(args.mc_grid, "--mc-grid", 0)
    if args.mc_grid == 1 or (args.mc_grid and args.runs == 0):
        raise OptionError(f"--mc-grid {args.mc_grid}: needs K >= 2 sizes and --runs >= 1 "
                          "(0: no grid)")
    scale = _scale_of_axis(args.scale, args.axis)
    sizes = _sizes(args.size, allowed)
    nv = parse_variances(args.noise_var)
    if args.plot:
        refuse_overwrite([args.plot], args.force)
    exps = [Experiment(d, n, r) for d in designs for n in ns for r in rates]
    # Monte Carlo work: runs × grid sizes × simulated effects × experiments (bench/limits.py)
    per_run = sum(limits.DESIGN_RUN_SECONDS + limits.DESIGN_RUN_SAMPLE_SECONDS * e.n
                  for e in exps) * sum(e in SIMULATED for e in effects)
    limits.check_time(per_run * args.runs * max(1, args.mc_grid),
                      f"--runs {args.runs}" + (f" --mc-grid {args.mc_grid}" if args.mc_grid
                                               else ""))
    res = analyze_design(exps, effects, sizes, nv, args.alpha, args.axis, args.runs,
                         args.seed, mapper=mapper_from_args(args),
                         progress=Progress("design", quiet=args.quiet), mc_grid=args.mc_grid,
                         gain=1.0 + scale)
    written = []
    if args.plot:
        from bench.figures.design import design_figure
        from bench.figures.save import save_figure

        written.append(save_figure(design_figure(res), args.plot, args.force))
    if args.json:
        print_json(res.to_dict())
    else:
        check_finite(res.to_dict(), "the result")
        print(res.summary())
        print_files(written)
    return 0


def register(sub) -> None:
    q = add_command(sub, "design", _cmd_design, help="power per effect and experiment design")
    add_option(q, "--designs", default=DEFAULT_DESIGNS,
               help="θ designs: uniform, held, sweep, reversal, accel (comma-separated)")
    add_option(q, "--count", default="2001", old="--n",
               help="calibration samples N of each experiment (comma-separated)")
    add_option(q, "--sweep-rate", default="0.314", old="--rate",
               help="mean sweep rates ω̄ of the experiments, rad/s (comma-separated)")
    add_option(q, "--effects", default=None,
               help="catalog effects (comma-separated; default: every testable one)")
    add_option(q, "--size", action="append", help="effect size in its unit (repeatable)")
    add_option(q, "--noise-var", default="0.25,0.64", help="stated σx², σy², (m/s²)²")
    add_option(q, "--axis", choices=("x", "y"), default="x")
    add_option(q, "--alpha", type=float, default=0.001,
               help="the gap's family false-alarm probability (its default: 0.001)")
    add_option(q, "--runs", type=integer, default=10,
               help="Monte Carlo runs per cell (0: analytic only)")
    add_option(q, "--seed", type=int, default=0, help="seed of the Monte Carlo runs")
    add_option(q, "--scale", default="0,0",
               help="the sensor's scale-factor error sx,sy (gain 1 + s, e.g. from a "
                    "calibration): the effects on --axis act through its gain, so the sizes "
                    "include it")
    add_option(q, "--mc-grid", type=integer, default=0,
               help="Monte Carlo effects: also run K sizes on a geometric grid of the "
                    "effect's strength, ×1/4 to ×4 around the asked size (saturation: "
                    "strength ln(g/L), a lower limit is stronger; noise_level: "
                    "|ln(σ²/stated)|), the same noise per run at every size, and report "
                    "the 80 %% / 95 %% sizes interpolated on the monotone fit (0: the "
                    "asked size only)")
    add_option(q, "--plot", help="power curves (.png or .svg)")
    add_option(q, "--quiet")
    add_json(q)
    add_force(q)
    add_sweep_options(q)
