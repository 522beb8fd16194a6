"""Score ``tiltbench gap`` on the drive part, per category and split.

    python -m validation.drive.score DIR [--split tune|heldout|all] [--jobs N]
                                         [--table FILE.md] [--json FILE.json]
                                         [--category C ...] [--max-clean K]
                                         [--outputs DIR [--reuse]]

Every case of DIR's ``manifest.json`` (of the chosen split) is run as a user would run it: the
``tiltbench`` command in a subprocess, ``tiltbench gap FILE <options> --json`` with the
options of its ``truth.json`` (``--noise-var`` or ``--datos``; ``--rate`` for a file without
t; ``--columns``, ``--units``, ``--sensitivity`` for CSV logs), at most two at a time. The
scorer reads the JSON and the truth; it imports neither ``bench`` nor ``calib``.

Scores (per split):

* ``drive_state`` **reported**: verdict ``unexplained``; **worded**: reported and one of its
  unexplained descriptions says it happens while the table moves (truth ``expected.words``).
* ``step_like`` **reported**: verdict ``unexplained``; **worded**: a description speaks of two
  levels / switching (telegraph) or steps (step, staircase) and none of "1/f".
* ``nil`` **right**: verdict ``nothing_detected`` and nothing named.
* ``clean`` **false alarms**: a verdict other than ``nothing_detected`` or any effect named;
  also per file format (course ``.mat``, CSV in m/s², CSV in raw counts).
* ``catalog`` **named right**: verdict ``explained`` and the named (effect, axis) set equals
  the truth's; **named**: the true names among those named; **params within 4 std**.
* over every case: **gap made worse** — an axis whose χ²/dof after exceeds χ²/dof before by
  more than 4·√(2/dof) (four times its spread under the null), both as ``gap_before`` /
  ``gap_after`` of the JSON give them; **contradictions** — verdict ``explained`` while a
  per-axis gap after is flagged (``consistent: false``); **silent flags** — verdict
  ``nothing_detected`` while a per-axis gap after is flagged; **errors** (no JSON).

``--max-clean K`` scores only the first K clean runs of the split (in case-id order) — for a
quick look; a reported false-alarm rate should use them all. The held-out split is for
reporting only: nothing may be tuned on it (README.md).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from .files import gap_args

MAX_JOBS = 2
CATEGORIES = ("drive_state", "step_like", "nil", "clean", "catalog")
WORSE_SPREADS = 4.0


def tiltbench() -> list[str]:
    """The ``tiltbench`` entry point of this Python (the one a user of this venv types)."""
    here = Path(sys.executable).parent / "tiltbench"
    if here.exists():
        return [str(here)]
    found = shutil.which("tiltbench")
    return [found] if found else [sys.executable, "-m", "bench.cli"]


def gap_command(truth: dict, folder: Path) -> list[str]:
    """``tiltbench gap FILE <the truth's options> --json`` (:func:`.files.gap_args`)."""
    return [*tiltbench(), "gap", str(folder / truth["file"]["name"]),
            *gap_args(truth["options"], folder), "--json"]


