"""Score ``tiltbench gap`` on the independent set, per split.

    python -m validation.independent.score DIR [--split tune|heldout|all] [--jobs 2]
                                               [--table FILE.md] [--json FILE.json]

Every case of DIR's ``manifest.json`` (of the chosen split) is analysed by the command line,
in a subprocess: ``python -m bench.cli gap FILE --noise-var SX,SY --json`` (+ ``--rate HZ``
for uniform runs stored without ``t``), at most two at a time. The scorer reads the JSON and
the truth; it imports neither ``bench`` nor ``calib``.

Scores (per split, and all together):

* **catalog named right**: verdict ``explained`` and the named (effect, axis) set equals the
  truth's (``tilt_offset`` on ``both``; an effect on both axes is two names). Also given:
  *catalog named* — the true names are among those named, whatever else.
* **false alarms**: clean runs and a changed local g (absorbed by the scale factors) with a
  verdict other than ``nothing_detected`` or any effect named.
* **out of catalog reported**: verdict ``unexplained``, or effects named while a per-axis gap
  after is flagged (``consistent: false``) — the issue's rule.
* **contradictions**: verdict ``explained`` while a per-axis gap after is flagged. Listed
  beside it, **silent flags**: verdict ``nothing_detected`` while a per-axis gap after is
  flagged (the verdict says nothing, the yardstick says something).
* **errors**: the command failed (exit code, no JSON); counted as wrong.
* beside the scores, **catalog params within 4 std**: the named true effects whose estimates
  lie within 4 std of the truth (signs and units of docs/effects.md checked end to end).

The held-out split is for reporting only: nothing in the generator, the sizes or the
detector may be tuned on it (README.md).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

MAX_JOBS = 2


def gap_command(case: dict, root: Path) -> list[str]:
    cmd = [sys.executable, "-m", "bench.cli", "gap", str(root / case["file"]), "--noise-var",
           ",".join(repr(float(v)) for v in case["noise_var"]), "--json"]
    if case["timing"] == "rate":
        cmd += ["--rate", repr(float(case["rate_hz"]))]
    return cmd


def run_case(case: dict, root: Path, timeout: float = 900.0) -> dict:
    """Run the command on one case: {"rc", "seconds", "result" (JSON or None), "stderr"}."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    t0 = time.perf_counter()
    try:
        p = subprocess.run(gap_command(case, root), capture_output=True, text=True, env=env,
                           timeout=timeout, check=False)
        rc, out, err = p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        rc, out, err = -1, "", f"timeout after {timeout} s"
    seconds = time.perf_counter() - t0
    try:
        result = json.loads(out) if rc == 0 else None
    except json.JSONDecodeError:
        result = None
    return {"rc": rc, "seconds": seconds, "result": result,
            "stderr": err.strip().splitlines()[-1] if err.strip() else ""}


def judge(case: dict, run: dict) -> dict:
    """One row of the per-case table: what was expected, what was said, and the marks."""
    res = run["result"]
    row = {"case_id": case["case_id"], "split": case["split"], "kind": case["kind"],
           "what": case["what"], "axis": case["axis"], "design": case["design"],
           "timing": case["timing"], "n": case["n"],
           "expected": case["expected"]["verdict"], "seconds": round(run["seconds"], 1)}
    if res is None:
        return {**row, "verdict": "error", "named": [], "flagged_after": [], "ok": False,
                "contradiction": False, "silent_flag": False, "error": run["stderr"]}
    named = sorted({(e["name"], e["axis"]) for e in res.get("effects", [])})
    flagged = sorted(ax for ax, g in res.get("gap_after", {}).items()
                     if not g.get("consistent", True))
    verdict = res.get("verdict")
    want = sorted({(e["name"], e["axis"]) for e in case["expected"]["effects"]})
    kind = case["kind"]
    if kind == "catalog":
        ok = verdict == "explained" and named == want
        loose = bool(want) and set(want) <= set(named)
    elif kind in ("clean", "absorbed"):
        ok = verdict == "nothing_detected" and not named
        loose = ok
    else:
        ok = verdict == "unexplained" or (bool(named) and bool(flagged))
        loose = ok
    return {**row, "verdict": verdict, "named": [f"{n}:{a}" for n, a in named],
            "param_z": param_z(case, res),
            "flagged_after": flagged, "ok": ok, "loose": loose,
            "contradiction": verdict == "explained" and bool(flagged),
            "silent_flag": verdict == "nothing_detected" and bool(flagged),
            "unexplained": [u.get("description", "") for u in res.get("unexplained", [])][:3]}


def param_z(case: dict, res: dict) -> float | None:
    """Largest |estimate − truth| / std over the true effects' parameters that the output
    gives (None when none is given): a check of the signs and units of docs/effects.md, not
    part of the scores (a walk's q is set on its drawn path, so its estimate may differ)."""
    worst = None
    got = {(e["name"], e["axis"]): e for e in res.get("effects", [])}
    for eff in case["expected"]["effects"]:
        e = got.get((eff["name"], eff["axis"]))
        if e is None:
            continue
        for key, true in eff["params"].items():
            est, std = e.get("params", {}).get(key), e.get("std", {}).get(key)
            if est is None or not std:
                continue
            z = abs(est - true) / std
            worst = z if worst is None else max(worst, z)
    return worst


