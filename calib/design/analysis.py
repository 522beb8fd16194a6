""":func:`analyze_design`: power of the gap detection for candidate experiments."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace

import numpy as np

from calib.calibration.ls import fit_axis
from calib.conventions import AXES, G, reference_accel
from calib.design import grid as mcgrid
from calib.design.experiments import Experiment
from calib.design.montecarlo import Cell, fraction, right_name, run_cells
from calib.design.pairs import PAIRS, pair_key, told_apart
from calib.design.power import (
    critical,
    lambda_for_power,
    noncentrality,
    power_from_lambda,
)
from calib.design.result import DesignResult
from calib.design.signals import LINEAR, SIMULATED, coefficients, size_of, size_unit
from calib.effects import AxisState, Extensions, ModelState, RunData, effect, stated_variances
from calib.gap.confusions import AMBIGUITY_LR
from calib.gap.selection import FAMILY_ALPHA, LATTICE_TESTS, candidate_list, first_step
from calib.stats.proportion import clopper_pearson
from calib.stats.runs import Mapper

DEFAULT_SIZES: dict[str, float] = {
    "misalignment": 0.005, "tilt_offset": 0.005, "nonlinearity_k2": 1e-3, "cross_axis": 1e-3,
    "bias_drift": 5e-3, "lever_arm": 0.05, "lowpass_lag": 0.05, "saturation": 9.6,
    "bias_random_walk": 0.02, "noise_level": 0.30, "quantization": 0.05}
"""Default size of each effect, in its unit (:func:`calib.design.signals.size_unit`)."""

LEVELS = (0.80, 0.95)


class _Design:
    """One experiment prepared: whitened nominal basis, the gap's α_step, effect columns."""

    def __init__(self, exp: Experiment, noise_var: np.ndarray, g: float, family_alpha: float):
        self.exp = exp
        th, t = exp.theta(), exp.times()
        a_r = reference_accel(th, g)
        self.sig = np.sqrt(noise_var)
        rng = np.random.default_rng(0)  # placeholder readings: testability needs columns only
        datos = a_r + rng.standard_normal(a_r.shape) * self.sig
        self.run = RunData.build(th, datos, g, t)
        self.ext = Extensions(self.run, np.ones(2))
        cands, _ = candidate_list(self.run)
        state = ModelState.nominal(noise_var)
        _, untestable = first_step(self.ext, state, cands)
        self.candidates = [c for c in cands if c not in untestable]
        self.n_tests = len(self.candidates) + LATTICE_TESTS
        self.alpha_step = family_alpha / self.n_tests
        n = exp.n
        self.basis = np.zeros((2 * n, 4))
        for k in range(2):  # H = [1, A_r] per axis, whitened by σ
            self.basis[k * n:(k + 1) * n, 2 * k] = 1.0 / self.sig[k]
            self.basis[k * n:(k + 1) * n, 2 * k + 1] = a_r[:, k] / self.sig[k]
        self.nominal = {}
        for k, a in enumerate(AXES):
            fit = fit_axis(th, a_r[:, k], a, float(noise_var[k]), g)
            self.nominal[a] = {"bias": float(fit.std[0]), "scale": float(fit.std[1])}

    def testable(self, name: str, axis: str) -> bool:
        key = (name, "both" if name == "tilt_offset" else axis)
        return key in self.candidates

    def columns(self, name: str, axis: str) -> np.ndarray:
        """Stacked whitened columns (2N, k) of a linear effect (zero on the other axis)."""
        n = self.exp.n
        if name == "tilt_offset":
            out = np.zeros((2 * n, 1))
            for k in range(2):
                out[k * n:(k + 1) * n, 0] = self.ext.tilt_column(k, AxisState()) / self.sig[k]
            return out
        k = AXES.index(axis)
        cols = effect(name).columns(self.ext, k, AxisState(linear=(name,)))
        out = np.zeros((2 * n, len(cols)))
        for j, c in enumerate(cols):
            out[k * n:(k + 1) * n, j] = c / self.sig[k]
        return out