def run_case(truth: dict, folder: Path, timeout: float = 900.0) -> dict:
    """{"rc", "seconds", "result" (JSON or None), "stderr" (last line)}."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    t0 = time.perf_counter()
    try:
        p = subprocess.run(gap_command(truth, folder), capture_output=True, text=True, env=env,
                           timeout=timeout, check=False)
        rc, out, err = p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        rc, out, err = -1, "", f"timeout after {timeout} s"
    try:
        result = json.loads(out) if rc == 0 else None
    except json.JSONDecodeError:
        result = None
    return {"rc": rc, "seconds": time.perf_counter() - t0, "result": result,
            "stderr": err.strip().splitlines()[-1] if err.strip() else ""}


def detector() -> dict:
    """Which ``tiltbench`` was scored: its ``--version`` and the folder its ``bench`` package
    is imported from (PYTHONPATH may point at a snapshot of another commit)."""
    env = {**os.environ}
    try:
        version = subprocess.run([*tiltbench(), "--version"], capture_output=True, text=True,
                                 env=env, timeout=120, check=False).stdout.strip()
    except (OSError, subprocess.TimeoutExpired):
        version = ""
    code = "import bench, pathlib; print(pathlib.Path(bench.__file__).parents[1])"
    try:
        where = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                               env=env, timeout=120, check=False, cwd="/").stdout.strip()
    except (OSError, subprocess.TimeoutExpired):
        where = ""
    return {"version": version, "source": where, "pythonpath": env.get("PYTHONPATH", "")}


def descriptions(res: dict) -> list[str]:
    out = []
    for u in res.get("unexplained", []) or []:
        out.append(" ".join(str(u.get(k, "")) for k in ("description", "reason", "signature")))
    return out


def worded(truth: dict, res: dict) -> bool:
    words = truth["expected"].get("words") or {}
    texts = descriptions(res)
    if not texts:
        return False
    hit = any(re.search(p, t) for p in words.get("any", []) for t in texts)
    bad = any(re.search(p, t) for p in words.get("none", []) for t in texts)
    return hit and not bad


def axis_gaps(res: dict) -> dict:
    """Per axis (χ²/dof before, after, dof, worse?) from gap_before / gap_after."""
    out = {}
    before, after = res.get("gap_before", {}) or {}, res.get("gap_after", {}) or {}
    for ax in ("x", "y"):
        b, a = before.get(ax) or {}, after.get(ax) or {}
        cb, ca = b.get("chi2_dof"), a.get("chi2_dof")
        dof = (a.get("details") or {}).get("dof") or (b.get("details") or {}).get("dof")
        if cb is None or ca is None or not dof:
            continue
        limit = WORSE_SPREADS * (2.0 / dof) ** 0.5
        out[ax] = {"before": cb, "after": ca, "dof": dof, "worse": ca - cb > limit}
    return out


def param_z(truth: dict, res: dict) -> float | None:
    """Largest |estimate − truth| / std over the true effects' parameters given."""
    worst = None
    got = {(e["name"], e["axis"]): e for e in res.get("effects", [])}
    for eff in truth["expected"]["effects"]:
        e = got.get((eff["name"], eff["axis"]))
        if e is None:
            continue
        for key, true in eff["params"].items():
            est, std = (e.get("params") or {}).get(key), (e.get("std") or {}).get(key)
            if est is None or not std:
                continue
            z = abs(est - true) / std
            worst = z if worst is None else max(worst, z)
    return worst


def judge(truth: dict, run: dict) -> dict:
    """One row of the per-case table."""
    row = {"case_id": truth["case_id"], "split": truth["split"], "category": truth["category"],
           "what": truth["what"], "axis": truth["axis"], "design": truth["design"],
           "timing": truth["timing"], "format": truth["file"]["format"]
           + ("_counts" if truth["file"].get("units") == "counts" else ""),
           "n": truth["n"], "z": (truth.get("size") or {}).get("z_target"),
           "expected": truth["expected"]["verdict"], "seconds": round(run["seconds"], 1)}
    res = run["result"]
    if res is None:
        return {**row, "verdict": "error", "named": [], "flagged_after": [], "ok": False,
                "loose": False, "worded": False, "contradiction": False,
                "silent_flag": False, "worse": [], "gaps": {}, "param_z": None,
                "unexplained": [], "error": run["stderr"]}
    named = sorted({(e["name"], e["axis"]) for e in res.get("effects", [])})
    flagged = sorted(ax for ax, g in (res.get("gap_after") or {}).items()
                     if isinstance(g, dict) and g.get("consistent") is False)
    verdict = res.get("verdict")
    want = sorted({(e["name"], e["axis"]) for e in truth["expected"]["effects"]})
    cat = truth["category"]
    if cat == "catalog":
        ok = verdict == "explained" and named == want
        loose = bool(want) and set(want) <= set(named)
    elif cat in ("clean", "nil"):
        ok = verdict == "nothing_detected" and not named
        loose = ok
    else:
        ok = verdict == "unexplained"
        loose = ok or (bool(named) and bool(flagged))
    gaps = axis_gaps(res)
    return {**row, "verdict": verdict, "named": [f"{n}:{a}" for n, a in named],
            "flagged_after": flagged, "ok": ok, "loose": loose,
            "worded": ok and cat in ("drive_state", "step_like") and worded(truth, res),
            "contradiction": verdict == "explained" and bool(flagged),
            "silent_flag": verdict == "nothing_detected" and bool(flagged),
            "worse": sorted(ax for ax, g in gaps.items() if g["worse"]), "gaps": gaps,
            "param_z": param_z(truth, res) if cat == "catalog" else None,
            "unexplained": [d[:160] for d in descriptions(res)][:3]}


def _frac(rows, key="ok") -> dict:
    return {"hits": sum(bool(r[key]) for r in rows), "of": len(rows)}