def summarize(rows: list[dict]) -> dict:
    def frac(sel, key="ok"):
        return {"hits": sum(r[key] for r in sel), "of": len(sel)}
    cat = [r for r in rows if r["kind"] == "catalog"]
    clean = [r for r in rows if r["kind"] in ("clean", "absorbed")]
    ooc = [r for r in rows if r["kind"] == "out_of_catalog"]
    return {
        "catalog_named_right": frac(cat),
        "catalog_named": frac(cat, "loose"),
        "catalog_params_within_4_std": {
            "hits": sum(r.get("param_z") is not None and r["param_z"] <= 4 for r in cat),
            "of": sum(r.get("param_z") is not None for r in cat)},
        "false_alarms": {"hits": sum(not r["ok"] for r in clean), "of": len(clean)},
        "out_of_catalog_reported": frac(ooc),
        "contradictions": {"hits": sum(r["contradiction"] for r in rows), "of": len(rows)},
        "silent_flags": {"hits": sum(r["silent_flag"] for r in rows), "of": len(rows)},
        "errors": {"hits": sum(r["verdict"] == "error" for r in rows), "of": len(rows)},
        "seconds": round(sum(r["seconds"] for r in rows), 1),
    }


def score(root: Path, split: str = "all", jobs: int = MAX_JOBS,
          progress=None) -> tuple[dict, list[dict]]:
    """Run and judge every case of ``split`` under ``root``: (summary per split, rows)."""
    man = json.loads((Path(root) / "manifest.json").read_text(encoding="utf-8"))
    cases = [c for c in man["cases"] if split == "all" or c["split"] == split]
    jobs = max(1, min(jobs, MAX_JOBS))
    rows: list[dict] = []
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        for case, run in zip(cases, pool.map(lambda c: run_case(c, Path(root)), cases),
                             strict=True):
            rows.append(judge(case, run))
            if progress:
                progress(rows[-1])
    summary = {s: summarize([r for r in rows if r["split"] == s])
               for s in ("tune", "heldout") if any(r["split"] == s for r in rows)}
    summary["all"] = summarize(rows)
    summary["seed"] = man["seed"]
    return summary, rows


def _pct(d: dict) -> str:
    return f"{d['hits']}/{d['of']}" + (f" ({100 * d['hits'] / d['of']:.0f} %)" if d["of"] else "")


def _num(x) -> str:
    return "—" if x is None else f"{x:.1f}"


def markdown(summary: dict, rows: list[dict]) -> str:
    keys = ("catalog_named_right", "catalog_named", "catalog_params_within_4_std",
            "false_alarms", "out_of_catalog_reported",
            "contradictions", "silent_flags", "errors")
    splits = [s for s in ("tune", "heldout", "all") if s in summary]
    lines = [f"# tiltbench gap on the independent set (seed {summary['seed']})", "",
             "| score | " + " | ".join(splits) + " |", "|---|" + "---|" * len(splits)]
    for k in keys:
        lines.append(f"| {k.replace('_', ' ')} | "
                     + " | ".join(_pct(summary[s][k]) for s in splits) + " |")
    lines += ["", "| case | split | expected | verdict | named | flagged after | ok "
              "| max abs(est − true)/std | s |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        mark = "yes" if r["ok"] else "**no**"
        if r["contradiction"]:
            mark += " (contradiction)"
        lines.append(f"| {r['case_id']} | {r['split']} | {r['expected']} | {r['verdict']} | "
                     f"{', '.join(r['named']) or '—'} | {', '.join(r['flagged_after']) or '—'}"
                     f" | {mark} | {_num(r.get('param_z'))} | {r['seconds']} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m validation.independent.score",
                                description="Run tiltbench gap on the independent set and "
                                "score it per split (markdown summary on stdout).")
    p.add_argument("root", type=Path, help="folder written by validation.independent.generate")
    p.add_argument("--split", choices=("tune", "heldout", "all"), default="all")
    p.add_argument("--jobs", type=int, default=MAX_JOBS, help="parallel runs (at most 2)")
    p.add_argument("--table", type=Path, help="write the summary and per-case table (.md)")
    p.add_argument("--json", type=Path, help="write the summary and rows as JSON")
    a = p.parse_args(argv)

    def progress(r):
        print(f"[score] {r['case_id']}: {r['verdict']} {'ok' if r['ok'] else 'WRONG'} "
              f"({r['seconds']} s)", file=sys.stderr)
    summary, rows = score(a.root, a.split, a.jobs, progress)
    text = markdown(summary, rows)
    if a.table:
        a.table.write_text(text, encoding="utf-8")
    if a.json:
        a.json.write_text(json.dumps({"summary": summary, "rows": rows}, indent=1,
                                     ensure_ascii=False) + "\n", encoding="utf-8")
    print(text.split("\n\n| case")[0])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
