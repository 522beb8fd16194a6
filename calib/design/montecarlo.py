"""Monte Carlo power through the real gap detection (:func:`calib.gap.analyze_gap`).

Run r of a cell (experiment, effect) draws readings from its own stream
``run_seeds(seed, runs, spawn_key=(cell,))[r]`` (:mod:`calib.stats.runs`), so the numbers do not
depend on the chunking, the workers or the cluster. Each run is analysed exactly as a
measured file would be (same ``family_alpha``); the power estimate is the fraction ``p̂`` of
runs where the effect is named on its axis, with binomial std ``sqrt(p̂(1 - p̂)/R)``: with R
runs it supports claims to about ±2 of those std, no finer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calib.design.experiments import Experiment
from calib.design.signals import readings
from calib.files.course import Ensayo
from calib.stats.proportion import clopper_pearson
from calib.stats.runs import Mapper, chunk_ranges, run_seeds, serial_map

CHUNK = 10


@dataclass(frozen=True)
class Cell:
    """One Monte Carlo cell: the effect ``name`` at ``size`` on ``axis`` in ``exp``."""

    exp: Experiment
    name: str
    size: float
    axis: str
    noise_var: tuple[float, float]
    g: float
    family_alpha: float
    gain: float = 1.0


def _run_chunk(task: tuple[Cell, list[np.random.SeedSequence]]
               ) -> list[tuple[list, list, str]]:
    """(named (name, axis) pairs, not-identifiable name lists, verdict) of each run."""
    from calib.gap import analyze_gap

    cell, seeds = task
    out = []
    for ss in seeds:
        rng = np.random.default_rng(ss)
        y = readings(cell.exp, cell.name, cell.size, cell.axis, np.array(cell.noise_var),
                     cell.g, rng, cell.gain)
        ens = Ensayo(tita=cell.exp.theta(), datos=y, t=cell.exp.times(), source="<design>")
        res = analyze_gap(ens, list(cell.noise_var), cell.g, family_alpha=cell.family_alpha)
        out.append(([(e.name, e.axis) for e in res.effects],
                    [list(d["names"]) for d in res.not_identifiable], str(res.verdict)))
    return out


def run_cells(cells: list[Cell], runs: int, seed: int, mapper: Mapper | None = None,
              progress=None, keys: list[tuple[int, ...]] | None = None
              ) -> list[list[tuple[list, list, str]]]:
    """The runs of every cell (cell i uses spawn key ``keys[i]``, default (i,)), mapped in
    chunks of :data:`CHUNK` runs. ``progress(done, total)`` counts chunks.

    Cells sharing a spawn key share their noise streams run by run (common random numbers:
    :func:`calib.design.signals.readings` draws the same normals whatever the size), as the
    sizes of a grid (:mod:`calib.design.grid`) do."""
    mapper = mapper or serial_map
    keys = keys or [(i,) for i in range(len(cells))]
    tasks, owner = [], []
    for i, cell in enumerate(cells):
        seeds = run_seeds(seed, runs, spawn_key=keys[i])
        for rg in chunk_ranges(runs, CHUNK):
            tasks.append((cell, [seeds[j] for j in rg]))
            owner.append(i)
    results = mapper(_run_chunk, tasks, progress) if tasks else []
    per_cell: list[list] = [[] for _ in cells]
    for i, res in zip(owner, results, strict=True):
        per_cell[i].extend(res)
    return per_cell


def fraction(hits: int, runs: int) -> dict:
    """The power row of a count: p̂ = hits/R, its binomial std ``sqrt(p̂(1 - p̂)/R)``, and
    the exact 95 % interval (:func:`calib.stats.proportion.clopper_pearson`; what R runs support,
    also at p̂ = 0 or 1 where the std says nothing)."""
    p = hits / runs
    lo, hi = clopper_pearson(hits, runs)
    return {"power": float(p), "power_std": float(np.sqrt(p * (1.0 - p) / runs)),
            "power_ci95": [lo, hi], "runs": int(runs)}


def right_name(named: list, not_identifiable: list, verdict: str, name: str, axis: str
               ) -> bool:
    """Did the whole workflow name the right effect? The verdict is "explained" and the
    named set is exactly ``{(name, axis)}`` (axis "both" for tilt_offset), or a single other
    effect that a ``not_identifiable`` entry lists together with it (the documented ties:
    tilt offset / equal misalignments, lag / rotation at a constant rate)."""
    want = (name, "both" if name == "tilt_offset" else axis)
    got = {(n, a) for n, a in named}
    if verdict != "explained" or len(got) != 1:
        return False
    (n, a), = got
    if (n, a) == want:
        return True
    return any(name in names and n in names for names in not_identifiable) and \
        (a == want[1] or "both" in (a, want[1]))
