""":class:`DesignResult`: the powers of :func:`calib.design.analyze_design`."""

from __future__ import annotations

from dataclasses import dataclass

from calib.results import ResultMixin
from calib.units import UNITS_KEY, with_units

STRENGTH_UNITS = {"saturation": "1", "noise_level": "1"}
"""Unit of the grid strength (:mod:`calib.design.grid`) where it is not the size's unit:
ln(g/L) and |ln(v/σ²)| are ratios."""


def _pct(p: float | None) -> str:
    return "—" if p is None else f"{100 * p:5.1f} %"


def _power(r: dict) -> str:
    """An analytic power, or a Monte Carlo one with the exact 95 % interval its runs allow."""
    if "power_ci95" not in r:
        return _pct(r.get("power"))
    lo, hi = r["power_ci95"]
    return f"{100 * r['power']:.0f} % [{100 * lo:.0f}, {100 * hi:.0f}] MC"


def _size(v: float | None, unit: str) -> str:
    return "—" if v is None else f"{v:.3g} {unit}"


def _mc_size(r: dict, level: int, unit: str) -> str:
    """A size from a Monte Carlo grid: marked MC, a bound ("> …", "< …") when the grid's
    powers never (or already at its smallest size) reach the level."""
    mc = r.get(f"size_{level}_mc")
    if mc is None:
        return _size(r.get(f"size_{level}"), unit)
    rel = "" if mc["relation"] == "=" else mc["relation"] + " "
    return f"{rel}{_size(r[f'size_{level}'], unit)} MC"


def _grid_notes(effects: dict, runs: int) -> list[str]:
    """Per Monte Carlo row with a grid: the bracketing grid sizes of the 80 / 95 % sizes and
    the exact 95 % intervals of their powers (what R runs per point support)."""
    out = []
    for name, e in effects.items():
        for i, r in enumerate(e["per_experiment"]):
            if "grid" not in r:
                continue
            parts = []
            for level in (80, 95):
                mc = r[f"size_{level}_mc"]
                br = ", ".join(f"{_size(v, e['unit'])} ({100 * lo:.0f}–{100 * hi:.0f} %)"
                               for v, (lo, hi) in zip(mc["bracket"], mc["bracket_power_ci95"],
                                                      strict=True))
                parts.append(f"{level} %: {_mc_size(r, level, e['unit'])} [{br}]")
            lines = "; ".join(parts)
            out.append(f"  {name} [{i}] {lines}")
    if out:
        out = ["", f"Monte Carlo sizes (MC): isotonic fit of the grid powers, interpolated in "
                   f"ln(strength); {runs} runs per grid point, so each bracketing point's power "
                   "is known only to its exact 95 % interval (in brackets):", *out]
    return out