def summarize(rows: list[dict]) -> dict:
    by = {c: [r for r in rows if r["category"] == c] for c in CATEGORIES}
    clean = by["clean"]
    cat = by["catalog"]
    return {
        "drive_state_reported": _frac(by["drive_state"]),
        "drive_state_worded": _frac(by["drive_state"], "worded"),
        "step_like_reported": _frac(by["step_like"]),
        "step_like_worded": _frac(by["step_like"], "worded"),
        "nil_right": _frac(by["nil"]),
        "clean_false_alarms": {"hits": sum(not r["ok"] for r in clean), "of": len(clean)},
        **{f"clean_false_alarms_{f}": {"hits": sum(not r["ok"] for r in clean
                                                   if r["format"] == f),
                                       "of": sum(r["format"] == f for r in clean)}
           for f in ("course", "csv", "csv_counts")},
        "catalog_named_right": _frac(cat),
        "catalog_named": _frac(cat, "loose"),
        "catalog_params_within_4_std": {
            "hits": sum(r["param_z"] is not None and r["param_z"] <= 4 for r in cat),
            "of": sum(r["param_z"] is not None for r in cat)},
        "gap_made_worse": {"hits": sum(bool(r["worse"]) for r in rows), "of": len(rows)},
        "contradictions": _frac(rows, "contradiction"),
        "silent_flags": _frac(rows, "silent_flag"),
        "errors": {"hits": sum(r["verdict"] == "error" for r in rows), "of": len(rows)},
        "seconds": round(sum(r["seconds"] for r in rows), 1),
    }


def by_what(rows: list[dict]) -> dict:
    out: dict = {}
    for r in rows:
        d = out.setdefault(f"{r['category']}:{r['what']}", {"ok": 0, "worded": 0, "of": 0})
        d["ok"] += bool(r["ok"])
        d["worded"] += bool(r["worded"])
        d["of"] += 1
    return out


def select(root: Path, split: str, categories=None, max_clean: int | None = None):
    man = json.loads((Path(root) / "manifest.json").read_text(encoding="utf-8"))
    cases = [c for c in man["cases"] if split == "all" or c["split"] == split]
    if categories:
        cases = [c for c in cases if c["category"] in categories]
    if max_clean is not None:
        clean = sorted(c["case_id"] for c in cases if c["category"] == "clean")[:max_clean]
        keep = set(clean)
        cases = [c for c in cases if c["category"] != "clean" or c["case_id"] in keep]
    return man, cases


def run_or_reuse(truth: dict, root: Path, outputs: Path | None, reuse: bool) -> dict:
    """:func:`run_case`, keeping the command's JSON in ``outputs/<case_id>.json`` when given;
    with ``reuse`` a JSON kept there earlier is read instead of running again (re-judging)."""
    kept = outputs / f"{truth['case_id']}.json" if outputs else None
    if reuse and kept is not None and kept.exists():
        return {"rc": 0, "seconds": 0.0, "stderr": "",
                "result": json.loads(kept.read_text(encoding="utf-8"))}
    run = run_case(truth, root / truth["case_id"])
    if kept is not None and run["result"] is not None:
        kept.write_text(json.dumps(run["result"], ensure_ascii=False), encoding="utf-8")
    return run


def score(root: Path, split: str = "all", jobs: int = MAX_JOBS, categories=None,
          max_clean: int | None = None, progress=None, outputs: Path | None = None,
          reuse: bool = False) -> tuple[dict, list[dict]]:
    """Run and judge the chosen cases under ``root``: (summary per split, rows)."""
    root = Path(root)
    man, cases = select(root, split, categories, max_clean)
    truths = [json.loads((root / c["truth"]).read_text(encoding="utf-8")) for c in cases]
    jobs = max(1, min(jobs, MAX_JOBS))
    if outputs is not None:
        Path(outputs).mkdir(parents=True, exist_ok=True)
    rows: list[dict] = []
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        runs = pool.map(lambda t: run_or_reuse(t, root, outputs and Path(outputs), reuse),
                        truths)
        for truth, run in zip(truths, runs, strict=True):
            rows.append(judge(truth, run))
            if progress:
                progress(rows[-1])
    summary = {s: summarize([r for r in rows if r["split"] == s])
               for s in ("tune", "heldout") if any(r["split"] == s for r in rows)}
    if len(summary) > 1:
        summary["all"] = summarize(rows)
    summary["seed"] = man["seed"]
    summary["detector"] = detector()
    summary["by_what"] = by_what(rows)
    summary["max_clean"] = max_clean
    return summary, rows


