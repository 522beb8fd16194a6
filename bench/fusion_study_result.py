"""What :mod:`bench.fusion_study` reports: a row per method and scenario, the NEES along the
path, and the whole study with its table (text, Markdown, JSON); definitions of every number
in :mod:`bench.fusion_study`'s docstring, the bands in :mod:`calib.stats.consistency`.

Units SI: s, m, m/s; areas m²; NEES and coverage dimensionless.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from calib.results import ResultMixin
from calib.stats.consistency import NEES_ALPHA

METHODS = ("dead_reckoning", "fixes", "filter", "smoother")
"""The four methods compared, in the order of the table."""


@dataclass(frozen=True)
class StudyRow:
    """One method in one scenario (module docstring for the definitions)."""

    scenario: str
    method: str
    rms_m: float
    final_std_m: float
    area_m2: float
    nees: float
    nees_band: tuple[float, float]
    nees_ok: bool
    coverage: float
    coverage_band: tuple[float, float]
    coverage_ok: bool
    path_band: tuple[float, float] | None = None
    path_out_frac: float | None = None
    path_out_ranges: tuple[tuple[float, float], ...] = ()
    path_ok: bool | None = None
    path4_band: tuple[float, float] | None = None
    path4_out_frac: float | None = None
    path_where: str = ""
    path4_where: str = ""

    def to_dict(self) -> dict:
        def opt(v):
            return None if v is None else list(v)

        return {"scenario": self.scenario, "method": self.method, "rms_m": self.rms_m,
                "final_std_m": self.final_std_m, "area_m2": self.area_m2, "nees": self.nees,
                "nees_band": list(self.nees_band), "nees_ok": self.nees_ok,
                "coverage": self.coverage, "coverage_band": list(self.coverage_band),
                "coverage_ok": self.coverage_ok, "path_band": opt(self.path_band),
                "path_out_frac": self.path_out_frac,
                "path_out_ranges": [list(r) for r in self.path_out_ranges],
                "path_ok": self.path_ok, "path4_band": opt(self.path4_band),
                "path4_out_frac": self.path4_out_frac, "path_where": self.path_where,
                "path4_where": self.path4_where}

    @classmethod
    def from_dict(cls, d: dict) -> StudyRow:
        def opt(v):
            return None if v is None else tuple(float(x) for x in v)

        return cls(d["scenario"], d["method"], float(d["rms_m"]), float(d["final_std_m"]),
                   float(d["area_m2"]), float(d["nees"]), tuple(d["nees_band"]),
                   bool(d["nees_ok"]), float(d["coverage"]), tuple(d["coverage_band"]),
                   bool(d["coverage_ok"]), opt(d.get("path_band")), d.get("path_out_frac"),
                   tuple(tuple(float(x) for x in r) for r in d.get("path_out_ranges", ())),
                   d.get("path_ok"), opt(d.get("path4_band")), d.get("path4_out_frac"),
                   d.get("path_where", ""), d.get("path4_where", ""))


PATH_NOTE = ("Path NEES: the mean over the runs of the NEES at every fix epoch (position, "
             "2 dof; 4-dof: position+velocity), each epoch against χ²(dof·R)/R at "
             f"α = {NEES_ALPHA:g}/(2M) (Bonferroni over the M epochs and the two NEES; α/M "
             "for fixes, position only); share of epochs outside (position) and where; "
             "consistent along the path = no epoch outside, position nor position+velocity. "
             "Dead reckoning: not computed (n/a).")

ROW_UNITS = {"rows.rms_m": "m", "rows.final_std_m": "m", "rows.area_m2": "m²",
             "rows.nees": "1", "rows.nees_band": "1", "rows.coverage": "1",
             "rows.coverage_band": "1", "rows.path_band": "1", "rows.path_out_frac": "1",
             "rows.path_out_ranges": "s", "rows.path4_band": "1", "rows.path4_out_frac": "1"}


@dataclass(frozen=True)
class PathNees:
    """Mean NEES over the runs at every fix epoch of one scenario and method (module
    docstring): ``t`` s, ``nees`` position (2 dof), ``nees4`` position+velocity (4 dof, empty
    when the method states no velocity covariance), each with its per-epoch Bonferroni band
    (:func:`calib.stats.consistency.path_band`)."""

    scenario: str
    method: str
    t: tuple[float, ...]
    nees: tuple[float, ...]
    band: tuple[float, float]
    nees4: tuple[float, ...] = ()
    band4: tuple[float, float] | None = None

    def out(self, dof: int = 2) -> np.ndarray:
        """(M,) bool, epochs whose mean NEES is outside its band."""
        v, b = (self.nees, self.band) if dof == 2 else (self.nees4, self.band4)
        v = np.asarray(v, float)
        return (v < b[0]) | (v > b[1])

    def to_dict(self) -> dict:
        return {"scenario": self.scenario, "method": self.method, "t": list(self.t),
                "nees": list(self.nees), "band": list(self.band), "nees4": list(self.nees4),
                "band4": None if self.band4 is None else list(self.band4)}

    @classmethod
    def from_dict(cls, d: dict) -> PathNees:
        b4 = d.get("band4")
        return cls(d["scenario"], d["method"], tuple(d["t"]), tuple(d["nees"]),
                   tuple(d["band"]), tuple(d.get("nees4", ())),
                   None if b4 is None else tuple(b4))


@dataclass(frozen=True, eq=False)
class StudyResult(ResultMixin):
    """The comparison: one :class:`StudyRow` per scenario × method, and the outage curve
    (filter: stated per-axis std ``sqrt(tr P/2)`` and empirical per-axis RMS error over the
    runs, against time, m)."""

    _TITLE = "Fusion comparison"
    _UNITS = "rms, std m; area m²; NEES, coverage 1; t s"

    config: dict
    rows: tuple[StudyRow, ...]
    outage_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    outage_std: np.ndarray = field(default_factory=lambda: np.zeros(0))
    outage_rms: np.ndarray = field(default_factory=lambda: np.zeros(0))
    outage_start: float = float("nan")
    paths: tuple[PathNees, ...] = ()

    def path(self, scenario: str, method: str = "filter") -> PathNees:
        for p in self.paths:
            if p.scenario == scenario and p.method == method:
                return p
        raise KeyError(f"no path NEES for {scenario!r}, {method!r}")

    def row(self, scenario: str, method: str) -> StudyRow:
        for r in self.rows:
            if r.scenario == scenario and r.method == method:
                return r
        raise KeyError(f"no row for {scenario!r}, {method!r}")

    @property
    def scenarios(self) -> list[str]:
        return list(dict.fromkeys(r.scenario for r in self.rows))

    def to_dict(self) -> dict:
        units = {"config.level": "1", "config.p0_std": "m", "config.v0_std": "m/s",
                 "config.gps_sigma": "m", "config.runs": "count", "config.seed": "1",
                 "config.chunk": "count", "config.scenarios.imu_hz": "Hz",
                 "config.scenarios.fix_hz": "Hz", "config.scenarios.outage_s": "s",
                 "config.scenarios.p0_factor": "1", "config.scenarios.q_factor": "1",
                 "config.scenarios.r_factor": "1", **ROW_UNITS,
                 "outage.t": "s", "outage.std": "m", "outage.rms": "m", "outage.start": "s",
                 "paths.t": "s", "paths.nees": "1", "paths.band": "1", "paths.nees4": "1",
                 "paths.band4": "1"}
        return {"config": self.config, "rows": [r.to_dict() for r in self.rows],
                "outage": {"t": self.outage_t.tolist(), "std": self.outage_std.tolist(),
                           "rms": self.outage_rms.tolist(),
                           "start": None if np.isnan(self.outage_start)
                           else self.outage_start},
                "paths": [p.to_dict() for p in self.paths],
                "units": units}

    @classmethod
    def from_dict(cls, d: dict) -> StudyResult:
        o = d.get("outage", {})
        start = o.get("start")
        return cls(d["config"], tuple(StudyRow.from_dict(r) for r in d["rows"]),
                   np.asarray(o.get("t", []), float), np.asarray(o.get("std", []), float),
                   np.asarray(o.get("rms", []), float),
                   float("nan") if start is None else float(start),
                   tuple(PathNees.from_dict(p) for p in d.get("paths", ())))

    def table(self) -> list[list[str]]:
        """Header and one line per row, as text (units in the header)."""
        head = ["scenario", "method", "RMS error (m)", "final std (m)",
                f"area {100 * self.config['level']:g} % (m²)", "mean NEES (band)",
                f"coverage {100 * self.config['level']:g} % (band)",
                "path NEES out: share (where)", "path NEES 4-dof out: share (where)",
                "consistent along the path"]
        lines = [head]
        for r in self.rows:
            lines.append([
                r.scenario, r.method.replace("_", " "), f"{r.rms_m:.3g}", f"{r.final_std_m:.3g}",
                f"{r.area_m2:.3g}",
                f"{r.nees:.2f} ({r.nees_band[0]:.2f}–{r.nees_band[1]:.2f})"
                + ("" if r.nees_ok else " OUT"),
                f"{r.coverage:.3f} ({r.coverage_band[0]:.3f}–{min(r.coverage_band[1], 1):.3f})"
                + ("" if r.coverage_ok else " OUT"),
                "n/a" if r.path_ok is None
                else f"{100 * r.path_out_frac:.0f} % ({r.path_where})",
                "n/a" if r.path4_out_frac is None
                else f"{100 * r.path4_out_frac:.0f} % ({r.path4_where})",
                "n/a" if r.path_ok is None else ("yes" if r.path_ok else "no")])
        return lines

    def summary(self) -> str:
        """The terminal summary (every line ≤ 100 columns): RMS error per scenario and method,
        a mark where the stated covariance is inconsistent; the full table is
        :meth:`markdown` (``fusion-study.md``)."""
        out = [f"Fusion comparison: {self.config['runs']} runs per scenario, seed "
               f"{self.config['seed']}, course geometry (60 s)",
               f"fixes σ = {self.config['gps_sigma']:g} m per axis; initial σ "
               f"{self.config['p0_std']:g} m, {self.config['v0_std']:g} m/s"]
        out.append("RMS error (m) along the path; * = the stated covariance is inconsistent "
                   "(mean NEES,")
        out.append("coverage or path NEES outside its band)")
        cols = [m.replace("_", " ") for m in METHODS]
        w0 = max(len(sc) for sc in [*self.scenarios, "scenario"])
        out.append("  ".join(["scenario".ljust(w0), *(c.rjust(14) for c in cols)]))
        for sc in self.scenarios:
            by = {r.method: r for r in self.rows if r.scenario == sc}
            cells = []
            for m in METHODS:
                r = by.get(m)
                bad = r is not None and not (r.nees_ok and r.coverage_ok
                                             and r.path_ok is not False)
                cells.append("—".rjust(14) if r is None
                             else (f"{r.rms_m:.3g}" + ("*" if bad else " ")).rjust(14))
            out.append("  ".join([sc.ljust(w0), *cells]))
        out.append("Final std (m), area (m²), NEES and coverage with their bands, path NEES: "
                   "the written report")
        out.append("(fusion-study.md).")
        return "\n".join(out)

    def markdown(self) -> str:
        lines = self.table()
        md = [f"# Fusion comparison ({self.config['runs']} runs per scenario, seed "
              f"{self.config['seed']})", "",
              "Course geometry (60 s, the course profile, P0 = (0, 0) m, V0 = (1, 3) m/s), fixes "
              f"σ = {self.config['gps_sigma']:g} m per axis, initial-state σ "
              f"{self.config['p0_std']:g} m and {self.config['v0_std']:g} m/s. Definitions: "
              "docs/fusion.md and `bench/fusion_study.py`.", "",
              "| " + " | ".join(lines[0]) + " |",
              "|" + "|".join("---" for _ in lines[0]) + "|"]
        md += ["| " + " | ".join(line) + " |" for line in lines[1:]]
        md += ["", PATH_NOTE]
        return "\n".join(md) + "\n"


def describe_ranges(ranges, t_first: float, t_last: float) -> str:
    """``out_ranges`` as text: "—" (none), "all t", "t ≤ 8 s", "t ≥ 40 s", "3–9 s", joined
    by ", " (at most three, then "+k more")."""
    if not ranges:
        return "—"
    words = []
    for a, b in ranges:
        if a <= t_first and b >= t_last:
            words.append("all t")
        elif a == b:
            words.append(f"t = {a:g} s")
        elif a <= t_first:
            words.append(f"t ≤ {b:g} s")
        elif b >= t_last:
            words.append(f"t ≥ {a:g} s")
        else:
            words.append(f"{a:g}–{b:g} s")
    more = len(words) - 3
    return ", ".join(words[:3]) + (f", +{more} more" if more > 0 else "")
