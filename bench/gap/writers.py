"""The report files of the discrepancy workflow: ``gap.md``, ``gap.json``, the figures and
the extended model ``model_after.xml``."""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

from bench.dataset import write_json
from bench.gap.figure import save_gap_figure
from bench.gap.files import REPORT_FILES
from bench.gap.report import GapReport, shrink_word
from bench.model import edit_tilt_table, load_spec
from calib.conventions import AXES
from calib.files.atomic import atomic_dir, write_text
from calib.gap.confusions import design_hint
from calib.gap.results import POOLED_WORDS
from calib.units import format_p, format_stat

PathLike = str | os.PathLike


def check_outputs(report_dir: PathLike, rrd: PathLike | None) -> None:
    """Refuse to overwrite: raise :class:`FileExistsError` naming every output that exists."""
    clash = [str(Path(report_dir) / n) for n in REPORT_FILES if (Path(report_dir) / n).exists()]
    if rrd is not None and Path(rrd).exists():
        clash.append(str(rrd))
    if clash:
        raise FileExistsError(f"{', '.join(clash)}: exist(s); pass --force to overwrite")


def verdict_markdown(report: GapReport) -> list[str]:
    """The verdict section of ``gap.md`` (also the head of the recording's text view)."""
    head, *rest = report.verdict_lines()
    lines = ["## Verdict", "", f"**{head.removeprefix('verdict: ')}**"]
    if rest:
        lines += ["", "| axis | what remains | signature | size | statistic | p |",
                  "|---|---|---|---|---|---|"]
        for u in report.unexplained:
            size = u.get("size")
            lines.append(f"| {u.get('axis', '?')} | {u.get('description', '')} | "
                         f"`{u.get('signature', '')}` | "
                         + ("" if size is None else f"{float(size):.3g} {u.get('unit', '')}")
                         + f" | {_num(u.get('statistic'), '.4g')} | "
                         f"{_num(u.get('p_value'), '.3g')} |")
    if report.tentative() and any(report.tentative()):
        lines += ["", "Effects marked *(tentative)* are named, but the final model fails "
                  "adequacy: something not in the model remains and may bias their "
                  "estimates."]
    return lines


def _num(v: object, fmt: str) -> str:
    return "" if v is None else format(float(v), fmt)


