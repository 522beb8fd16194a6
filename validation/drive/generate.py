"""Write the drive part: one folder per case with its file (``ensayo.mat`` or ``log.csv``,
``datos.txt`` when the noise is stated that way) and ``truth.json``, plus ``manifest.json``.

    python -m validation.drive.generate --out DIR --seed S [--split tune|heldout|all] [--force]

``truth.json`` holds the expected answer of ``tiltbench gap``, every parameter, the sizes and
the options to run it with (``options``, ``gap_args``); it is never inside the case's file.
The output is built in a temporary folder beside DIR and moved into place at the end (an
error leaves nothing half written); a non-empty DIR is kept unless ``--force``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from . import files
from .cases import (
    CASES,
    CATEGORIES,
    FORMAT,
    HELDOUT_FRACTION,
    SPLIT_SALT,
    build,
    case_by_id,
    split_of,
)

MANIFEST_FORMAT = "tiltbench-drive-manifest/1"


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o))


def dumps(obj) -> str:
    return json.dumps(obj, indent=1, default=_json_default, allow_nan=False,
                      ensure_ascii=False) + "\n"


def write_case(folder: Path, mo, datos: np.ndarray, truth: dict) -> None:
    folder.mkdir(parents=True)
    files.write(folder, {"file": truth["file"], "options": truth["options"]}, mo.theta,
                mo.time, datos, mo.timing, truth["noise_var"])
    (folder / "truth.json").write_text(dumps(truth), encoding="utf-8")


def counts(rows: list[dict]) -> dict:
    out = {}
    for cat in CATEGORIES:
        sel = [r for r in rows if r["category"] == cat]
        out[cat] = {s: sum(r["split"] == s for r in sel) for s in ("tune", "heldout")}
    clean = [r for r in rows if r["category"] == "clean"]
    out["clean_by_format"] = {f: {s: sum(r["fmt"] == f and r["split"] == s for r in clean)
                                  for s in ("tune", "heldout")}
                              for f in ("mat", "csv_ms2", "csv_counts")}
    return out


def manifest(seed: int, split: str, truths: list[dict]) -> dict:
    written = {t["case_id"] for t in truths}
    every = [{"category": c.category, "fmt": c.fmt, "split": split_of(c.case_id)}
             for c in CASES]
    return {
        "format": MANIFEST_FORMAT, "truth_format": FORMAT, "seed": seed, "written_split": split,
        "split_rule": {"salt": SPLIT_SALT, "heldout_fraction": HELDOUT_FRACTION,
                       "rule": "heldout iff int(sha256(salt + ':' + case_id).hexdigest()[:8], "
                               "16) / 2**32 < heldout_fraction, else tune"},
        "splits": {c.case_id: split_of(c.case_id) for c in CASES},
        "counts_all_cases": counts(every),
        "cases": [{"case_id": t["case_id"], "split": t["split"], "category": t["category"],
                   "what": t["what"], "axis": t["axis"], "design": t["design"],
                   "timing": t["timing"], "n": t["n"], "format": t["file"]["format"],
                   "expected": t["expected"]["verdict"],
                   "file": f"{t['case_id']}/{t['file']['name']}",
                   "truth": f"{t['case_id']}/truth.json"} for t in truths],
        "not_written": sorted(set(case_by_id()) - written),
        "units": {"cases.n": "count", "split_rule.heldout_fraction": "1"},
    }


def generate(out: Path, seed: int, split: str = "all", force: bool = False,
             only: list[str] | None = None) -> dict:
    """Write the cases of ``split`` (``tune``, ``heldout``, ``all``; ``only``: these ids)
    under ``out``; return the manifest."""
    out = Path(out)
    if out.exists() and any(out.iterdir()) and not force:
        raise FileExistsError(f"{out} is not empty: pass --force to replace it")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    try:
        truths = []
        for c in CASES:
            if split != "all" and split_of(c.case_id) != split:
                continue
            if only is not None and c.case_id not in only:
                continue
            mo, datos, truth = build(c, seed)
            write_case(tmp / c.case_id, mo, datos, truth)
            truths.append(truth)
        (tmp / "manifest.json").write_text(dumps(manifest(seed, split, truths)),
                                           encoding="utf-8")
        if out.exists():
            old = out.with_name(f".{out.name}.old")
            shutil.rmtree(old, ignore_errors=True)
            os.replace(out, old)
            os.replace(tmp, out)
            shutil.rmtree(old)
        else:
            os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return json.loads((out / "manifest.json").read_text(encoding="utf-8"))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m validation.drive.generate",
                                description="Write the drive validation part (a file and "
                                "truth.json per case, manifest.json).")
    p.add_argument("--out", required=True, type=Path, help="output directory")
    p.add_argument("--seed", type=int, default=0, help="seed of the set (default 0)")
    p.add_argument("--split", choices=("tune", "heldout", "all"), default="all",
                   help="which part to write (default all)")
    p.add_argument("--force", action="store_true", help="replace a non-empty --out")
    a = p.parse_args(argv)
    t0 = time.perf_counter()
    try:
        man = generate(a.out, a.seed, a.split, a.force)
    except FileExistsError as e:
        print(f"generate: error: {e}", file=sys.stderr)
        return 2
    n = {s: sum(c["split"] == s for c in man["cases"]) for s in ("tune", "heldout")}
    per = {cat: sum(c["category"] == cat for c in man["cases"]) for cat in CATEGORIES}
    print(f"wrote {len(man['cases'])} cases to {a.out} (tune {n['tune']}, heldout "
          f"{n['heldout']}; " + ", ".join(f"{k} {v}" for k, v in per.items())
          + f"), seed {a.seed}, {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
