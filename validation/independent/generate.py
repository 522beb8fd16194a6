"""Write the independent set: one folder per case with ``ensayo.mat`` and ``truth.json``, and
``manifest.json`` (the split, the expected answers).

    python -m validation.independent.generate --out DIR --seed S [--split tune|heldout|all]
                                              [--force]

``ensayo.mat`` is in the course format (MATLAB v5, scipy.io): ``tita`` (N×1, rad), ``datos``
(N×2, m/s², x column first) and, for runs whose timing is ``"t"``, ``t`` (N×1, s). A run
whose timing is ``"rate"`` has no ``t``: its samples are uniform at ``rate_hz`` (the scorer
passes ``--rate``). ``truth.json`` holds the answer expected of ``tiltbench gap`` and every
parameter; it is never inside the ``.mat``. The whole output is built in a temporary folder
beside DIR and moved into place at the end, so an error leaves nothing half written; an
existing non-empty DIR is kept unless ``--force``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np
import scipy.io

from .cases import CASES, FORMAT, HELDOUT_FRACTION, SPLIT_SALT, build, case_by_id, split_of

MANIFEST_FORMAT = "tiltbench-independent-manifest/1"


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o))


def write_case(folder: Path, motion, datos: np.ndarray, truth: dict) -> None:
    folder.mkdir(parents=True)
    mat = {"tita": motion.theta.reshape(-1, 1), "datos": np.asarray(datos, dtype=float)}
    if motion.timing == "t":
        mat["t"] = motion.t.reshape(-1, 1)
    scipy.io.savemat(folder / "ensayo.mat", mat, format="5", do_compression=False)
    text = json.dumps(truth, indent=1, default=_json_default, allow_nan=False,
                      ensure_ascii=False)
    (folder / "truth.json").write_text(text + "\n", encoding="utf-8")


def manifest(seed: int, split: str, truths: list[dict]) -> dict:
    written = {t["case_id"] for t in truths}
    return {
        "format": MANIFEST_FORMAT, "truth_format": FORMAT, "seed": seed, "written_split": split,
        "split_rule": {"salt": SPLIT_SALT, "heldout_fraction": HELDOUT_FRACTION,
                       "rule": "heldout iff int(sha256(salt:case_id)[:8]) / 2**64 < fraction"},
        "splits": {c.case_id: split_of(c.case_id) for c in CASES},
        "cases": [{"case_id": t["case_id"], "split": t["split"], "kind": t["kind"],
                   "what": t["what"], "axis": t["axis"], "design": t["design"],
                   "timing": t["timing"], "rate_hz": t["rate_hz"], "n": t["n"],
                   "noise_var": t["noise_var"], "expected": t["expected"],
                   "file": f"{t['case_id']}/ensayo.mat", "truth": f"{t['case_id']}/truth.json"}
                  for t in truths],
        "not_written": sorted(set(case_by_id()) - written),
        "units": {"seed": "—", "cases.rate_hz": "Hz", "cases.n": "count",
                  "cases.noise_var": "(m/s²)²", "split_rule.heldout_fraction": "1"},
    }


def generate(out: Path, seed: int, split: str = "all", force: bool = False) -> dict:
    """Write the cases of ``split`` (``tune``, ``heldout`` or ``all``) under ``out``; return
    the manifest."""
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
            motion, datos, truth = build(c, seed)
            write_case(tmp / c.case_id, motion, datos, truth)
            truths.append(truth)
        man = manifest(seed, split, truths)
        (tmp / "manifest.json").write_text(json.dumps(man, indent=1, default=_json_default,
                                                      ensure_ascii=False) + "\n",
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
    return man


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m validation.independent.generate",
                                description="Write the independent validation set "
                                "(ensayo.mat + truth.json per case, manifest.json).")
    p.add_argument("--out", required=True, type=Path, help="output directory")
    p.add_argument("--seed", type=int, default=0, help="seed of the set (default 0)")
    p.add_argument("--split", choices=("tune", "heldout", "all"), default="all",
                   help="which part to write (default all)")
    p.add_argument("--force", action="store_true", help="replace a non-empty --out")
    a = p.parse_args(argv)
    try:
        man = generate(a.out, a.seed, a.split, a.force)
    except FileExistsError as e:
        print(f"generate: error: {e}", file=sys.stderr)
        return 2
    n = {s: sum(c["split"] == s for c in man["cases"]) for s in ("tune", "heldout")}
    print(f"wrote {len(man['cases'])} cases to {a.out} (tune {n['tune']}, "
          f"heldout {n['heldout']}), seed {a.seed}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
