"""The batched grid scan of the adequacy checks gives what one test per block gives.

``AxisSpace.scan`` is a fast path: with q = 0 it works in the centred image of the whitened
rows (``Extensions.white``), each block's QR is written out from its Gram matrix, and blocks
are whitened together. Each must give the ΔRSS that ``AxisSpace.test`` (pivoted QR
in the whitened rows, one block at a time) gives, for single columns, pairs and triples, a
block inside the model (ΔRSS 0), with and without a walk, and after ``without``. Data from
numpy only.
"""

from __future__ import annotations

import numpy as np
import pytest

from calib.conventions import G
from calib.effects import Extensions, ModelState
from calib.effects.run import RunData
from calib.gap.space import AxisSpace, order_columns

STATED = (0.25, 0.64)


def _space(q: float) -> tuple[AxisSpace, RunData]:
    rng = np.random.default_rng(7)
    n = 4000
    t = np.arange(n) / 100.0
    th = np.linspace(0.0, 4.0 * np.pi, n)
    datos = np.column_stack([-G * np.sin(th) * 1.01 + 0.05, -G * np.cos(th) * 0.99])
    datos += rng.normal(0.0, np.sqrt(STATED), (n, 2))
    datos[:, 0] += 0.2 * np.sin(7.3 * th)  # something for the scan to find
    run = RunData.build(th, datos, G, t=t)
    ext = Extensions(run, np.array([1.01, 0.99]))
    state = ModelState.nominal(STATED)
    st = state.axes[0]
    state = state.with_axis(0, type(st)(q=q, sigma2_stated=st.sigma2_stated))
    return AxisSpace(ext, state, 0), run


def _one_by_one(space: AxisSpace, make, grid) -> np.ndarray:
    out = []
    for g in grid:
        fit = space.test(make(g))
        out.append(0.0 if fit is None else fit[0])
    return np.array(out)


@pytest.mark.parametrize("q", [0.0, 0.05])
@pytest.mark.parametrize("width", [1, 2, 3])
def test_scan_gives_the_delta_rss_of_each_block(q, width):
    space, run = _space(q)
    th, tc = run.tita, run.tcol

    def make(v):
        cols = [np.cos(v * th), np.sin(v * th), tc * np.cos(v * th)][:width]
        return np.column_stack(cols)

    grid = list(np.linspace(3.1, 9.7, 23))
    scanned = space.scan(make, grid)
    assert scanned.shape == (len(grid),)
    np.testing.assert_allclose(scanned, _one_by_one(space, make, grid), rtol=1e-7, atol=1e-9)
    assert grid[int(np.argmax(scanned))] == pytest.approx(7.3, abs=0.3)


@pytest.mark.parametrize("q", [0.0, 0.05])
def test_a_block_inside_the_model_adds_nothing_and_a_partial_one_its_new_part(q):
    space, run = _space(q)
    th = run.tita
    inside = run.a_ref[:, 0]  # the scale column of axis x, already in the model

    def make(kind):
        if kind == "inside":
            return np.column_stack([inside, 2.0 * inside])
        if kind == "half":
            return np.column_stack([inside, np.sin(7.3 * th)])
        return np.column_stack([np.sin(7.3 * th), inside])

    grid = ["inside", "half", "half-reversed"]
    scanned = space.scan(make, grid)
    assert scanned[0] == pytest.approx(0.0, abs=1e-6)
    np.testing.assert_allclose(scanned[1:], _one_by_one(space, make, grid)[1:], rtol=1e-6)
    assert scanned[1] > 10.0


@pytest.mark.parametrize("q", [0.0, 0.05])
def test_scan_after_without_sees_what_is_left(q):
    space, run = _space(q)
    th = run.tita

    def make(v):
        return np.column_stack([np.cos(v * th), np.sin(v * th)])

    grid = list(np.linspace(3.1, 9.7, 23))
    left = space.without(make(7.3))
    scanned = left.scan(make, grid)
    np.testing.assert_allclose(scanned, _one_by_one(left, make, grid), rtol=1e-7, atol=1e-9)
    assert scanned[int(np.argmin(np.abs(np.array(grid) - 7.3)))] < 1e-6
    assert scanned.max() < space.scan(make, grid).max()


def test_order_columns_are_cos_and_sin_of_the_order_whatever_the_sequence():
    th = np.linspace(-3.0, 40.0, 5001)
    cols = order_columns(th)
    step = np.arange(0.5, 12.0, 0.03)
    asked = list(step) + [7.0, 8.0, 9.0, 0.5, 0.53, 0.53] + list(step[::-1])
    worst = max(np.max(np.abs(cols(v) - np.column_stack([np.cos(v * th), np.sin(v * th)])))
                for v in asked)
    assert worst < 32 * 1e-15 * np.max(np.abs(th)) * 4  # ORDER_CHAIN products (space.py)


