"""Assertions several test files share: honest intervals over a Monte Carlo run of fits, two
JSON trees equal to a relative tolerance, a frozen result object."""

from __future__ import annotations

import json
from collections.abc import Iterable

import numpy as np
import pytest


def assert_honest_intervals(fits: Iterable, truth, p: float = 0.95) -> None:
    """R fits of simulated sets from a right model, each with ``params`` (k,), ``cov`` (k, k),
    ``conf_int(p)`` (k, 2) and ``lack_of_fit.p_value``: assert that they are honest.

    * Coverage: each parameter's p-interval holds the truth with probability p, so hits/R is
      binomial with sd sqrt(p(1 − p)/R); checked as |hits/R − p| ≤ 4 sd per parameter.
    * NEES (p̂ − p)ᵀ cov⁻¹ (p̂ − p) is χ²(k) with σ² given (with σ² estimated from d dof its
      mean is k·d/(d − 2), inside the band for the large d of these tests): its mean over R
      runs has sd sqrt(2k/R), checked within k ± 4 sd.
    * The lack-of-fit test rejects a right model at α = 0.05 with probability 0.05: its rate is
      checked within 4·sqrt(0.05·0.95/R).
    """
    truth = np.asarray(truth, dtype=float)
    k = truth.size
    hits = np.zeros(k)
    nees = []
    rejected = 0
    for fit in fits:
        lo, hi = fit.conf_int(p).T
        hits += (lo <= truth) & (truth <= hi)
        d = fit.params - truth
        nees.append(d @ np.linalg.solve(fit.cov, d))
        rejected += fit.lack_of_fit.p_value < 0.05
    R = len(nees)
    band = 4 * np.sqrt(p * (1 - p) / R)
    assert np.all(np.abs(hits / R - p) <= band), hits / R
    assert abs(np.mean(nees) - k) <= 4 * np.sqrt(2 * k / R), np.mean(nees)
    assert abs(rejected / R - 0.05) <= 4 * np.sqrt(0.05 * 0.95 / R), rejected / R


def assert_same_tree(got, want, rtol: float = 1e-12, where: str = "") -> None:
    """Equal JSON trees: the same keys, lengths and values, floats to ``rtol`` relative to
    ``want`` (absolute below 1): two routes to one result (a refit and a saved file, a .mat and
    its CSV) may round the last bits differently (BLAS on another memory layout)."""
    if isinstance(want, dict):
        assert isinstance(got, dict) and got.keys() == want.keys(), where
        for k in want:
            assert_same_tree(got[k], want[k], rtol, f"{where}.{k}")
    elif isinstance(want, list):
        assert isinstance(got, list) and len(got) == len(want), where
        for i, (x, y) in enumerate(zip(got, want, strict=True)):
            assert_same_tree(x, y, rtol, f"{where}[{i}]")
    elif isinstance(got, float) and isinstance(want, float):
        assert abs(got - want) <= rtol * max(1.0, abs(want)), (where, got, want)
    else:
        assert got == want, where


def assert_frozen_and_serialisable(result, field: str, array: np.ndarray) -> dict:
    """A result object (STYLE.md: frozen, read-only arrays): setting ``field`` raises
    AttributeError and writing into ``array``, one of its arrays, raises ValueError; its
    ``to_dict()`` goes through JSON text. Returns that JSON, parsed."""
    with pytest.raises(AttributeError):
        setattr(result, field, None)
    with pytest.raises(ValueError):
        array[(0,) * array.ndim] = 0.0
    return json.loads(json.dumps(result.to_dict()))


def result_only(doc: dict | str) -> dict:
    """A command's ``--json`` (a dict or its text) without how its logs were read
    (``provenance`` and the units of its numbers): two routes to one result read different
    files."""
    import json

    doc = dict(json.loads(doc) if isinstance(doc, str) else doc)
    doc.pop("provenance", None)
    if "units" in doc:
        doc["units"] = {k: v for k, v in doc["units"].items()
                        if not k.startswith("provenance.")}
    return doc
