"""The documented entity schema of the recordings and the generator of its docs table.

:data:`ENTITY_DOCS` lists every entity a recording may hold; ``docs/recordings.md`` holds
:func:`entity_table_markdown` between markers (``python -m bench.record docs/recordings.md``
rewrites it with :func:`update_docs`); :func:`documented` finds the row of an entity.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

TREE_ROOTS: dict[str, str] = {"truth": "truth", "estimate": "estimates",
                              "trajectory": "trajectory"}
"""Entity root of each JSON tree → key in the dict returned by :func:`read_recording`."""


@dataclass(frozen=True)
class EntityDoc:
    """One row of the documented entity table.

    pattern : entity path; ``{axis}`` ∈ {x, y}, ``{k}`` a letter / name, ``**`` any subtree.
    archetype : rerun archetype(s) logged there.  index : timelines ("static" if none).
    content : what it holds, with units.  kinds : recordings that contain it
    ("calibration", "truth-run", "vehicle", "gap", "fusion").  optional : present only when
    the data exist
    (e.g. the truth of a generated set).
    """

    pattern: str
    archetype: str
    index: str
    content: str
    kinds: tuple[str, ...]
    optional: bool = False

    def regex(self) -> re.Pattern:
        out = re.escape(self.pattern)
        out = out.replace(re.escape("{axis}"), "(x|y)").replace(re.escape("{k}"), "[^/]+?")
        out = out.replace(re.escape("/**"), "(/.*)?")
        return re.compile("^" + out + "$")


# A table, one row per entity: its rows are alike in shape, not in logic (nothing to share).
_CAL = ("calibration", "truth-run")
_VEH = ("vehicle", "truth-run")
ENTITY_DOCS: tuple[EntityDoc, ...] = (
    EntityDoc("calibration/{axis}/measured", "Scalars + SeriesPoints", "sample, theta_urad",
              "measured A_m, m/s²", _CAL),
    EntityDoc("calibration/{axis}/fit", "Scalars + SeriesLines", "sample, theta_urad",
              "fitted model (1 + scale)·A_r + bias, m/s² (≤ 2001 samples)", ("calibration",)),
    EntityDoc("calibration/{axis}/true", "Scalars + SeriesLines", "sample, theta_urad",
              "true model (1 + scale)·a + bias with the true parameters and MuJoCo's true "
              "specific force a, m/s² (≤ 2001 samples)", _CAL, optional=True),
    EntityDoc("calibration/{axis}/residual", "Scalars + SeriesPoints", "sample, theta_urad",
              "residual A_m − fit, m/s² (truth-run: A_m − true model)", _CAL),
    EntityDoc("calibration/{axis}/residual_band/plus", "Scalars + SeriesLines",
              "sample, theta_urad", "+σ (first and last θ), m/s²", _CAL),
    EntityDoc("calibration/{axis}/residual_band/minus", "Scalars + SeriesLines",
              "sample, theta_urad", "−σ (first and last θ), m/s²", _CAL),
    EntityDoc("calibration/{axis}/residual_mean", "Scalars + SeriesLines",
              "sample, theta_urad", "binned mean of the residual (100 θ bins of equal counts, "
              "at the bins' mean θ), m/s²", _CAL),
    EntityDoc("calibration/{axis}/theta_plot", "Transform3D", "static",
              "static 2-D plot against θ (rad), shown by the blueprint: maps its data box onto "
              "a 300 × 100 box with +y up (translation, scale)", _CAL),
    EntityDoc("calibration/{axis}/theta_plot/measured", "Points2D", "static",
              "(θ rad, A_m m/s²) per sample (float32)", _CAL),
    EntityDoc("calibration/{axis}/theta_plot/fit", "LineStrips2D", "static",
              "fitted model against θ (≤ 2001 points)", ("calibration",)),
    EntityDoc("calibration/{axis}/theta_plot/true", "LineStrips2D", "static",
              "true model against θ (≤ 2001 points)", _CAL, optional=True),
    EntityDoc("calibration/{axis}/residual_plot", "Transform3D", "static",
              "static 2-D plot of the residuals (as `theta_plot`)", _CAL),
    EntityDoc("calibration/{axis}/residual_plot/residual", "Points2D", "static",
              "(θ rad, residual m/s²) per sample", _CAL),
    EntityDoc("calibration/{axis}/residual_plot/band", "LineStrips2D", "static",
              "±σ lines over the θ range, m/s²", _CAL),
    EntityDoc("calibration/{axis}/residual_plot/mean", "LineStrips2D", "static",
              "binned mean of the residual (as `residual_mean`), m/s²", _CAL),
    EntityDoc("calibration/{axis}/vs_ar", "Transform3D", "static",
              "static 2-D plot of the reading error against the reference (as `theta_plot`)",
              _CAL),
    EntityDoc("calibration/{axis}/vs_ar/measured", "Points2D", "static",
              "(A_r, A_m − A_r) per sample, m/s² (float32)", _CAL),
    EntityDoc("calibration/{axis}/vs_ar/mean", "LineStrips2D", "static",
              "binned mean of A_m − A_r over 100 A_r bins, m/s²", _CAL),
    EntityDoc("calibration/{axis}/vs_ar/fit", "LineStrips2D", "static",
              "fitted error line scale·A_r + bias over the A_r range, m/s²", ("calibration",)),
    EntityDoc("calibration/{axis}/vs_ar/true", "LineStrips2D", "static",
              "true error line scale·A_r + bias, m/s²", _CAL, optional=True),
    EntityDoc("calibration/{axis}/vs_ar/ideal", "LineStrips2D", "static",
              "ideal sensor A_m − A_r = 0, m/s²", _CAL),
    EntityDoc("calibration/{axis}/{k}/axes", "LineStrips2D", "static",
              "frame and ticks (and the zero line) of the static plot k = theta_plot, "
              "residual_plot or vs_ar, in its data units", _CAL),
    EntityDoc("calibration/{axis}/{k}/axes/labels", "Points2D (labels)", "static",
              "tick values of the static plot k", _CAL),
    EntityDoc("vehicle/acceleration/{k}/{axis}", "Scalars + SeriesLines", "time",
              "acceleration: k = measured (A_m), corrected (Â_r) or true, m/s²", _VEH),
    EntityDoc("vehicle/position_std/{axis}", "Scalars + SeriesLines", "time",
              "standard deviation of the corrected position (calibration + noise), m",
              ("vehicle",)),
    EntityDoc("vehicle/plane", "Transform3D", "static", "2-D frame with +y up",
              _VEH + ("fusion",)),
    EntityDoc("vehicle/plane/grid", "LineStrips2D", "static",
              "the plane's scale: frame and grid lines at round metres (one step for x and "
              "y), drawn under everything", _VEH + ("fusion",)),
    EntityDoc("vehicle/plane/grid/labels", "Points2D (labels)", "static",
              "grid values in m under the bottom and left of the frame, and the axis names "
              "`x (m)`, `y (m)`", _VEH + ("fusion",)),
    EntityDoc("vehicle/plane/path/{k}", "LineStrips2D", "static",
              "trajectory, k = raw (uncorrected), corrected or true, m (fusion, turning run: "
              "`corrected` is the turning dead reckoning)", _VEH + ("fusion",)),
    EntityDoc("vehicle/plane/position/{k}", "Points2D", "time",
              "position at the current time, k = raw, corrected or true, m (static colour and "
              "radius: those of the path)", _VEH),
    EntityDoc("vehicle/plane/candidates", "Points2D (labels)", "static",
              "candidate arrival points (puntos.mat), m", _VEH + ("fusion",)),
    EntityDoc("vehicle/plane/arrival/estimate", "Points2D", "static",
              "corrected arrival point, m (fusion: not for a turning run)",
              ("vehicle", "fusion")),
    EntityDoc("vehicle/plane/arrival/ellipse", "LineStrips2D", "static",
              "confidence ellipse of the arrival point at the stated level, m",
              ("vehicle", "fusion")),
    EntityDoc("vehicle/plane/uncertainty/ellipse", "LineStrips2D", "time",
              "ellipse at the same level around the corrected position at each time (error "
              "propagation over time), m", ("vehicle",)),
    EntityDoc("vehicle/plane/uncertainty/snapshots", "LineStrips2D", "static",
              "the growing ellipse at 10 evenly spaced times (the half-way one labelled), m",
              ("vehicle",)),
    EntityDoc("summary/parameters", "TextDocument (Markdown)", "static",
              "estimates with std and interval next to the true values and z-scores "
              "(truth-run: the true values)",
              ("calibration", "truth-run", "vehicle")),
    EntityDoc("summary/decision", "TextDocument (Markdown)", "static",
              "arrival decision, distances to the candidates (fusion: fused and dead "
              "reckoning)", ("vehicle", "fusion")),
    EntityDoc("vehicle/plane/fixes", "Points2D", "static",
              "position fixes used by `fuse` (inside the run, not rejected by the gate), m",
              ("fusion",)),
    EntityDoc("vehicle/plane/rejected_fixes", "Points2D (labels)", "static",
              "fixes the innovation gate rejected (NIS ≥ c), red, each labelled with its NIS, m",
              ("fusion",), optional=True),
    EntityDoc("vehicle/plane/fused/path", "LineStrips2D", "static",
              "Kalman-filtered path (every node), m", ("fusion",)),
    EntityDoc("vehicle/plane/fused/position", "Points2D", "time",
              "filtered position at the current time, m", ("fusion",)),
    EntityDoc("vehicle/plane/fused/ellipses", "LineStrips2D", "static",
              "filtered confidence ellipses at the stated level at every k-th fix (≤ 20), m; "
              "absent when the run is inconsistent", ("fusion",), optional=True),
    EntityDoc("vehicle/plane/fused/arrival", "LineStrips2D", "static",
              "fused arrival ellipse at the stated level (unlabelled: the decision view gives "
              "its size), m; absent when the run is inconsistent", ("fusion",), optional=True),
    EntityDoc("fusion/innovation/{axis}", "Scalars + SeriesPoints", "time",
              "innovation ν = fix − predicted position at each fix, m", ("fusion",)),
    EntityDoc("fusion/innovation_band/{axis}/{k}", "Scalars + SeriesLines", "time",
              "±sqrt(S_ii) of the innovation (k = plus, minus), m", ("fusion",)),
    EntityDoc("fusion/position_std/{axis}", "Scalars + SeriesLines", "time",
              "std of the filtered position, m", ("fusion",)),
    EntityDoc("fusion/nis/used", "Scalars + SeriesPoints", "time",
              "NIS = νᵀS⁻¹ν of each fix the filter used (χ²_d under a right model), "
              "dimensionless", ("fusion",)),
    EntityDoc("fusion/nis/rejected", "Scalars + SeriesPoints", "time",
              "NIS of each fix the gate rejected (red), dimensionless", ("fusion",),
              optional=True),
    EntityDoc("fusion/nis/gate", "Scalars + SeriesLines", "time",
              "the gate c = χ²_d⁻¹(1 − α_g) over the fixes' span (`--gate-alpha` > 0), "
              "dimensionless", ("fusion",), optional=True),
    EntityDoc("fusion/window_nis/sum", "Scalars + SeriesPoints", "time",
              "windowed NIS test: T_w = Σ min(NIS, c) over each window of ≤ K fixes, at the "
              "window's mid time, dimensionless", ("fusion",)),
    EntityDoc("fusion/window_nis/band/{k}", "Scalars + SeriesLines", "time",
              "two-sided band of T_w at Šidák's α_w (k = lo, hi), a step from each window's "
              "first to its last fix, dimensionless", ("fusion",)),
    EntityDoc("fusion/window_nis/failing", "Scalars + SeriesPoints", "time",
              "T_w of the windows out of their band (red), dimensionless", ("fusion",),
              optional=True),
    EntityDoc("summary/consistency", "TextDocument (Markdown)", "static",
              "the consistency verdict (\"consistent: …\" or \"INCONSISTENT: …\", as `fuse` "
              "prints it), the gate's count and the failing windows", ("fusion",)),
    EntityDoc("fusion/heading/{k}", "Scalars + SeriesLines", "time",
              "turning run: heading ψ, k = fused (filtered), dead_reckoning (gyro integrated) "
              "or true (truth.json, every second), rad", ("fusion",), optional=True),
    EntityDoc("fusion/heading_std", "Scalars + SeriesLines", "time",
              "turning run: std σ_ψ of the filtered heading, rad", ("fusion",), optional=True),
    EntityDoc("fusion/heading_error/{k}", "Scalars + SeriesPoints", "time",
              "turning run with truth: ψ − ψ true at the truth's samples, k = fused or "
              "dead_reckoning, rad", ("fusion",), optional=True),
    EntityDoc("fusion/heading_error_band/{k}", "Scalars + SeriesLines", "time",
              "turning run with truth: ±σ_ψ of the filter at the truth's samples (k = plus, "
              "minus), rad", ("fusion",), optional=True),
    EntityDoc("fusion_report/**", "Scalars | TextDocument, + json_type, json_path", "static",
              "final fused position, covariance and std, dead reckoning's std, fixes, mean "
              "NIS, P0/Q/R, decision, `consistent` and `consistency` (as `fuse --json`; read "
              "back under \"fusion_report\")", ("fusion",)),
    EntityDoc("gap/{axis}/residual_{k}", "Scalars + SeriesPoints", "sample, theta_urad",
              "discrepancy workflow: residual before / after adding the named effects, m/s² "
              "(bench/gap/recording.py)", ("gap",)),
    EntityDoc("gap/{axis}/band_{k}/{k}", "Scalars + SeriesLines", "sample, theta_urad",
              "±σ band of the before / after model (smallest and largest θ), m/s²", ("gap",)),
    EntityDoc("gap/{axis}/mean_{k}", "Scalars + SeriesLines", "sample, theta_urad",
              "binned mean of the residual before / after (≈ 80 samples per θ bin, at most 100 "
              "bins), m/s²", ("gap",)),
    EntityDoc("gap/{axis}/plot_time", "Transform3D", "static",
              "static 2-D plot of the residuals in time order (t in s; the sample index when "
              "the run has no times), shown by the blueprint as the gap figure's row in time",
              ("gap",)),
    EntityDoc("gap/{axis}/plot_time/residual", "Points2D", "static",
              "(t s or sample, residual before m/s²) per sample, small and translucent",
              ("gap",)),
    EntityDoc("gap/{axis}/plot_time/band", "LineStrips2D", "static",
              "±σ lines of the after model over the run, m/s²", ("gap",)),
    EntityDoc("gap/{axis}/plot_time/mean", "LineStrips2D", "static",
              "binned mean of the residual before in time (≈ 80 samples per bin, at most 100 "
              "bins), drawn on top, m/s²", ("gap",)),
    EntityDoc("gap/{axis}/plot_time/mean_after", "LineStrips2D", "static",
              "binned mean of the residual after in time (red), m/s²", ("gap",)),
    EntityDoc("gap/{axis}/plot_time/moving", "LineStrips2D", "static",
              "a thick grey bar along the bottom under each stretch where the table moves "
              "(calib.gap.drive_state); only on a run with moving and held stretches", ("gap",),
              optional=True),
    EntityDoc("gap/{axis}/plot_{k}", "Transform3D", "static",
              "static 2-D plot of the residual before / after against θ (rad), shown by the "
              "blueprint (as `theta_plot`; before and after share the y range)", ("gap",)),
    EntityDoc("gap/{axis}/plot_{k}/residual", "Points2D", "static",
              "(θ rad, residual m/s²) per sample, small and translucent", ("gap",)),
    EntityDoc("gap/{axis}/plot_{k}/band", "LineStrips2D", "static",
              "±σ lines of the before / after model over the θ range, m/s²", ("gap",)),
    EntityDoc("gap/{axis}/plot_{k}/mean", "LineStrips2D", "static",
              "binned mean of the residual (as `mean_{k}`), drawn on top, m/s²", ("gap",)),
    EntityDoc("gap/{axis}/plot_{k}/axes", "LineStrips2D", "static",
              "frame, ticks and zero line of the plot, in its data units", ("gap",)),
    EntityDoc("gap/{axis}/plot_{k}/axes/labels", "Points2D (labels)", "static",
              "tick values and axis names of the plot", ("gap",)),
    EntityDoc("gap/effects", "TextDocument (Markdown)", "static",
              "the named effects with their evidence (`gap.md` without its image)", ("gap",)),
    EntityDoc("gap_report/**", "Scalars | TextDocument, + json_type, json_path", "static",
              "every node of the `gap --json` object (read back under \"gap_report\")",
              ("gap",)),
    EntityDoc("truth/**", "Scalars | TextDocument, + json_type, json_path", "static",
              "every node of truth.json (path = JSON keys, list items by index)",
              ("calibration", "truth-run", "vehicle", "fusion"), optional=True),
    EntityDoc("estimate/**", "Scalars | TextDocument, + json_type, json_path", "static",
              "every node of the `calibrate --json` object", ("calibration", "vehicle")),
    EntityDoc("trajectory/**", "Scalars | TextDocument, + json_type, json_path", "static",
              "every node of the trajectory/decision object (`trajectory` and `region`)",
              ("vehicle",)),
)
"""The documented entities; ``docs/recordings.md`` holds :func:`entity_table_markdown`."""


def entity_table_markdown() -> str:
    """The entity table of ``docs/recordings.md`` (generated from :data:`ENTITY_DOCS`)."""
    lines = ["| entity path | archetype | timelines | content | recordings |",
             "|---|---|---|---|---|"]
    for d in ENTITY_DOCS:
        kinds = ", ".join(d.kinds) + (" (if available)" if d.optional else "")
        lines.append(f"| `{d.pattern}` | {d.archetype} | {d.index} | {d.content} | {kinds} |")
    return "\n".join(lines)


def documented(entity: str) -> EntityDoc | None:
    """The :class:`EntityDoc` whose pattern matches ``entity`` (leading '/' optional)."""
    e = entity.lstrip("/")
    for d in ENTITY_DOCS:
        if d.regex().match(e):
            return d
    return None


def update_docs(doc: str | os.PathLike) -> bool:
    """Rewrite the entity table between the markers in ``doc``; True if it changed."""
    doc = Path(doc)
    text = doc.read_text(encoding="utf-8")
    start, end = "<!-- entity-table:start -->", "<!-- entity-table:end -->"
    i, j = text.index(start) + len(start), text.index(end)
    new = text[:i] + "\n" + entity_table_markdown() + "\n" + text[j:]
    if new != text:
        from calib.files.atomic import write_text

        write_text(doc, new, force=True)  # atomic and locked, as every output
    return new != text