def _pct(d: dict) -> str:
    return f"{d['hits']}/{d['of']}" + (f" ({100 * d['hits'] / d['of']:.0f} %)" if d["of"] else "")


def _num(x) -> str:
    return "—" if x is None else f"{x:.1f}"


SUMMARY_KEYS = ("drive_state_reported", "drive_state_worded", "step_like_reported",
                "step_like_worded", "nil_right", "clean_false_alarms",
                "clean_false_alarms_course", "clean_false_alarms_csv",
                "clean_false_alarms_csv_counts", "catalog_named_right", "catalog_named",
                "catalog_params_within_4_std", "gap_made_worse", "contradictions",
                "silent_flags", "errors")


def markdown(summary: dict, rows: list[dict], title: str = "") -> str:
    splits = [s for s in ("tune", "heldout", "all") if s in summary]
    det = summary.get("detector") or {}
    lines = [f"# tiltbench gap on the drive part (seed {summary['seed']}){title}", "",
             f"Detector: `{det.get('version', '')}` from `{det.get('source', '')}`.", "",
             "| score | " + " | ".join(splits) + " |", "|---|" + "---|" * len(splits)]
    for k in SUMMARY_KEYS:
        lines.append(f"| {k.replace('_', ' ')} | "
                     + " | ".join(_pct(summary[s][k]) for s in splits) + " |")
    lines.append("| seconds (sum over runs) | "
                 + " | ".join(str(summary[s]["seconds"]) for s in splits) + " |")
    if summary.get("max_clean") is not None:
        lines += ["", f"Only the first {summary['max_clean']} clean runs were scored."]
    lines += ["", "| category:what | right | worded | of |", "|---|---|---|---|"]
    for k, d in sorted(summary["by_what"].items()):
        lines.append(f"| {k} | {d['ok']} | {d['worded'] if not k.startswith(('clean', 'cat', 'nil')) else '—'} | {d['of']} |")  # noqa: E501
    lines += ["", "| case | exp. | verdict | named | flagged after | ok | worded | worse "
              "| χ²/dof x b→a | χ²/dof y b→a | max abs(est−true)/std | unexplained (first) "
              "| s |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        mark = "yes" if r["ok"] else "**no**"
        if r["contradiction"]:
            mark += " (contradiction)"
        g = r["gaps"]
        gx = f"{g['x']['before']:.3f}→{g['x']['after']:.3f}" if "x" in g else "—"
        gy = f"{g['y']['before']:.3f}→{g['y']['after']:.3f}" if "y" in g else "—"
        une = (r["unexplained"][0] if r["unexplained"] else r.get("error", "")) \
            .replace("|", "/")[:110]
        wd = ("yes" if r["worded"] else "no") if r["category"] in ("drive_state",
                                                                     "step_like") else "—"
        lines.append(f"| {r['case_id']} | {r['expected']} | {r['verdict']} | "
                     f"{', '.join(r['named']) or '—'} | {', '.join(r['flagged_after']) or '—'}"
                     f" | {mark} | {wd} | {', '.join(r['worse']) or '—'} | {gx} | {gy} | "
                     f"{_num(r['param_z'])} | {une or '—'} | {r['seconds']} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m validation.drive.score",
                                description="Run tiltbench gap on the drive part and score "
                                "it per category and split (markdown summary on stdout).")
    p.add_argument("root", type=Path, help="folder written by validation.drive.generate")
    p.add_argument("--split", choices=("tune", "heldout", "all"), default="all")
    p.add_argument("--jobs", type=int, default=MAX_JOBS, help="parallel runs (at most 2)")
    p.add_argument("--category", action="append", choices=CATEGORIES,
                   help="score only this category (repeatable)")
    p.add_argument("--max-clean", type=int, help="score only the first K clean runs")
    p.add_argument("--table", type=Path, help="write the summary and per-case table (.md)")
    p.add_argument("--json", type=Path, help="write the summary and rows as JSON")
    p.add_argument("--outputs", type=Path,
                   help="keep each case's gap JSON in this folder (<case_id>.json)")
    p.add_argument("--reuse", action="store_true",
                   help="with --outputs: read a kept JSON instead of running the case again")
    a = p.parse_args(argv)

    def progress(r):
        print(f"[score] {r['case_id']}: {r['verdict']} {'ok' if r['ok'] else 'WRONG'} "
              f"({r['seconds']} s)", file=sys.stderr, flush=True)
    summary, rows = score(a.root, a.split, a.jobs, a.category, a.max_clean, progress,
                          a.outputs, a.reuse)
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