def gap_markdown(report: GapReport) -> str:
    """The Markdown report (``gap.md``): the verdict first, then the replay, the named
    effects, the gap before / after and why it shrank or did not."""
    d = report.to_dict()
    lines = ["# Discrepancy workflow (gap)", "", *verdict_markdown(report), "",
             "## Run", "",
             f"- samples: {report.replay.n}; g = {report.g} m/s²; stated σ² = "
             f"{report.noise_var[0]:g}, {report.noise_var[1]:g} (m/s²)²",
             f"- timing: {report.timing}; replay: **{report.replay.mode}** — "
             f"{report.replay.reason}"]
    if report.replay.mode == "sweep":
        lines.append(f"- the replay follows the measured encoder to "
                     f"{report.tracking_error:.2g} rad")
    lines += ["", "## Effects named", ""]
    if not d["effects"]:
        lines.append("None." if report.verdict == "unexplained" else
                     f"None: nothing detected at α = {report.verdict_alpha:g}.")
    else:
        lines += ["| effect | axis | estimate ± std (calib LS) | mujoco.sysid ± std | "
                  "statistic | p | timing |", "|---|---|---|---|---|---|---|"]
        for e in d["effects"]:
            est = "; ".join(f"{k} = {v:.6g} ± {e['std'].get(k, float('nan')):.2g}"
                            for k, v in e["params"].items())
            s = e.get("sysid", {})
            sy = ("; ".join(f"{k} = {v:.6g} ± {s['std'][k]:.2g}"
                            for k, v in s["params"].items()) if "params" in s
                  else s.get("error", "—"))
            name = f"`{e['name']}`" + (" *(tentative)*" if e["tentative"] else "")
            p = format_p(e["p_value"]).removeprefix("p = ").removeprefix("p ")
            lines.append(f"| {name} | {e['axis']} | {est} | {sy} | "
                         f"{format_stat(e['statistic'])}{POOLED_WORDS if e.get('pooled') else ''}"
                         f" | {p} | {e['timing']} |")
    if d["reported"]:
        lines += ["", "## Seen, not named", "",
                  "Effects that change the fit by less than the practical threshold "
                  "(`calib.gap.practical`): in the model, not named as missing.", ""]
        lines += [f"- `{r['name']}` ({r['axis']}): {r['description']}" for r in d["reported"]]
    if d["not_identifiable"]:
        lines += ["", "## Not identifiable", ""]
        lines += [f"- {', '.join(i['names'])}: {i['reason']}"
                  + (f" — {design_hint(i['names'])}" if len(i["names"]) == 2 else "")
                  for i in d["not_identifiable"]]
    if d["needs_timing"]:
        lines += ["", "## Needs timing", "",
                  "Not testable without sample times (`t` in the file or `--rate`): "
                  + ", ".join(f"`{n}`" for n in d["needs_timing"])
                  + ". `bias_drift` and `bias_random_walk` are reported per sample."]
    lines += ["", f"## Gap (family α = {report.family_alpha}; χ²/dof against the stated σ²)",
              "", "| axis | χ²/dof before | max z before | χ²/dof after | max z after | "
              "after consistent with noise | shrank |", "|---|---|---|---|---|---|---|"]
    for ax in AXES:
        b, a = report.gap_before[ax], report.gap_after[ax]
        da, sh = d["gap_after"][ax], d["shrink"][ax]
        lines.append(f"| {ax} | {b.chi2_dof:.4f} | {b.max_signature_z:.2f} ({b.worst}) | "
                     f"{da['chi2_dof']:.4f} | {a.max_signature_z:.2f} ({a.worst}) | "
                     f"{'yes' if da['consistent'] else 'no'} | "
                     f"{'yes' if sh['shrunk'] else 'no'} |")
    lines += ["", "Per axis:", ""]
    for ax in AXES:
        da, sh = d["gap_after"][ax], d["shrink"][ax]
        lines.append(f"- {ax}: {shrink_word(sh)} — {sh['reason']}")
        if "reason" in da and da["reason"] not in sh["reason"]:
            lines.append(f"  (after not consistent: {da['reason']})")
    lines += ["", "![residuals before and after](gap.png)", "",
              "The edited model is `model_after.xml` (MjSpec edit of models/tilt_table.xml); "
              "sensor terms and fitted bias/scale are in `gap.json` (`model_after`)."]
    return "\n".join(lines) + "\n"


def write_model_after(report: GapReport, path: PathLike, force: bool = False) -> Path:
    """Write the extended model (``MjSpec`` edit of a copy of the tilt table) as MJCF."""
    spec = load_spec()
    edit_tilt_table(spec, report.table_after)
    spec.compile()
    return write_text(path, spec.to_xml(), force=force)


def write_report(report: GapReport, out_dir: PathLike, force: bool = False) -> dict[str, str]:
    """Write ``gap.json``, ``gap.md``, ``gap.png``, ``gap.svg``, ``model_after.xml``.

    The directory is written as one set (:func:`calib.files.atomic.atomic_dir`): into a temporary
    directory beside ``out_dir`` that replaces the report as a whole when complete (other
    files in ``out_dir`` are kept); refused while another run writes ``out_dir``.
    """
    out = Path(out_dir)
    if not force:
        check_outputs(out, None)
    files = {"json": str(out / "gap.json"), "markdown": str(out / "gap.md"),
             "png": str(out / "gap.png"), "svg": str(out / "gap.svg"),
             "model_after": str(out / "model_after.xml")}
    with atomic_dir(out, force, owned=REPORT_FILES) as tmp:
        write_model_after(report, tmp / "model_after.xml", force=True)
        save_gap_figure(report, [tmp / "gap.png", tmp / "gap.svg"])
        write_text(tmp / "gap.md", gap_markdown(report), force=True)
        write_json(tmp / "gap.json", replace(report, files=files).to_dict(), force=True)
    return files
