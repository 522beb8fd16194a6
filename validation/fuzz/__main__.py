"""``python -m validation.fuzz --out DIR --seed 0 [--jobs 2] [--kinds a,b] [--src PATH]``:
build the inputs, run every case, print the table by kind, write ``DIR/fuzz.json``."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from validation.fuzz.cases import KINDS, all_cases
from validation.fuzz.fixtures import build
from validation.fuzz.runner import FAULTS, WIDTH, Outcome, run_case

REPO = Path(__file__).resolve().parents[2]


def table(outcomes: list[Outcome]) -> str:
    """Cases and faults by kind (a case with several faults counts in each column)."""
    kinds = list(dict.fromkeys(o.kind for o in outcomes))
    wide = {k: max(13, len(k) + 1) for k in FAULTS}  # a space before every column's name
    head = f"{'kind':<12}{'cases':>6}{'clean':>6}" + "".join(f"{k:>{wide[k]}}" for k in FAULTS)
    rows = [head]
    for kind in [*kinds, "total"]:
        sel = [o for o in outcomes if kind in ("total", o.kind)]
        counts = [sum(k in o.faults for o in sel) for k in FAULTS]
        clean = sum(not o.faults for o in sel)
        rows.append(f"{kind:<12}{len(sel):>6}{clean:>6}"
                    + "".join(f"{c:>{wide[k]}}" for k, c in zip(FAULTS, counts, strict=True)))
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m validation.fuzz", description=__doc__)
    p.add_argument("--out", required=True, type=Path, help="work folder (inputs, cases, json)")
    p.add_argument("--seed", type=int, default=0, help="seed of the generated inputs")
    p.add_argument("--jobs", type=int, default=2, help="cases run at once")
    p.add_argument("--kinds", default=None,
                   help=f"comma-separated subset of {','.join(KINDS)}")
    p.add_argument("--match", default=None, help="only cases whose name contains this")
    p.add_argument("--src", type=Path, default=REPO,
                   help="source tree of bench/calib to test (default: this checkout)")
    args = p.parse_args(argv)
    env = {**os.environ, "PYTHONPATH": str(args.src.resolve()), "OPENBLAS_NUM_THREADS": "1",
           "RERUN_ANALYTICS": "0", "XDG_CONFIG_HOME": str(args.out.resolve() / "xdg"),
           "COLUMNS": "100"}
    out = args.out.resolve()
    t0 = time.monotonic()
    files = build(out / "base", args.seed, env)
    kinds = args.kinds.split(",") if args.kinds else None
    cases = [c for c in all_cases(files, kinds) if not args.match or args.match in c.name]
    print(f"inputs built in {time.monotonic() - t0:.0f} s; {len(cases)} cases", file=sys.stderr)

    def one(item):
        i, case = item
        o = run_case(case, out / "cases" / f"{i:03d}", env)
        mark = ",".join(o.faults) or "clean"
        print(f"[{i:03d}] {o.kind:<10} {o.seconds:6.1f} s {mark:<22} {o.name}",
              file=sys.stderr, flush=True)
        return o

    with ThreadPoolExecutor(max(1, args.jobs)) as pool:
        outcomes = list(pool.map(one, enumerate(cases)))
    text = table(outcomes)
    print(text)
    bad = [o for o in outcomes if o.faults]
    for o in bad:
        print(f"- {o.kind}: {o.name}: {','.join(o.faults)} (exit {o.codes}) {o.detail} "
              f"| {o.stderr_tail[:160]}")
    if outcomes:  # the widths of issue 29 (stderr and readable stdout)
        top = max(outcomes, key=lambda o: o.widest)
        word = max(outcomes, key=lambda o: o.widest_word)
        errors = [o for o in outcomes if 2 in o.codes]  # refused: exit 2
        top_error = max(errors, key=lambda o: o.widest, default=None)
        print(f"widest line: {top.widest} columns (limit {WIDTH}), in: {top.name}")
        if top_error is not None:
            print(f"widest line of the {len(errors)} refused cases (exit 2): "
                  f"{top_error.widest} columns, in: {top_error.name}")
        print(f"widest single word (a path, may exceed {WIDTH}): {word.widest_word} columns, "
              f"in: {word.name}")
    report = {"seed": args.seed, "src": str(args.src.resolve()),
              "seconds": round(time.monotonic() - t0, 1), "faults": list(FAULTS),
              "table": text, "cases": [o.to_dict() for o in outcomes]}
    (out / "fuzz.json").write_text(json.dumps(report, indent=1))
    print(f"wrote {out / 'fuzz.json'} ({report['seconds']} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