@dataclass(frozen=True, eq=False)
class DesignResult(ResultMixin):
    """Power per experiment and effect (JSON: :meth:`to_dict`, units in ``"units"``).

    settings : family α, stated σ², axis, Monte Carlo runs and seed, g, the ambiguity margin.
    experiments : per experiment: design, N, mean sweep rate (rad/s), duration (s), timed,
        the gap's per-step α and test count, ``nominal_std`` (axis → bias m/s², scale 1).
    effects : name → axis, size, unit, method ("analytic" | "monte_carlo") and
        ``per_experiment`` rows: testable, power (fraction), analytic: noncentrality λ,
        lambda_unit (λ at unit coefficient), df, critical value, size_80 and size_95 (the
        effect's unit); Monte Carlo: power_std (binomial), power_ci95 (exact), runs; with
        a grid (``settings.mc_grid``, :mod:`calib.design.grid`) also ``grid`` (factors,
        strength, sizes, hits, powers, power_ci95, powers_monotone, runs), size_80 and
        size_95, and ``size_80_mc`` / ``size_95_mc`` (relation "=", "<" or ">", bracketing
        grid sizes, the exact 95 % intervals of their powers).
    pairs : "A-vs-B" → names, size of A, unit, method, per_experiment power (to tell A,
        true, from B).
    """

    settings: dict
    experiments: tuple[dict, ...]
    effects: dict
    pairs: dict

    _TITLE = "Experiment design: power of the gap detection"
    _UNITS = "sizes in each effect's unit; powers as fractions; std in m/s² and 1"

    def _units(self) -> dict[str, str]:
        u = {"settings.family_alpha": "1", "settings.noise_var": "(m/s²)²",
             "settings.runs": "count", "settings.seed": "—", "settings.g": "m/s²",
             "settings.ambiguity_lr": "1",
             "experiments.n": "count", "experiments.rate": "rad/s", "experiments.duration": "s",
             "experiments.alpha_step": "1", "experiments.n_tests": "count",
             "experiments.nominal_std.*.bias": "m/s²", "experiments.nominal_std.*.scale": "1"}
        for name, e in self.effects.items():
            for k in ("size", "per_experiment.size_80", "per_experiment.size_95"):
                u[f"effects.{name}.{k}"] = e["unit"]
        for key, e in self.pairs.items():
            u[f"pairs.{key}.size"] = e["unit"]
        if self.settings.get("mc_grid"):
            u.update({"settings.mc_grid": "count", "settings.mc_span": "1"})
            for name, e in self.effects.items():
                pe = f"effects.{name}.per_experiment"
                u.update({f"{pe}.grid.sizes": e["unit"], f"{pe}.size_80_mc.bracket": e["unit"],
                          f"{pe}.size_95_mc.bracket": e["unit"],
                          f"{pe}.grid.strength": STRENGTH_UNITS.get(name, e["unit"])})
            u.update({"effects.*.per_experiment.grid.factors": "1",
                      "effects.*.per_experiment.grid.hits": "count",
                      "effects.*.per_experiment.grid.powers": "1",
                      "effects.*.per_experiment.grid.power_ci95": "1",
                      "effects.*.per_experiment.grid.powers_monotone": "1",
                      "effects.*.per_experiment.grid.runs": "count",
                      "effects.*.per_experiment.*.bracket_power_ci95": "1"})
        u.update({"effects.*.per_experiment.right_name": "1",
                  "effects.*.per_experiment.right_name_std": "1",
                  "effects.*.per_experiment.right_name_ci95": "1",
                  "settings.gain": "1"})
        u.update({"effects.*.per_experiment.power": "1",
                  "effects.*.per_experiment.power_std": "1",
                  "effects.*.per_experiment.power_ci95": "1",
                  "effects.*.per_experiment.noncentrality": "1",
                  "effects.*.per_experiment.lambda_unit": "1",
                  "effects.*.per_experiment.critical": "1",
                  "effects.*.per_experiment.df": "count",
                  "effects.*.per_experiment.runs": "count",
                  "pairs.*.per_experiment.power": "1", "pairs.*.per_experiment.power_std": "1",
                  "pairs.*.per_experiment.power_ci95": "1",
                  "pairs.*.per_experiment.noncentrality": "1",
                  "pairs.*.per_experiment.runs": "count"})
        return u

    def to_dict(self) -> dict:
        return with_units({"settings": self.settings, "experiments": list(self.experiments),
                           "effects": self.effects, "pairs": self.pairs}, self._units())

    @classmethod
    def from_dict(cls, d: dict) -> DesignResult:
        d = {k: v for k, v in d.items() if k != UNITS_KEY}
        return cls(dict(d["settings"]), tuple(d["experiments"]), dict(d["effects"]),
                   dict(d["pairs"]))

    def summary(self) -> str:
        """A table: per effect and experiment the power, and the 80 % / 95 % sizes."""
        s = self.settings
        lines = [f"Experiment design: gap detection power (family α = {s['family_alpha']:g}, "
                 f"stated σ² = {s['noise_var'][0]:g}, {s['noise_var'][1]:g} (m/s²)², "
                 f"per-axis effects on {s['axis']}; Monte Carlo: {s['runs']} runs, "
                 f"seed {s['seed']})", "", "Experiments (nominal fit std):"]
        for i, e in enumerate(self.experiments):
            ns = e["nominal_std"]
            lines.append(
                f"  [{i}] {e['design']:<8} N = {e['n']}, ω̄ = {e['rate']:g} rad/s, "
                f"T = {e['duration']:.3g} s, α_step = {e['alpha_step']:.3g} "
                f"({e['n_tests']} tests); std bias x {ns['x']['bias']:.3g} m/s², "
                f"scale x {ns['x']['scale']:.3g}, bias y {ns['y']['bias']:.3g} m/s², "
                f"scale y {ns['y']['scale']:.3g}")
        lines += ["", f"Sizes for a sensor gain 1 + scale = {s.get('gain', 1.0):g}. power: "
                      "the first selection step (linear: analytic); right name: the whole "
                      "workflow names exactly this effect, verdict explained (Monte Carlo of "
                      "analyze_gap, exact 95 % interval).",
                  f"{'effect (size)':<40} {'exp':>4} {'power':>18} {'right name':>18} "
                  f"{'80 % power at':>16} {'95 % power at':>16}"]
        for name, e in self.effects.items():
            head = f"{name} {e['axis']} ({_size(e['size'], e['unit'])})"
            for i, r in enumerate(e["per_experiment"]):
                if not r["testable"]:
                    pw = "not testable"
                else:
                    pw = _power(r)
                rn = "—"
                if "right_name" in r:
                    lo, hi = r["right_name_ci95"]
                    rn = f"{100 * r['right_name']:.0f} % [{100 * lo:.0f}, {100 * hi:.0f}]"
                lines.append(f"{head if i == 0 else '':<40} [{i}] {pw:>18} {rn:>18} "
                             f"{_mc_size(r, 80, e['unit']):>16} "
                             f"{_mc_size(r, 95, e['unit']):>16}")
        lines += _grid_notes(self.effects, s["runs"])
        if self.pairs:
            lines += ["", "Telling apart (A true, B the look-alike; the gap's 2 ln 10 margin):"]
            for e in self.pairs.values():
                a, b = e["names"]
                for i, r in enumerate(e["per_experiment"]):
                    pw = "not testable" if not r["testable"] else _power(r)
                    lines.append(f"  {a} ({_size(e['size'], e['unit'])}) vs {b}: [{i}] {pw}")
        return "\n".join(lines)