def _linear_row(d: _Design, name: str, size: float, axis: str, gain: float = 1.0) -> dict:
    """Analytic power of one linear effect in one experiment (:mod:`calib.design.power`):
    the first selection step's, with the sensor gain 1 + scale multiplying the effect."""
    if not d.testable(name, axis):
        return {"testable": False}
    cols = d.columns(name, axis)
    coef = gain * coefficients(name, size, d.exp, axis)
    c = float(np.linalg.norm(coef))
    direction = coef / c if c > 0 else np.eye(coef.size)[-1]
    lam1 = noncentrality(d.basis, cols @ direction)
    df = cols.shape[1]
    crit = critical(d.alpha_step, df)
    lam = lam1 * c * c
    row = {"testable": True, "power": float(power_from_lambda(lam, df, crit)),
           "noncentrality": lam, "lambda_unit": lam1, "df": df, "critical": crit}
    sign = -1.0 if size < 0 else 1.0
    for p in LEVELS:
        cp = np.sqrt(lambda_for_power(p, df, crit) / lam1) if lam1 > 0 else np.inf
        s = size_of(name, float(cp) / gain, d.exp) if np.isfinite(cp) else None
        row[f"size_{round(100 * p)}"] = None if s is None else sign * s
    return row


def _pair_linear(d: _Design, a: str, b: str, size: float, axis: str) -> dict:
    """Analytic power to tell A (true, at ``size``) from B (:mod:`calib.design.pairs`)."""
    if not (d.testable(a, axis) and d.testable(b, axis)):
        return {"testable": False}
    sa = d.columns(a, axis) @ coefficients(a, size, d.exp, axis)
    basis = np.column_stack([d.basis, d.columns(b, axis)])
    lam = noncentrality(basis, sa)
    df = len(coefficients(a, size, d.exp, axis))
    return {"testable": True, "power": float(power_from_lambda(lam, df, AMBIGUITY_LR)),
            "noncentrality": lam}


def _hits(res: list, name: str, axis: str) -> int:
    """Runs in which the gap named ``name`` on ``axis`` (or both axes)."""
    return sum(any(n == name and a in (axis, "both") for n, a in named) for named, *_ in res)


def _right(res: list, name: str, axis: str) -> int:
    """Runs in which the whole workflow named exactly the right effect, verdict "explained"
    (:func:`calib.design.montecarlo.right_name`)."""
    return sum(right_name(named, conf, verdict, name, axis) for named, conf, verdict in res)


def _grid_row(s: np.ndarray, f: np.ndarray, sizes: list[float],
              to_size: Callable[[float], float], hits: list[int], runs: int) -> dict:
    """The grid entries of a Monte Carlo row (:mod:`calib.design.grid`): sizes, powers with
    their exact 95 % intervals, the isotonic fit, and the smallest sizes with 80 / 95 %
    (``size_P``, and ``size_P_mc``: relation "=", "<" or ">" in size, the bracketing grid
    sizes and the exact 95 % intervals of their powers)."""
    powers = [h / runs for h in hits]
    ci = [list(clopper_pearson(h, runs)) for h in hits]
    fit = mcgrid.isotonic(powers)
    rising = sizes[-1] > sizes[0]  # size grows with strength (saturation: it falls)
    out: dict = {"grid": {"factors": [float(x) for x in f], "strength": [float(x) for x in s],
                          "sizes": sizes, "hits": [int(h) for h in hits], "powers": powers,
                          "power_ci95": ci, "powers_monotone": [float(x) for x in fit],
                          "runs": int(runs)}}
    for p in LEVELS:
        sp, rel, k = mcgrid.smallest_strength(s, fit, p)
        idx = [k - 1, k] if rel == "=" else [0] if rel == "<" else [len(s) - 1]
        if not rising and rel != "=":
            rel = {"<": ">", ">": "<"}[rel]
        out[f"size_{round(100 * p)}"] = to_size(sp)
        out[f"size_{round(100 * p)}_mc"] = {"relation": rel, "bracket": [sizes[j] for j in idx],
                                            "bracket_power_ci95": [ci[j] for j in idx]}
    return out


ALPHA_MIN = 1e-12
"""Smallest family α: the per-step α (α/m, m ≤ a few dozen tests) must stay a normal float
whose χ² quantile is finite (a denormal α gives an infinite critical value)."""