def test_stop_responses_by_filter_equal_the_sum_over_stops():
    """The ringing and settling columns come from one-pole filters of the stops (a complex
    pole for the ringing, a real one for the settling; one pole on a uniform grid, one per
    step on a jittered one). They equal each stop's damped cos and sin, and its decaying
    exponential, written out here over the whole run after the stop
    (``calib.gap.mechanisms``)."""
    from calib.gap.mechanisms import _ring_columns, settling_columns, stops

    n = 3000
    th = np.zeros(n)
    for a, b, to in ((100, 300, 1.0), (900, 1000, -0.5), (1500, 1700, 2.0), (2400, 2450, 1.5)):
        th[a:b] = np.linspace(th[a - 1], to, b - a)
        th[b:] = to
    rng = np.random.default_rng(5)
    uniform = np.arange(n) / 200.0
    jittered = np.cumsum(rng.uniform(0.004, 0.006, n))
    for t in (uniform, jittered):
        run = RunData.build(th, np.zeros((n, 2)), G, t=t)
        hold = stops(run)
        assert len(hold) == 4 and (run.h_uniform is not None) == (t is uniform)
        for f, zeta in ((4.0, 0.03), (0.7, 0.2), (20.0, 0.02)):
            w = 2.0 * np.pi * f
            ring, settle = np.zeros((n, 4)), np.zeros((n, 2))
            for i, _, sign in hold:
                tau = run.t[i - 1:] - run.t[i - 1]
                env = np.exp(-zeta * w * tau)
                c = env * np.cos(w * np.sqrt(1.0 - zeta**2) * tau)
                si = env * np.sin(w * np.sqrt(1.0 - zeta**2) * tau)
                ring[i - 1:] += np.column_stack([sign * c, sign * si, c, si])
                e = np.exp(-(run.tcol[i - 1:] - run.tcol[i - 1]) / (1.0 / f))
                settle[i - 1:] += np.column_stack([sign * e, e])
            np.testing.assert_allclose(_ring_columns(run, hold, f, zeta), ring, rtol=0.0,
                                       atol=1e-12)
            np.testing.assert_allclose(settling_columns(run, hold, 1.0 / f), settle, rtol=0.0,
                                       atol=1e-12)
            assert np.max(np.abs(ring)) > 0.9


@pytest.mark.parametrize("q", [0.0, 0.05])
def test_each_column_alone_is_its_own_test_and_the_joint_is_test(q):
    """``AxisSpace.test_each``: the joint result is :meth:`test`'s; each column alone gives
    the ΔRSS and coefficient of :meth:`test` on that column alone (0 for a column in the
    model's span: here the constant, which the bias already is)."""
    space, run = _space(q)
    th = run.tita
    z = np.column_stack([np.cos(7.3 * th), np.sin(7.3 * th), np.ones(th.size),
                         (np.mod(th, 2 * np.pi) < 1.0).astype(float)])
    joint, drss, alone = space.test_each(z)
    ref = space.test(z)
    assert joint[0] == pytest.approx(ref[0], rel=1e-12) and joint[1] == ref[1] == 3
    for j in range(z.shape[1]):
        one = space.test(z[:, j:j + 1])
        if one is None:
            assert drss[j] == 0.0 and alone[j] == 0.0
            continue
        assert drss[j] == pytest.approx(one[0], rel=1e-9)
        assert alone[j] == pytest.approx(one[2][0], rel=1e-9)
    assert drss[2] == 0.0 and drss[0] > 0.0


@pytest.mark.parametrize("q", [0.0, 0.05])
def test_test_is_the_regression_of_the_whole_design(q):
    """``AxisSpace.test`` against the whitened system refitted whole by ``numpy.linalg.lstsq``
    (the model's columns and the block together): its ΔRSS is the drop of the RSS, and the
    block's coefficients are those of the joint fit (Frisch–Waugh–Lovell). With a column of
    the block in the model (the constant) and one repeated, the rank counts the new
    directions only and the fitted part of the block is the joint fit's."""
    space, run = _space(q)
    th = run.tita
    harmonics = [f(j * th) for j in (2, 3, 5, 7) for f in (np.cos, np.sin)]
    full = np.column_stack([*harmonics, np.sin(7.3 * th)])
    yw, hw, _, _, _ = space.ext.axis_system(0, space.st, False)

    def rss(x):
        return float(np.sum((yw - x @ np.linalg.lstsq(x, yw, rcond=None)[0]) ** 2))

    zw = space.ext.whiten(space.st, full)
    got = space.test(full)
    coef = np.linalg.lstsq(np.column_stack([hw, zw]), yw, rcond=None)[0][hw.shape[1]:]
    assert got[1] == full.shape[1]
    assert got[0] == pytest.approx(rss(hw) - rss(np.column_stack([hw, zw])), rel=1e-9)
    np.testing.assert_allclose(got[2], coef, rtol=1e-8, atol=1e-12)
    assert got[0] > 100.0  # the 7.3 rad⁻¹ line of _space is found

    deficient = np.column_stack([full, np.ones(th.size), full[:, -1]])
    got = space.test(deficient)
    assert got[1] == full.shape[1]
    assert got[0] == pytest.approx(rss(hw) - rss(np.column_stack([hw, zw])), rel=1e-9)
    fitted = space.ext.whiten(space.st, deficient) @ got[2]
    np.testing.assert_allclose(fitted, zw @ coef, rtol=0.0, atol=1e-8 * np.abs(zw @ coef).max())
