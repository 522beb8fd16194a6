"""``tiltbench fusion-study``: the thesis comparison on the course geometry (issue 13, part 5).

    tiltbench fusion-study [--out DIR] [--runs R] [--seed S] [--workers K | --scheduler ADDR]
                           [--json] [--force]

Dead reckoning, fixes alone, Kalman filter and RTS smoother, per scenario (IMU 100/50 Hz,
fixes 1/10 Hz, 20 s outage at the end, P0/Q/R mis-set ×10 and ÷10): RMS error along the path
(m), stated final std (m), 99.7 % region area (m²), mean final NEES with its χ² band, the
region's coverage, and the NEES along the path (share of fix epochs out of the per-epoch
Bonferroni band, where, and "consistent along the path" yes/no) (:mod:`bench.fusion_study`,
docs/fusion.md). Prints the table (or ``--json``) and
writes ``fusion-study.md`` and ``fusion-study.png`` into ``--out`` (default
``fusion-study``), refusing to overwrite without ``--force``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bench.cli.options import add_command, add_force, add_sweep_options, check_count, integer
from bench.cli.output import check_finite, print_files, print_json
from bench.cli.vocabulary import add_option

FILES = ("fusion-study.md", "fusion-study.png")


def _cmd_fusion_study(args: argparse.Namespace) -> int:
    from bench import fusion_study
    from bench.cli.options import mapper_from_args
    from bench.cli.progress import Progress
    from calib.files.atomic import atomic_dir

    check_count(args.runs, "--runs", 2)
    out = Path(args.out)
    clash = [n for n in FILES if (out / n).exists()]
    if clash and not args.force:
        from bench.cli.options import OptionError

        raise OptionError(f"--out {out}: {', '.join(clash)} already exist(s); pass --force "
                          "to replace them")
    progress = Progress("fusion-study", quiet=args.quiet)
    config = fusion_study.StudyConfig(runs=args.runs, seed=args.seed,
                                      scenarios=fusion_study.SCENARIOS)
    res = fusion_study.run_study(config, mapper_from_args(args),
                    progress, lambda done, total: progress.count(done, total, "tasks"))
    d = res.to_dict()
    check_finite(d, "the result")
    from bench.figures.fusion_study import fusion_study_figure
    from bench.figures.save import save_figure

    with atomic_dir(out, args.force, owned=FILES) as tmp:
        (tmp / FILES[0]).write_text(res.markdown(), encoding="utf-8")
        save_figure(fusion_study_figure(res), tmp / FILES[1], force=True)
    if args.json:
        print_json({**d, "files": [str(out / n) for n in FILES]})
        return 0
    print(res.summary())
    print_files([out / n for n in FILES])
    return 0


def register(sub) -> None:
    p = add_command(sub, "fusion-study", _cmd_fusion_study, help="dead reckoning vs fixes vs "
                    "Kalman filter vs smoother on the course geometry (docs/fusion.md)")
    add_option(p, "--out", default="fusion-study",
               help="folder for fusion-study.md and fusion-study.png")
    add_option(p, "--runs", type=integer, default=200,
               help="Monte Carlo runs per scenario (200: a NEES band of about ±0.6 around 2)")
    add_option(p, "--seed", type=int, default=0, help="seed of the runs")
    add_option(p, "--json", help="print one JSON object (units map)")
    add_option(p, "--quiet")
    add_sweep_options(p)
    add_force(p, "fusion-study.md and fusion-study.png in --out")