def analyze_design(experiments: Sequence[Experiment], effects: Sequence[str],
                   sizes: Mapping[str, float] | None = None, noise_var=(0.25, 0.64),
                   family_alpha: float = FAMILY_ALPHA, axis: str = "x", runs: int = 20,
                   seed: int = 0, g: float = G, mapper: Mapper | None = None,
                   progress: Callable[[str], None] | None = None,
                   mc_grid: int = 0, gain: float = 1.0) -> DesignResult:
    """Power of the gap detection for each experiment and effect, and of the pairs.

    Parameters
    ----------
    experiments : candidate :class:`Experiment` s.  effects : catalog names
        (:data:`calib.design.signals.LINEAR` analytic, :data:`~calib.design.signals.SIMULATED`
        Monte Carlo).  sizes : effect → size in its unit (defaults :data:`DEFAULT_SIZES`).
    noise_var : (2,) stated σ², (m/s²)².  family_alpha : the gap's family α (its per-step α
        is ``family_alpha / m`` for each experiment).  axis : the axis carrying per-axis
        effects.  runs, seed : Monte Carlo runs per cell and seed (0 runs: analytic only).
    mapper : :class:`calib.stats.runs.Mapper` for the Monte Carlo.  progress : message callback.
    mc_grid : K ≥ 2: each Monte Carlo cell is also run at K sizes on a geometric grid of the
        effect's strength around the asked size (:mod:`calib.design.grid`; the same noise
        streams at every size), giving its 80 % / 95 % sizes; 0: the asked size only.
    gain : the sensor's gain 1 + scale (the effects act through it: a sensor reading 3 %
        low needs a 3 % larger effect for the same power); the stated sizes include it.

    With ``runs`` > 0 every testable cell, the linear effects included, is also run through
    the whole workflow (:func:`calib.gap.analyze_gap` on readings made from the effect's
    physics): ``right_name`` is the fraction of runs where it names exactly the right effect
    with the verdict "explained" (ties listed as not identifiable count), next to ``power``
    (linear: the first step's analytic power; Monte Carlo: named on its axis).

    Returns
    -------
    DesignResult

    Examples
    --------
    The power to detect a 0.005 rad misalignment with 2001 samples, a uniform static design
    against a reversing sweep (analytic: no Monte Carlo effect asked):

    >>> from calib.design import Experiment, analyze_design
    >>> res = analyze_design([Experiment("uniform", 2001, 0.314),
    ...                       Experiment("reversal", 2001, 0.314)], ["misalignment"])
    >>> [round(r["power"], 2) for r in res.effects["misalignment"]["per_experiment"]]
    [0.18, 0.16]
    """
    say = progress or (lambda _msg: None)
    sizes = {**DEFAULT_SIZES, **dict(sizes or {})}
    nv = stated_variances(noise_var)
    if not (np.isfinite(gain) and gain > 0):
        raise ValueError(f"gain (1 + scale) must be positive, got {gain}")
    if not ALPHA_MIN <= family_alpha < 1:
        raise ValueError(f"family_alpha must be in [{ALPHA_MIN:g}, 1), got {family_alpha}")
    if axis not in AXES:
        raise ValueError(f"axis must be x or y, got {axis!r}")
    if mc_grid:
        mcgrid.factors(mc_grid)  # K >= 2, else ValueError
    unknown = [e for e in effects if e not in LINEAR + SIMULATED]
    if unknown:
        raise ValueError(f"no design power for {', '.join(unknown)}; choose from "
                         f"{', '.join(LINEAR + SIMULATED)}")
    say(f"{len(experiments)} experiment(s): nominal fits and the gap's α per design")
    designs = [_Design(e, nv, g, family_alpha) for e in experiments]
    table: dict[str, dict] = {}
    for name in effects:
        table[name] = {"axis": "both" if name == "tilt_offset" else axis,
                       "size": float(sizes[name]), "unit": size_unit(name),
                       "method": "analytic" if name in LINEAR else "monte_carlo",
                       "per_experiment": [None] * len(designs)}
    cells, where = [], []
    for i, d in enumerate(designs):
        for name in effects:
            if name in LINEAR:
                row = _linear_row(d, name, sizes[name], axis, gain)
                table[name]["per_experiment"][i] = row
                if runs and row["testable"]:
                    cells.append(Cell(d.exp, name, float(sizes[name]), axis, (nv[0], nv[1]),
                                      g, family_alpha, gain))
                    where.append((i, name))
            elif name == "lowpass_lag" and not d.exp.timed:
                table[name]["per_experiment"][i] = {"testable": False}
            elif runs == 0:
                table[name]["per_experiment"][i] = {"testable": True, "power": None}
            else:
                cells.append(Cell(d.exp, name, float(sizes[name]), axis, (nv[0], nv[1]), g,
                                  family_alpha, gain))
                where.append((i, name))
    # grid cells (mc_grid): cell j's sizes share its spawn key (j,), so run r draws the same
    # noise at every size; the factor 1 of an odd K is cell j itself
    extra, keys, grids = [], [(j,) for j in range(len(cells))], []
    f = mcgrid.factors(mc_grid) if mc_grid else np.ones(0)
    for j, c in enumerate(cells if mc_grid else []):
        if c.name in LINEAR:  # analytic sizes: no grid
            grids.append(None)
            continue
        s0 = mcgrid.strength(c.name, c.size, nv, axis, g)
        def to_size(x, c=c):
            return mcgrid.size_from(c.name, x, c.size, nv, axis, g)
        ids, at = [], []
        for fk in f:
            if fk == 1.0:  # the asked size, exactly
                ids.append(j)
                at.append(c.size)
                continue
            ids.append(len(cells) + len(extra))
            at.append(to_size(s0 * fk))
            extra.append(replace(c, size=at[-1]))
            keys.append((j,))
        grids.append((s0 * f, ids, at, to_size))
    outcomes: list = []
    if cells:
        say(f"Monte Carlo: {len(cells) + len(extra)} cell(s) × {runs} runs through the gap "
            "detection")
        outcomes = run_cells(cells + extra, runs, seed, mapper,
                             lambda done, total: say(f"Monte Carlo chunks {done}/{total}"),
                             keys=keys)
    mc = {}
    for j, ((i, name), res) in enumerate(zip(where, outcomes[:len(cells)], strict=True)):
        right = {f"right_name{k[5:]}": v
                 for k, v in fraction(_right(res, name, axis), runs).items() if k != "runs"}
        if name in LINEAR:  # the analytic first-step row, and the whole workflow's
            table[name]["per_experiment"][i].update({**right, "runs": int(runs)})
            mc[(i, name)] = res
            continue
        row = {"testable": True, **fraction(_hits(res, name, axis), runs), **right}
        if mc_grid:
            s, ids, at, to_size = grids[j]
            row.update(_grid_row(s, f, at, to_size,
                                 [_hits(outcomes[k], name, axis) for k in ids], runs))
        table[name]["per_experiment"][i] = row
        mc[(i, name)] = res
    pairs: dict[str, dict] = {}
    for a, b in PAIRS:
        if a not in effects or b not in effects:
            continue
        entry = {"names": [a, b], "size": float(sizes[a]), "unit": size_unit(a),
                 "method": "analytic" if a in LINEAR and b in LINEAR else "monte_carlo",
                 "per_experiment": []}
        for i, d in enumerate(designs):
            if entry["method"] == "analytic":
                row = _pair_linear(d, a, b, sizes[a], axis)
            elif (i, a) in mc:
                ok = sum(told_apart(a, b, axis, named, conf)
                         for named, conf, _ in mc[(i, a)])
                row = {"testable": True, **fraction(ok, runs)}
            else:
                row = {"testable": False}
            entry["per_experiment"].append(row)
        pairs[pair_key(a, b)] = entry
    exps = []
    for d in designs:
        exps.append({**d.exp.to_dict(), "alpha_step": d.alpha_step, "n_tests": d.n_tests,
                     "nominal_std": d.nominal})
    settings = {"family_alpha": float(family_alpha), "noise_var": [float(v) for v in nv],
                "axis": axis, "runs": int(runs), "seed": int(seed), "g": float(g),
                "gain": float(gain),
                "ambiguity_lr": float(AMBIGUITY_LR)}
    if mc_grid:
        settings.update({"mc_grid": int(mc_grid), "mc_span": mcgrid.SPAN})
    return DesignResult(settings, tuple(exps), table, pairs)

