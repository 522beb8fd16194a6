"""What commands print and the checks they make on their outputs before any work.

``--json``: one JSON object on stdout and nothing else there (:func:`print_json`). Readable
output names every file the command wrote (:func:`print_summary`, :func:`print_files`).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T")


def print_json(obj: Any) -> None:
    """``obj`` as stable JSON (:func:`calib.io.dumps`) on stdout."""
    from calib.io import dumps

    print(dumps(obj), end="")


def print_summary(args: argparse.Namespace, title: str, summary: dict) -> None:
    """What a generate command wrote: one JSON object with ``--json``, else readable lines
    (the title, scalar entries as ``key: value``, nested mappings one entry per line)."""
    if args.json:
        print_json(summary)
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


def print_files(paths: Iterable[str | Path | None]) -> None:
    """``wrote: PATH`` for each file written (None entries: options not given)."""
    for p in paths:
        if p is not None:
            print(f"wrote: {p}")


def refuse_overwrite(paths: Iterable[str | Path | None], force: bool = False) -> None:
    """Check output files before any work, so that a refused run writes nothing.

    None entries are skipped. A directory is never a valid output file (ValueError); an
    existing file needs ``--force`` (FileExistsError, worded by ``main``).
    """
    for p in paths:
        if p is None:
            continue
        p = Path(p)
        if p.is_dir():
            raise ValueError(f"{p}: is a directory; expected an output file name")
        if p.exists() and not force:
            raise FileExistsError(f"{p}: exists")


def warnings_to_stderr(fn: Callable[[], T]) -> T:
    """Run ``fn``; print each warning it raised as ``warning: …`` on stderr (every time)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fn()
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    return result

