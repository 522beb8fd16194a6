"""``tiltbench examples [DIR] [--force] [--json]``: the shipped datasets and docs pages.

The README's examples read ``data/…`` (small datasets made by the bench, ``data/README.md``)
and the commands' ``--help`` points to ``docs/…`` pages. A source checkout has both beside
``bench/``; a wheel carries them as package data, ``bench/data/`` and ``bench/docs/``
(``pyproject.toml`` maps one to the other, as for ``models/``). ``tiltbench examples DIR``
copies them to ``DIR/data/`` and ``DIR/docs/`` so that the README's examples run from any
directory after ``pip install``; without ``DIR`` it lists where they are installed.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bench.cli.options import add_command, add_force, add_json
from bench.cli.output import print_json

FOLDERS = ("data", "docs")
"""What is shipped, under the same names in a checkout, in a wheel (``bench/…``) and in DIR."""

_BENCH_DIR = Path(__file__).resolve().parent.parent

DESCRIPTION = """\
Copy the datasets the README's examples use (data/…: course, misalignment, sweep-lever-arm,
positions; data/README.md says what each holds) and the documentation pages the --help texts
refer to (docs/gap.md, docs/effects.md, docs/validate.md, docs/recordings.md,
docs/python-api.md) into DIR/data/ and DIR/docs/. Without DIR: print where they are installed.
Existing files are kept unless --force.
"""
"""What ``--help`` says before the options (argparse reflows it)."""


def source_dir(folder: str) -> Path:
    """Where ``folder`` (``data`` or ``docs``) is: installed as ``bench/FOLDER`` (a wheel) or
    beside ``bench/`` (a source checkout or an editable install)."""
    candidates = (_BENCH_DIR / folder, _BENCH_DIR.parent / folder)
    found = next((d for d in candidates if d.is_dir()), None)
    if found is None:
        raise FileNotFoundError(f"{candidates[0]}: the shipped {folder}/ folder is missing "
                                "(reinstall tiltbench)")
    return found


def shipped_files() -> dict[str, Path]:
    """Relative name (``data/misalignment/ensayo.mat``, ``docs/gap.md``) → installed file.
    Only what a wheel carries (no caches, no hidden files)."""
    out = {}
    for folder in FOLDERS:
        root = source_dir(folder)
        for p in sorted(root.rglob("*")):
            rel = p.relative_to(root)
            if p.is_file() and not any(part.startswith((".", "__")) for part in rel.parts):
                out[f"{folder}/{rel.as_posix()}"] = p
    return out


def write_examples(out_dir: str | Path, force: bool = False) -> list[Path]:
    """Copy every shipped file to ``out_dir`` (same relative names); the written paths.

    Every target is checked before anything is written: an existing file without ``force``
    is :class:`FileExistsError`, so a refused run writes nothing. Each file is written
    atomically (:func:`calib.files.atomic.write_bytes`).
    """
    from calib.files.atomic import write_bytes

    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise NotADirectoryError(20, "Not a directory", str(out_dir))
    files = shipped_files()
    targets = {rel: out_dir / rel for rel in files}
    for target in targets.values():
        if target.is_dir():
            raise ValueError(f"{target}: is a directory; expected an output file name")
        if target.exists() and not force:
            raise FileExistsError(f"{target}: exists")
    return [write_bytes(targets[rel], src.read_bytes(), force=force)
            for rel, src in files.items()]


def _cmd_examples(args: argparse.Namespace) -> int:
    if args.dir is None:  # where they are installed; nothing written
        files = shipped_files()
        if args.json:
            print_json({"installed": {f: str(src_dir) for f, src_dir in
                                      ((f, source_dir(f)) for f in FOLDERS)},
                        "files": {rel: str(p) for rel, p in files.items()}})
            return 0
        for folder in FOLDERS:
            print(f"{folder}/: {source_dir(folder)}")
        print("copy them with: tiltbench examples DIR")
        return 0
    written = write_examples(args.dir, force=args.force)
    if args.json:
        print_json({"dir": str(args.dir), "files": [str(p) for p in written]})
        return 0
    print(f"example datasets and docs pages in {args.dir} (datasets: "
          f"{Path(args.dir) / 'data' / 'README.md'})")
    for p in written:
        print(f"wrote: {p}")
    return 0


def register(sub) -> None:
    p = add_command(sub, "examples", _cmd_examples, description=DESCRIPTION, help="write the "
                    "example datasets (data/) and the docs pages (docs/) to DIR")
    p.add_argument("dir", nargs="?", metavar="DIR", help="output folder (created if needed)")
    add_force(p, "existing files in DIR")
    add_json(p)
