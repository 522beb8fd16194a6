"""A noise level, or noise the drive adds while the table moves (:mod:`calib.gap.drive_noise`).

Runs are plain numpy here (a stop-and-go sweep: holds and moves at one speed, readings
``-g sin θ``, ``-g cos θ`` plus white noise), never the bench's or the validation's code.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import optimize, stats

from calib.files.course import Ensayo
from calib.gap import analyze_gap
from calib.gap.drive_noise import gain

G = 9.80665
STATED = (0.25, 0.64)


def _stop_and_go(rng, moving_var: tuple[float, float], held_var: tuple[float, float]):
    """Twelve holds of 2 s and moves of 1 s between them over one turn, 100 Hz; the noise
    variance of each axis is ``moving_var`` while moving and ``held_var`` while holding."""
    hold, move = 200, 100
    stops = np.linspace(0.0, 2 * np.pi, 13)
    th, mv = [], []
    for a, b in zip(stops[:-1], stops[1:], strict=True):
        th += [np.full(hold, a), a + (b - a) * np.arange(1, move + 1) / move]
        mv += [np.zeros(hold, bool), np.ones(move, bool)]
    th.append(np.full(hold, stops[-1]))
    mv.append(np.zeros(hold, bool))
    th, mv = np.concatenate(th), np.concatenate(mv)
    t = 0.01 * np.arange(th.size)
    a = np.column_stack([-G * np.sin(th), -G * np.cos(th)])
    sd = np.where(mv[:, None], np.sqrt(moving_var), np.sqrt(held_var))
    y = a * (1 + np.array([0.01, -0.02])) + np.array([0.1, -0.2]) + sd * rng.standard_normal(
        a.shape)
    return Ensayo(th, y, t, source="stop-and-go"), mv


@pytest.mark.parametrize("scale", [0.8, 1.0, 1.4])
def test_gain_is_the_difference_of_the_two_maximised_likelihoods(scale):
    """D against each model's Gaussian log-likelihood maximised numerically (scipy); at
    scale 0.8 the moving noise is below the stated one and the rival sits on its bound."""
    rng = np.random.default_rng(3)
    mv = np.arange(900) % 3 != 0
    e = rng.standard_normal(900) * np.where(mv, scale, 1.0) * 0.5
    s2 = 0.25

    def level(lv):
        return -2 * np.sum(stats.norm.logpdf(e, scale=np.exp(lv / 2)))

    def rival(lv):
        v = s2 + np.exp(lv)  # the moving variance: noise added to the sensor's, v ≥ s²
        return -2 * (np.sum(stats.norm.logpdf(e[mv], scale=np.sqrt(v)))
                     + np.sum(stats.norm.logpdf(e[~mv], scale=np.sqrt(s2))))

    lo = optimize.minimize_scalar(level, bounds=(-10, 5), method="bounded",
                                  options={"xatol": 1e-10}).fun
    ri = optimize.minimize_scalar(rival, bounds=(-30, 5), method="bounded",
                                  options={"xatol": 1e-10}).fun
    d, v = gain(e, mv, s2)
    assert d == pytest.approx(lo - ri, abs=1e-4)
    assert v == pytest.approx(max(np.mean(e[mv] ** 2), s2), rel=1e-12)


def test_noise_added_while_moving_is_said_and_the_noise_level_not_named():
    ens, _ = _stop_and_go(np.random.default_rng(11), moving_var=(0.25, 1.6),
                          held_var=STATED)
    a = analyze_gap(ens, STATED)
    found = [f for f in a.adequacy["drive_noise"] if f["axis"] == "y"]
    assert found and found[0]["decision"] == "leans", a.adequacy["drive_noise"]
    assert found[0]["moving_std"] == pytest.approx(np.sqrt(1.6), rel=0.15)
    assert ("noise_level", "y") not in a.named
    assert a.verdict == "unexplained"
    said = [u for u in a.unexplained if u["signature"] == "move_noise"]
    assert said and "while the table moves" in said[0]["description"]
    assert any(set(d["names"]) == {"noise_level", "move_noise"} for d in a.not_identifiable)


def test_a_true_noise_level_keeps_its_name():
    """The same design, the larger variance held and moving alike: the rival is far behind
    (D ≈ −n_h·(r − 1 − ln r) ≈ −100 for r = 1.6 over 2600 held samples)."""
    ens, _ = _stop_and_go(np.random.default_rng(12), moving_var=(0.25, 1.0),
                          held_var=(0.25, 1.0))
    a = analyze_gap(ens, STATED)
    assert ("noise_level", "y") in a.named and a.verdict == "explained", a.summary()
    assert a.adequacy["drive_noise"] == []

