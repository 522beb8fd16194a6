"""Practical significance (issue 33, item 2): an effect is named only when it changes the fit
by at least ``PRACTICAL_FRACTION`` of σ (:mod:`calib.gap.practical`); a quantization step far
below σ is reported, not named ("quantized at q = … m/s² (… σ), no effect on the fit").

The headline case: a clean log in raw counts (a CSV read with ``--units counts
--sensitivity``), whose lattice is 0.001 σ of the noise, gives ``nothing_detected`` — every
real log in counts used to be "explained" by ``quantization``. A lattice of 1 σ is still
named.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from bench.cli import main
from calib.files.course import validate_ensayo
from calib.gap import analyze_gap
from calib.gap.practical import (
    PRACTICAL_FRACTION,
    lattice_matters,
    mean_change,
    noise_change,
    quantization_change,
)

G0 = 9.80665
"""Standard gravity: counts are converted as ``counts / sensitivity · 9.80665``."""

STATED = (0.25, 0.64)


def _counts_log(path, n: int = 4001, sensitivity: float = 16384.0, seed: int = 0) -> None:
    """A clean full turn logged at 100 Hz in raw counts: ``t, ax, ay, theta`` (s, counts,
    counts, rad), course signs, the stated noise; lsb = 9.80665/16384 ≈ 0.0006 m/s²."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 100.0
    th = np.sort(rng.uniform(0.0, 2.0 * np.pi, n))
    ax = -G0 * np.sin(th) + np.sqrt(STATED[0]) * rng.standard_normal(n)
    ay = -G0 * np.cos(th) + np.sqrt(STATED[1]) * rng.standard_normal(n)
    cx, cy = (np.round(a / G0 * sensitivity).astype(int) for a in (ax, ay))
    rows = "\n".join(f"{t[i]:.2f},{cx[i]},{cy[i]},{th[i]:.9f}" for i in range(n))
    path.write_text("t,ax,ay,theta\n" + rows + "\n")


def test_the_rule_and_its_thresholds():
    assert PRACTICAL_FRACTION == 0.01
    s2 = 0.25
    assert not lattice_matters(0.0006, s2)  # 0.0012 σ
    assert not lattice_matters(0.48 * 0.5, s2) and lattice_matters(0.50 * 0.5, s2)
    assert quantization_change(0.5, s2) == pytest.approx(np.sqrt(1 + 1 / 12) - 1)
    assert mean_change(13.0, 4001) > PRACTICAL_FRACTION  # significant ⇒ practical at 4001
    assert mean_change(13.0, 10**6) < PRACTICAL_FRACTION  # not on a million samples
    assert noise_change(0.25 * 1.02, 0.25) == pytest.approx(np.sqrt(1.02) - 1)


def test_a_clean_log_in_raw_counts_names_nothing(tmp_path, capsys):
    log = tmp_path / "counts.csv"
    _counts_log(log)
    argv = ["gap", str(log), "--units", "counts", "--sensitivity", "16384", "--noise-var",
            "0.25,0.64", "--g", str(G0)]
    assert main([*argv, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["verdict"] == "nothing_detected", doc["unexplained"]
    assert doc["effects"] == [] and doc["consistent_after"]
    rep = {r["axis"]: r for r in doc["reported"]}
    assert set(rep) == {"x", "y"} and all(r["name"] == "quantization" for r in rep.values())
    assert rep["x"]["params"]["lsb"] == pytest.approx(G0 / 16384, rel=1e-6)
    assert rep["x"]["change"] < 1e-6
    assert "quantized at q = 0.0005986 m/s² (0.0012 σ) on x, no effect on the fit" in \
        rep["x"]["description"]
    for ax in "xy":
        assert doc["gap_before"][ax]["consistent"] and doc["gap_after"][ax]["consistent"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "verdict: nothing detected" in text
    assert "reported, not named: quantized at q =" in text


def test_a_lattice_of_one_sigma_is_still_named():
    rng = np.random.default_rng(5)
    n = 4001
    th = np.sort(rng.uniform(0.0, 2.0 * np.pi, n))
    y = np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)]) + rng.standard_normal(
        (n, 2)) * np.sqrt(STATED)
    lsb = 0.5  # 1 σ on x: Sheppard adds 1/12 of the variance, 4 % of the std
    y[:, 0] = lsb * np.round(y[:, 0] / lsb)
    res = analyze_gap(validate_ensayo(th, y, None), STATED)
    assert ("quantization", "x") in res.named and res.verdict == "explained", res.summary()
    assert not res.reported
