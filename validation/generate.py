"""Write the validation set as course-format files: ``python -m validation.generate OUTDIR``.

Each case becomes ``OUTDIR/<id>.mat`` (``tita`` N×1 rad, ``datos`` N×2 m/s², ``t`` N×1 s when
timed; ``scipy.io.savemat``, MATLAB v5 like the course file) and ``OUTDIR/truth.json`` holds,
per case id, the expected names, every true parameter, the sizes in σ and ``noise_var``.
Run the analysis on one file with ``tiltbench gap OUTDIR/<id>.mat --noise-var 0.25,0.64``.
An existing OUTDIR with files in it is refused unless ``--force``.
"""

from __future__ import annotations

import argparse
import io
import json
import sys
from pathlib import Path

import numpy as np
import scipy.io

from validation.cases import Case, validation_set

FORMAT_VERSION = 1
HEADER_TEXT = 116
"""Length of the descriptive text at the start of a MATLAB v5 file, bytes."""


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, float) and not np.isfinite(obj):
        return None if np.isnan(obj) else ("inf" if obj > 0 else "-inf")
    return obj


def write_case(case: Case, outdir: Path) -> Path:
    """``outdir/<id>.mat`` in the course format; returns its path."""
    mat = {"tita": np.asarray(case.tita).reshape(-1, 1), "datos": np.asarray(case.datos)}
    if case.t is not None:
        mat["t"] = np.asarray(case.t).reshape(-1, 1)
    path = outdir / f"{case.id}.mat"
    buf = io.BytesIO()
    scipy.io.savemat(buf, mat, format="5", do_compression=False, oned_as="column")
    data = bytearray(buf.getvalue())
    # scipy stamps the 116-byte descriptive text with the time: replace it (same seed, same bytes)
    text = f"MATLAB 5.0 MAT-file, tiltbench validation case {case.id}".encode("ascii")
    data[:HEADER_TEXT] = text[:HEADER_TEXT].ljust(HEADER_TEXT, b" ")
    path.write_bytes(bytes(data))
    return path


def write_set(cases: list[Case], outdir: str | Path, seed: int, force: bool = False) -> Path:
    """Write every case and ``truth.json``; refuse a non-empty ``outdir`` unless ``force``."""
    outdir = Path(outdir)
    if outdir.exists() and any(outdir.iterdir()) and not force:
        raise FileExistsError(f"{outdir} is not empty; pass --force to overwrite")
    outdir.mkdir(parents=True, exist_ok=True)
    for case in cases:
        write_case(case, outdir)
    truth = {"format_version": FORMAT_VERSION, "seed": seed,
             "units": {"tita": "rad", "datos": "m/s^2", "t": "s", "noise_var": "(m/s^2)^2"},
             "size_definition": "see validation/sizes.py",
             "cases": {c.id: _jsonable(c.to_truth()) for c in cases}}
    path = outdir / "truth.json"
    path.write_text(json.dumps(truth, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m validation.generate",
                                     description="Write the validation set (.mat + truth.json).")
    parser.add_argument("outdir", help="output directory")
    parser.add_argument("--seed", type=int, default=0, help="seed of the set (default 0)")
    parser.add_argument("--clean", type=int, default=22, help="number of clean runs")
    parser.add_argument("--force", action="store_true", help="overwrite a non-empty OUTDIR")
    args = parser.parse_args(argv)
    out = Path(args.outdir)
    if out.exists() and any(out.iterdir()) and not args.force:  # before the work
        sys.stderr.write(f"error: {out} is not empty; pass --force to overwrite\n")
        return 1
    try:
        path = write_set(validation_set(args.seed, args.clean), args.outdir, args.seed,
                         args.force)
    except FileExistsError as exc:
        sys.stderr.write(f"error: {exc}\n")
        return 1
    sys.stdout.write(f"wrote {path.parent} ({path.name} and the .mat files)\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
