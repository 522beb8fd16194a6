"""``tiltbench design``: which θ design, N and sweep rate detect the effects, and separate
the look-alike pairs (:mod:`calib.design`). ``--json`` prints one JSON object on stdout;
progress goes to stderr."""

from __future__ import annotations

import argparse

from bench import limits
from bench.cli.options import (
    OptionError,
    add_force,
    add_json,
    add_sweep_options,
    check_count,
    integer,
    mapper_from_args,
    parse_floats,
    parse_ints,
    parse_variances,
)
from bench.cli.output import check_finite, print_files, print_json, refuse_overwrite
from bench.cli.progress import Progress

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


def _cmd_design(args: argparse.Namespace) -> int:
    from calib.design import DESIGNS, Experiment, analyze_design
    from calib.design.analysis import ALPHA_MIN
    from calib.design.experiments import RATE_RANGE
    from calib.design.signals import LINEAR, SIMULATED

    allowed = LINEAR + SIMULATED
    designs = _names(args.designs, DESIGNS, "--designs")
    effects = _names(args.effects, allowed, "--effects") if args.effects else list(allowed)
    ns = parse_ints(args.n, "--n")
    rates = parse_floats(args.rate, "--rate")
    if any(n < 16 for n in ns):
        raise OptionError(f"--n {args.n}: every N must be >= 16")
    # each process holds one experiment of the largest N at a time (bench/limits.py)
    limits.check_memory(limits.DESIGN_SAMPLE_BYTES * max(ns), f"--n {max(ns)}")
    lo, hi = RATE_RANGE
    if any(not lo <= r <= hi for r in rates):
        raise OptionError(f"--rate {args.rate}: sweep rates must be within [{lo:g}, {hi:g}] "
                          "rad/s")
    if not ALPHA_MIN <= args.alpha < 1:
        raise OptionError(f"--alpha {args.alpha}: must be in [{ALPHA_MIN:g}, 1)")
    check_count(args.runs, "--runs", 0)
    check_count(args.mc_grid, "--mc-grid", 0)
    if args.mc_grid == 1 or (args.mc_grid and args.runs == 0):
        raise OptionError(f"--mc-grid {args.mc_grid}: needs K >= 2 sizes and --runs >= 1 "
                          "(0: no grid)")
    if not -0.5 < args.scale < 0.5:
        raise OptionError(f"--scale {args.scale}: the sensor's scale factor must be within "
                          "(-0.5, 0.5) (gain 1 + scale; e.g. -0.03 for a sensor reading 3 % low)")
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
                         gain=1.0 + args.scale)
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
    q = sub.add_parser("design", help="power per effect and experiment design")
    q.add_argument("--designs", default=DEFAULT_DESIGNS,
                   help="θ designs: uniform, held, sweep, reversal, accel (comma-separated)")
    q.add_argument("--n", default="2001", help="samples N (comma-separated)")
    q.add_argument("--rate", default="0.314", help="mean sweep rates, rad/s (comma-separated)")
    q.add_argument("--effects", default=None,
                   help="catalog effects (comma-separated; default: every testable one)")
    q.add_argument("--size", action="append", metavar="NAME=VALUE",
                   help="effect size in its unit (repeatable)")
    q.add_argument("--noise-var", default="0.25,0.64", help="stated σx², σy², (m/s²)²")
    q.add_argument("--axis", choices=("x", "y"), default="x",
                   help="axis carrying the per-axis effects")
    q.add_argument("--alpha", type=float, default=0.005,
                   help="the gap's family false-alarm probability")
    q.add_argument("--runs", type=integer, default=10,
                   help="Monte Carlo runs per cell (0: analytic only)")
    q.add_argument("--seed", type=int, default=0, help="seed of the Monte Carlo runs")
    q.add_argument("--scale", type=float, default=0.0,
                   help="the sensor's scale factor s (gain 1 + s, e.g. from a calibration): "
                        "the effects act through the gain, so the sizes include it")
    q.add_argument("--mc-grid", type=integer, default=0, metavar="K",
                   help="Monte Carlo effects: also run K sizes on a geometric grid of the "
                        "effect's strength, ×1/4 to ×4 around the asked size (saturation: "
                        "strength ln(g/L), a lower limit is stronger; noise_level: "
                        "|ln(σ²/stated)|), the same noise per run at every size, and report "
                        "the 80 %% / 95 %% sizes interpolated on the monotone fit (0: the "
                        "asked size only)")
    q.add_argument("--plot", default=None, metavar="F", help="power curves (.png or .svg)")
    q.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    add_json(q)
    add_force(q)
    add_sweep_options(q)
    q.set_defaults(handler=_cmd_design)
