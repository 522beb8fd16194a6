"""The named effects of an axis or one step of the bias (:mod:`calib.gap.step_swap`).

On a stop-and-go run that turns one way, a function of time is a function of θ: a bias step
can be taken by the catalog's angle-shaped columns. The logs are made here with numpy from
the course signs (the stop-and-go tour of ``tests/test_gap_drive_state.py``); the comparison's
AIC gain is checked against least squares written here, a step taken by a misalignment is
said as not told apart, and a true misalignment keeps its name with nothing said.
"""

from __future__ import annotations

import numpy as np
import pytest

from calib.conventions import G
from calib.effects import Extensions, ModelState, RunData
from calib.gap.space import AxisSpace
from tests.test_gap_drive_state import STATED, _analyse, course_readings, stop_and_go


def _stepped(seed: int, size: float):
    """A one-way stop-and-go run (one turn) whose y bias steps by ``size`` σ at 55 % of the
    run (plus 37 samples per seed): (t, θ, readings, index of the step)."""
    t, th, _ = stop_and_go(seed=seed, turns=1.0)
    _, y = course_readings(th, seed)
    i0 = int(0.55 * th.size) + 37 * seed
    y[i0:, 1] += size * np.sqrt(STATED[1])
    return t, th, y, i0


def _chi2(th: np.ndarray, y: np.ndarray, cols: list[np.ndarray]) -> float:
    """RSS/σ² of y's readings on bias, scale (−g cos θ) and ``cols`` (numpy least squares)."""
    x = np.column_stack([np.ones(th.size), -G * np.cos(th), *cols])
    beta, *_ = np.linalg.lstsq(x, y[:, 1], rcond=None)
    r = y[:, 1] - x @ beta
    return float(r @ r / STATED[1])


def test_a_step_taken_by_a_misalignment_is_said_as_not_told_apart():
    """A step of 0.3 σ on y at 22.4 s is named a misalignment of y (the run turns one way:
    −g sin θ follows the clock); one step in its place fits as well after the place's charge
    (D ≈ 4, "describes"): the misalignment stays named and the pair is listed, with the step's
    time and size. D is the gain of least squares written here."""
    t, th, y, i0 = _stepped(1, 0.3)
    res = _analyse(t, th, y)
    assert res.named == [("misalignment", "y")], res.summary()
    (found,) = res.adequacy["step"]
    assert found["decision"] == "describes" and found["names"] == ["misalignment"]
    assert abs(found["at"] - t[i0]) < 0.3 and 0.15 < found["step"] < 0.45
    pairs = [p for p in res.not_identifiable if "bias_step" in p["names"]]
    assert pairs and pairs[0]["names"] == ["misalignment", "bias_step"]
    assert "cannot tell misalignment from a step of" in pairs[0]["reason"]
    i = int(np.searchsorted(t, found["at"]))
    n = th.size
    lr_step = _chi2(th, y, []) - _chi2(th, y, [(np.arange(n) >= i).astype(float)])
    lr_mis = _chi2(th, y, []) - _chi2(th, y, [-G * np.sin(th)])
    gain = (lr_step - 2.0 * (1.0 + np.log(n))) - (lr_mis - 2.0)
    assert found["gain"] == pytest.approx(gain, abs=1e-6)


@pytest.mark.parametrize("seed", range(4))
def test_a_true_misalignment_keeps_its_name_and_nothing_is_said(seed):
    """A rotation of y by 0.012 rad (about 10 of its std) on the same runs: named, and no
    step fits within the likelihood ratio of 10 of it."""
    t, th, _ = stop_and_go(seed=seed, turns=1.0)
    _, y = course_readings(th, seed)
    y[:, 1] += 0.012 * (-G * np.sin(th))
    res = _analyse(t, th, y)
    assert res.named == [("misalignment", "y")], res.summary()
    assert res.adequacy["step"] == []


def test_the_step_scan_gives_the_test_of_every_place():
    """:meth:`AxisSpace.step_scan` (cumulative sums, every place at once) equals
    :meth:`AxisSpace.test` of the step column place by place, with a misalignment in the
    model beside bias and scale."""
    t, th, y, _ = _stepped(2, 0.5)
    ext = Extensions(RunData.build(th, y, G, t), np.array([1.0, 1.0]))
    nominal = ModelState.nominal(STATED)
    state = nominal.with_axis(1, nominal.axes[1].add("misalignment"))
    space = AxisSpace(ext, state, 1)
    scan = space.step_scan()
    n = th.size
    assert scan.shape == (n - 1,)
    for i in (1, 5, 700, 2237, n - 6, n - 1):
        got = space.test((np.arange(n) >= i).astype(float)[:, None])[0]
        assert scan[i - 1] == pytest.approx(got, rel=1e-9, abs=1e-9), i
