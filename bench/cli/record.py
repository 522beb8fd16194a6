"""``tiltbench record read FILE.rrd [--json]`` and ``tiltbench record entities FILE.rrd
[--all] [--json]``."""

from __future__ import annotations

import argparse

from bench.cli.options import add_command, add_json
from bench.cli.output import print_json
from bench.cli.vocabulary import add_option


def _flat(obj, prefix: str = "", key: str = "") -> list[tuple[str, str, object]]:
    """``(path, key path, value)`` of every leaf: ``path`` joins keys and list indices with
    ``/`` (as printed), ``key path`` joins keys only with ``.`` (as in a ``units`` map,
    :mod:`calib.units`)."""
    if isinstance(obj, dict):
        return [kv for k in sorted(obj) for kv in _flat(
            obj[k], f"{prefix}/{k}" if prefix else k, f"{key}.{k}" if key else k)]
    if isinstance(obj, list):
        return [kv for i, v in enumerate(obj) for kv in _flat(v, f"{prefix}/{i}", key)]
    return [(prefix, key, obj)]


def _shown(value: object, unit: str | None) -> str:
    """A leaf as printed: its repr, then its unit (none for text, counts and ratios)."""
    text = repr(value)
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return text
    if unit == "1":
        return text + " (dimensionless)"
    return text + (f" {unit}" if unit and unit not in ("count", "—") else "")


def _cmd_read(args: argparse.Namespace) -> int:
    from bench.record import read_recording  # imports rerun: start-up time

    data = read_recording(args.file)
    if args.json:
        print_json(data)
        return 0
    from calib.units import UNITS_KEY, unit_of

    for root, tree in data.items():
        if tree is None:
            print(f"{root}: (not in the recording)")
            continue
        print(f"{root}:" + ("" if isinstance(tree, dict) and UNITS_KEY in tree else
                            "  (no units map: numbers in SI, docs/units.md)"))
        units = tree.get(UNITS_KEY, {}) if isinstance(tree, dict) else {}
        body = {k: v for k, v in tree.items() if k != UNITS_KEY} if units else tree
        seen: dict[str, int] = {}  # leaves so far per key path: the entry of a list unit
        for path, key, v in _flat(body):
            unit = unit_of(units, key)
            k = seen[key] = seen.get(key, -1) + 1
            if unit and unit.startswith("[") and unit.endswith("]"):  # one unit per entry
                entries = unit[1:-1].split(", ")
                unit = entries[k] if k < len(entries) else None
            print(f"  {path} = {_shown(v, unit)}")
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
    r = add_command(kinds, "read", _cmd_read, help="truth and estimates back from a .rrd")
    r.add_argument("file", help="recording (.rrd)")
    add_option(r, "--json", help='print {"truth": ..., "estimates": ..., "trajectory": ...} '
               "as JSON")
    e = add_command(kinds, "entities", _cmd_entities,
                    help="entity paths with their documented pattern")
    e.add_argument("file", help="recording (.rrd)")
    add_option(e, "--all")
    add_json(e)
