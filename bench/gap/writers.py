"""The report files of the discrepancy workflow: ``gap.md``, ``gap.json``, the figures and
the extended model ``model_after.xml``."""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

from bench.dataset import write_json
from bench.gap.figure import save_gap_figure
from bench.gap.report import GapReport
from bench.model import edit_tilt_table, load_spec
from calib.conventions import AXES
from calib.io import atomic_write_text

PathLike = str | os.PathLike

REPORT_FILES = ("gap.json", "gap.md", "gap.png", "gap.svg", "model_after.xml")
"""What :func:`write_report` writes into the report directory."""


def check_outputs(report_dir: PathLike, rrd: PathLike | None) -> None:
    """Refuse to overwrite: raise :class:`FileExistsError` naming every output that exists."""
    clash = [str(Path(report_dir) / n) for n in REPORT_FILES if (Path(report_dir) / n).exists()]
    if rrd is not None and Path(rrd).exists():
        clash.append(str(rrd))
    if clash:
        raise FileExistsError(f"{', '.join(clash)}: exist(s); pass --force to overwrite")


def gap_markdown(report: GapReport) -> str:
    """The Markdown report (``gap.md``)."""
    d = report.to_dict()
    lines = ["# Discrepancy workflow (gap)", "",
             f"- samples: {report.replay.n}; g = {report.g} m/s²; stated σ² = "
             f"{report.noise_var[0]:g}, {report.noise_var[1]:g} (m/s²)²",
             f"- timing: {report.timing}; replay: **{report.replay.mode}** — "
             f"{report.replay.reason}"]
    if report.replay.mode == "sweep":
        lines.append(f"- the replay follows the measured encoder to "
                     f"{report.tracking_error:.2g} rad")
    lines += ["", "## Effects named", ""]
    if not d["effects"]:
        lines.append("None: the nominal model (bias, scale) explains the data within the "
                     "noise.")
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
            lines.append(f"| `{e['name']}` | {e['axis']} | {est} | {sy} | "
                         f"{e['statistic']:.4g} | {e['p_value']:.3g} | {e['timing']} |")
    if d["not_identifiable"]:
        lines += ["", "## Not identifiable", ""]
        lines += [f"- {', '.join(i['names'])}: {i['reason']}" for i in d["not_identifiable"]]
    if d["needs_timing"]:
        lines += ["", "## Needs timing", "",
                  "Not testable without sample times (`t` in the file or `--rate`): "
                  + ", ".join(f"`{n}`" for n in d["needs_timing"])
                  + ". `bias_drift` and `bias_random_walk` are reported per sample."]
    lines += ["", f"## Gap (family α = {report.family_alpha})", "",
              "| axis | χ²/dof before | max z before | χ²/dof after | max z after | "
              "after consistent with noise |", "|---|---|---|---|---|---|"]
    for ax in AXES:
        b, a = report.gap_before[ax], report.gap_after[ax]
        lines.append(f"| {ax} | {b.chi2_dof:.4f} | {b.max_signature_z:.2f} ({b.worst}) | "
                     f"{a.chi2_dof:.4f} | {a.max_signature_z:.2f} ({a.worst}) | "
                     f"{'yes' if a.consistent(report.family_alpha) else 'no'} |")
    lines += ["", "![residuals before and after](gap.png)", "",
              "The edited model is `model_after.xml` (MjSpec edit of models/tilt_table.xml); "
              "sensor terms and fitted bias/scale are in `gap.json` (`model_after`)."]
    return "\n".join(lines) + "\n"


def write_model_after(report: GapReport, path: PathLike, force: bool = False) -> Path:
    """Write the extended model (``MjSpec`` edit of a copy of the tilt table) as MJCF."""
    spec = load_spec()
    edit_tilt_table(spec, report.table_after)
    spec.compile()
    return atomic_write_text(path, spec.to_xml(), force=force)


def write_report(report: GapReport, out_dir: PathLike, force: bool = False) -> dict[str, str]:
    """Write ``gap.json``, ``gap.md``, ``gap.png``, ``gap.svg``, ``model_after.xml``."""
    out = Path(out_dir)
    if not force:
        check_outputs(out, None)
    out.mkdir(parents=True, exist_ok=True)
    files = {"json": str(out / "gap.json"), "markdown": str(out / "gap.md"),
             "png": str(out / "gap.png"), "svg": str(out / "gap.svg"),
             "model_after": str(out / "model_after.xml")}
    write_model_after(report, files["model_after"], force=True)
    save_gap_figure(report, files["png"])
    save_gap_figure(report, files["svg"])
    atomic_write_text(files["markdown"], gap_markdown(report), force=True)
    write_json(files["json"], replace(report, files=files).to_dict(), force=True)
    return files

