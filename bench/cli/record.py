"""``tiltbench record read FILE.rrd [--json]`` and ``tiltbench record entities FILE.rrd
[--all] [--json]``."""

from __future__ import annotations

import argparse

from bench.cli.options import add_json
from bench.cli.output import print_json


def _flat(obj, prefix: str = "") -> list[tuple[str, object]]:
    if isinstance(obj, dict):
        return [kv for k in sorted(obj) for kv in _flat(obj[k], f"{prefix}/{k}" if prefix else k)]
    if isinstance(obj, list):
        return [kv for i, v in enumerate(obj) for kv in _flat(v, f"{prefix}/{i}")]
    return [(prefix, obj)]


def _cmd_read(args: argparse.Namespace) -> int:
    from bench.record import read_recording  # imports rerun: start-up time

    data = read_recording(args.file)
    if args.json:
        print_json(data)
        return 0
    for root, tree in data.items():
        if tree is None:
            print(f"{root}: (not in the recording)")
            continue
        print(f"{root}:")
        for k, v in _flat(tree):
            print(f"  {k} = {v!r}")
    return 0


def _cmd_entities(args: argparse.Namespace) -> int:
    from bench.record import documented, recording_entities  # imports rerun: start-up time

    rows = []
    for e in recording_entities(args.file):
        d = documented(e)
        if args.all or not (d and d.pattern.endswith("/**")):
            rows.append((str(e), d.pattern if d else None))
    if args.json:
        print_json({"file": str(args.file),
                    "entities": [{"path": e, "pattern": pat} for e, pat in rows]})
        return 0
    for e, pat in rows:
        print(f"{e}\t{pat or '(undocumented)'}")
    return 0


def register(sub) -> None:
    p = sub.add_parser("record", help="read rerun recordings written by tiltbench")
    kinds = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    r = kinds.add_parser("read", help="truth and estimates back from a .rrd")
    r.add_argument("file", help="recording (.rrd)")
    r.add_argument("--json", action="store_true",
                   help='print {"truth": ..., "estimates": ..., "trajectory": ...} as JSON')
    r.set_defaults(handler=_cmd_read)
    e = kinds.add_parser("entities", help="entity paths with their documented pattern")
    e.add_argument("file", help="recording (.rrd)")
    e.add_argument("--all", action="store_true", help="also list the JSON tree nodes")
    add_json(e)
    e.set_defaults(handler=_cmd_entities)
