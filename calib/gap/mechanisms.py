"""Mechanisms of a real bench the catalog does not have, looked for on the final model.

Four checks per axis, each with a p-value, judged in the adequacy battery
(:func:`calib.gap.adequacy.run_battery`, Bonferroni over the battery at its family α): a
failure makes the verdict "unexplained" and says what the mechanism is in words (none of them
is a catalog effect, so none is ever named).

``ringing``
    A lightly damped mode excited when the table stops (timed runs with holds). After each
    stop ``i`` (θ held after moving, ``s_i`` the sign of the move that stopped) the columns
    ``Σ_i s_i·e^{-ζω τ_i}·(cos ω_d τ_i, sin ω_d τ_i)`` and the same unsigned (``τ_i`` the time
    since the stop, from the stop on: the mode rings on through the hold and the next moves
    to the end of the run; ``ω_d = ω·sqrt(1 - ζ²)``) are added to the final model
    (GLS in its whitened space, :class:`calib.gap.space.AxisSpace`): ``ΔRSS ~ χ²(4)``,
    maximised over a grid of frequencies and damping ratios, Bonferroni over the grid. Reported:
    frequency, damping ratio, initial amplitude (the damped-mode fit on the segments after the
    stops).
``drive_angle``
    A vibration tied to the drive: ``cos νθ, sin νθ`` at an order ν of the drive angle (a gear
    or belt ratio, or a tooth count), searched on a grid of fractional ν up to
    :data:`DRIVE_ORDERS`' top and of whole ν up to :data:`MAX_TEETH` (a gear of up to 48
    teeth), ``ΔRSS ~ χ²(2)``, Bonferroni over the grid; with timing also
    the same columns times ``|ω|/max|ω|`` (a vibration growing with the drive speed; only
    when the speed varies, :data:`SPEED_CV`). The
    integer orders up to the ``harmonics`` check's last (6) are left out (1 and 2 are the
    catalog's scale, K2 and cross-axis; 3–6 the ``harmonics`` check's); a whole tooth count
    above them is a harmonic of θ nothing else looks for, so it is on the grid.
``settling``
    A settling transient after each stop (a relaxation of the mount or the sensor after a
    move, not oscillating): ``Σ_i s_i·e^{-τ_i/T}`` and the same unsigned (``τ_i`` the time since
    stop i, from its last moving sample to the end of the run: the relaxation goes on through
    the next moves), added to the final model: ``ΔRSS ~ χ²(2)``, maximised over a geometric
    grid of time constants T (:data:`SETTLE_TIMES`, fractions of the run's span, from two
    samples up), Bonferroni over the grid. Static runs too (time then in samples). The same
    columns are a rival of the random walk (:mod:`calib.gap.walk`), which absorbs a slow one.
``frozen``
    The output repeating one value exactly (a stuck register, dropped updates): the longest
    run of identical consecutive readings, L samples. With white noise of std σ rounded to a
    step ``lsb`` (0: not rounded), one level has probability at most
    ``p = 2Φ(lsb/2σ) - 1``, so ``P(some run ≥ L) ≤ N·p^{L-1}`` (union bound over the start;
    exactly 0 without rounding for L ≥ 2). Runs at the axis' extreme readings are left to
    saturation (an output stuck at its rail is a clipped reading).

Why by hand: these are the shapes of this bench; no library tests a damped mode after the
stops of a measured encoder or a frozen output against a rounded Gaussian's repeat law.
"""

from __future__ import annotations

import numpy as np

from calib import distributions as stats
from calib.conventions import AXES
from calib.effects import Extensions, ModelState
from calib.filters import constant_recursion, first_order_recursion
from calib.gap.space import AxisSpace, Check, order_columns

RING_FREQS = np.geomspace(0.5, 25.0, 24)
"""Frequencies (Hz) of the ringing grid (those below the Nyquist frequency / 2 are used)."""

RING_DAMPING = (0.02, 0.05, 0.1, 0.2, 0.4)
"""Damping ratios ζ of the ringing grid."""

SETTLE_TIMES = np.geomspace(1e-3, 0.25, 16)
"""Time constants T of the settling grid, fractions of the run's span (those of at least two
samples are used)."""

MIN_HOLD = 5
"""Fewest held samples after a stop for it to count."""

DRIVE_ORDERS = (0.5, 12.0)
"""Range of the fractional orders ν of the drive-angle grid (gear or belt ratios), spaced by
half a cycle over the run's angle range (``0.5/turns``, between 0.02 and 0.25); the integers
up to :data:`LAST_HARMONIC` are excluded."""

MAX_TEETH = 48
"""Whole orders (tooth counts) are searched from :data:`LAST_HARMONIC` + 1 up to this."""

SPEED_CV = 0.1
"""The drive-speed variant of the drive-angle check is searched only when ``|ω|`` varies by
more than this coefficient of variation: below it ``|ω|/max|ω|·cos νθ`` correlates with
``cos νθ`` at more than ``1/sqrt(1 + 0.1²)`` ≈ 0.995 (a constant sweep's ramps)."""

LAST_HARMONIC = 6
"""The highest integer order tested elsewhere (``harmonics`` check of the adequacy battery:
3–6; 1 and 2 are catalog effects): integer orders above it are on the drive grid."""


def drive_orders(turns: float) -> np.ndarray:
    """The orders ν searched for a run covering ``turns`` turns: fractional ones up to
    :data:`DRIVE_ORDERS`' top, and the whole tooth counts from :data:`LAST_HARMONIC` + 1 to
    :data:`MAX_TEETH` (a tooth count is a whole number: the fine grid is not needed there)."""
    step = float(np.clip(0.5 / max(turns, 1e-9), 0.02, 0.25))
    v = np.arange(DRIVE_ORDERS[0], DRIVE_ORDERS[1] + 1e-9, step)
    near = np.abs(v - np.round(v)) <= min(0.02, step / 2)
    v = v[~near | (np.round(v) > LAST_HARMONIC)]
    whole = np.arange(LAST_HARMONIC + 1, MAX_TEETH + 1, dtype=float)
    return np.unique(np.concatenate([v[np.abs(v - np.round(v)) > 1e-9], whole]))


def resolved_order(tita: np.ndarray) -> float:
    """The highest order ν of θ the run's angles resolve: ``π / (median gap between its
    sorted distinct angles)`` (half a period per typical gap at most; above it ``cos νθ`` at
    the visited angles aliases onto a lower order, or is any pattern over a few poses). The
    median, not the largest gap: a few poses spread unevenly over two turns (one wide gap)
    still resolve an order 2.5 that the wide gap alone would exclude."""
    u = np.unique(np.asarray(tita, dtype=float))
    gap = float(np.median(np.diff(u))) if u.size > 1 else np.inf
    return float(np.pi / gap) if gap > 0 else np.inf


def stops(run) -> list[tuple[int, int, float]]:
    """(first held sample, end of the hold, sign of the move that stopped) of each stop:
    θ moving, then held (equal consecutive θ) for at least :data:`MIN_HOLD` samples."""
    th = run.tita
    held = np.concatenate([[False], np.diff(th) == 0.0])  # held[i]: θ_i == θ_{i-1}
    edges = np.diff(np.concatenate([[0], held.astype(np.int8), [0]]))  # runs [start, stop)
    out = []
    for i, j in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        if i >= 2 and j - i >= MIN_HOLD:
            out.append((int(i), int(j), float(np.sign(th[i] - th[i - 2]) or 1.0)))
    return out


def _stop_kicks(run, hold: list[tuple[int, int, float]], dtype: type = float) -> np.ndarray:
    """(N, 2): at each stop's last moving sample ``i − 1``, the sign of the move that stopped
    (column 0) and 1 (column 1); zero elsewhere. The inputs of the stop responses."""
    kicks = np.zeros((run.n, 2), dtype=dtype)
    for i, _, s in hold:
        kicks[i - 1] += (s, 1.0)
    return kicks


def _ring_columns(run, hold: list[tuple[int, int, float]], f: float, zeta: float
                  ) -> np.ndarray:
    """(N, 4): ``Σ_i s_i·Re, Σ_i s_i·Im, Σ_i Re, Σ_i Im`` of ``e^{λτ_i}`` after each stop
    (τ_i ≥ 0 the time since its last moving sample, λ = −ζω + iω_d, ω = 2πf,
    ω_d = ω√(1 − ζ²)): the damped cos and sin of a mode rung by every stop.

    ``e^{λτ}`` sampled at the run's times is the impulse response of the one-pole complex
    filter ``y_k = p_k·y_{k−1} + x_k``, ``p_k = e^{λ(t_k − t_{k−1})}`` (the product of the
    poles from a stop to sample k is ``e^{λτ}``): every stop at once, in O(N), on a uniform
    grid (one pole) or not (a pole per step)."""
    w = 2.0 * np.pi * f
    lam = complex(-zeta * w, w * np.sqrt(1.0 - zeta**2))
    kicks = _stop_kicks(run, hold, complex)
    if run.h_uniform is not None:
        rings = constant_recursion(np.exp(lam * run.h_uniform), kicks)
    else:
        rings = first_order_recursion(np.exp(lam * np.diff(run.t, prepend=run.t[0])), kicks)
    return np.column_stack([rings[:, 0].real, rings[:, 0].imag,
                            rings[:, 1].real, rings[:, 1].imag])


def ringing(space: AxisSpace, run, axis: str) -> Check | None:
    """The damped mode after the stops (module docstring)."""
    if run.t is None:
        return None
    hold = stops(run)
    if not hold:
        return None
    h = float(np.median(np.diff(run.t)))
    grid = [(f, z) for f in RING_FREQS if f < 0.25 / h for z in RING_DAMPING]
    if not grid:
        return None
    f, z = grid[int(np.argmax(space.scan(lambda fz: _ring_columns(run, hold, *fz), grid)))]
    fit = space.test(_ring_columns(run, hold, f, z))
    if fit is None:
        return None
    stat, dof, coef = fit
    logp = min(0.0, float(np.log(len(grid)) + stats.chi2.logsf(stat, dof)))
    amp = float(max(np.hypot(coef[0], coef[1]), np.hypot(coef[2], coef[3])))
    return Check("ringing", axis, stat, logp, f"chi2({dof}) × {len(grid)} (f, ζ)", amp, "m/s²",
                 f"ringing after the stops on {axis}: a damped oscillation of {f:.3g} Hz "
                 f"(damping ratio {z:.2g}), {amp:.3g} m/s² at the stop, after each of "
                 f"{len(hold)} stops — a lightly damped mode of the table or the mount")


def settle_times(run) -> np.ndarray:
    """Time constants of the settling grid for this run (run's time unit)."""
    span = float(run.tcol[-1] - run.tcol[0])
    h = float(np.median(np.diff(run.tcol)))
    return SETTLE_TIMES[SETTLE_TIMES * span >= 2.0 * h] * span


def settling_columns(run, hold: list[tuple[int, int, float]], tconst: float) -> np.ndarray:
    """(N, 2): ``Σ_i s_i·e^{-τ_i/T}`` and ``Σ_i e^{-τ_i/T}`` after each stop (docstring; τ_i
    in the run's time column): the one-pole filter of :func:`_ring_columns` with the real
    pole ``e^{−(t_k − t_{k−1})/T}`` per step."""
    tc = run.tcol
    return first_order_recursion(np.exp(-np.diff(tc, prepend=tc[0]) / tconst),
                                 _stop_kicks(run, hold))


def settling(space: AxisSpace, run, axis: str) -> Check | None:
    """The settling transient after the stops (module docstring)."""
    hold = stops(run)
    grid = settle_times(run)
    if not hold or grid.size == 0:
        return None
    tconst = float(grid[int(np.argmax(space.scan(lambda c: settling_columns(run, hold, c),
                                                     grid)))])
    fit = space.test(settling_columns(run, hold, tconst))
    if fit is None:
        return None
    stat, dof, coef = fit
    logp = min(0.0, float(np.log(grid.size) + stats.chi2.logsf(stat, dof)))
    amp = float(max(abs(coef[0]), abs(coef[1])))
    unit = "s" if run.time_unit == "s" else "samples"
    return Check("settling", axis, stat, logp, f"chi2({dof}) × {grid.size} time constants",
                 amp, "m/s²",
                 f"a settling transient after the stops on {axis}: {amp:.3g} m/s² at the stop, "
                 f"decaying with a time constant of about {tconst:.3g} {unit}, after each of "
                 f"{len(hold)} stops (signed by the move {coef[0]:+.3g}, unsigned "
                 f"{coef[1]:+.3g} m/s²) — the mount or the sensor relaxing after a move")


def drive_grid(run) -> tuple[list, object] | None:
    """The drive-angle search of a run: its grid of (order, words, speed weight) and the
    column maker ``cols(g)`` (None when no order applies); shared by both axes."""
    th = run.tita
    turns = float(np.ptp(th)) / (2.0 * np.pi)
    top = resolved_order(th)
    orders = [v for v in drive_orders(turns) if v * turns >= 1.5 and v <= top]
    if not orders:
        return None
    speed = None
    if run.omega is not None:
        w = np.abs(run.omega)
        # a speed that hardly changes (coefficient of variation below SPEED_CV) gives the
        # same columns twice: the variant adds a test and no power
        if float(np.std(w)) > SPEED_CV * float(np.mean(w)):
            speed = w / max(float(np.max(w)), 1e-300)
    variants = [("", 1.0)] + ([] if speed is None else
                              [(" growing with the drive speed", speed[:, None])])
    grid = [(v, label, w) for label, w in variants for v in orders]
    at = order_columns(th)

    def cols(g):
        c = at(g[0])
        return c if isinstance(g[2], float) else c * g[2]

    return grid, cols


def drive_scans(spaces: list[AxisSpace], run) -> list[np.ndarray] | None:
    """ΔRSS of the drive-angle grid on each space (the two axes), the columns built once
    (:meth:`AxisSpace.scan_many`); None when no order applies."""
    made = drive_grid(run)
    if made is None:
        return None
    grid, cols = made
    return AxisSpace.scan_many(spaces, cols, grid)


def drive_angle(space: AxisSpace, run, axis: str, gains: np.ndarray | None = None
                ) -> Check | None:
    """A vibration at a non-integer order of the drive angle (module docstring); ``gains``
    the grid's ΔRSS already scanned on this space (:func:`drive_scans`)."""
    made = drive_grid(run)
    if made is None:
        return None
    grid, cols = made
    tests = len(grid)
    if gains is None:
        gains = space.scan(cols, grid)
    g = grid[int(np.argmax(gains))]
    fit = space.test(cols(g))
    if fit is None:
        return None
    stat, dof, coef = fit
    v, label = g[0], g[1]
    logp = min(0.0, float(np.log(tests) + stats.chi2.logsf(stat, dof)))
    amp = float(np.hypot(*coef[:2]))
    return Check("drive_angle", axis, stat, logp, f"chi2({dof}) × {tests} orders", amp, "m/s²",
                 f"a vibration tied to the drive on {axis}: order {v:.3g} of θ (a tooth count,"
                 f" a gear or belt ratio){label}, {amp:.3g} m/s²")


def frozen(readings: np.ndarray, sigma2: float, lsb: float, run, axis: str) -> Check | None:
    """The longest run of identical consecutive readings (module docstring)."""
    y = np.asarray(readings, dtype=float)
    n = y.size
    if n < 3:
        return None
    same = np.diff(y) == 0.0
    rails = (y[1:] == y.max()) | (y[1:] == y.min())
    same &= ~rails
    if not np.any(same):
        return None
    # longest run of True in `same` (L - 1 repeats: L identical samples)
    edges = np.diff(np.concatenate([[0], same.astype(int), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    longest = int(np.max(ends - starts))
    where = int(starts[np.argmax(ends - starts)])
    # the readings' resolution: the model's step, or the finest change seen (data written
    # with few decimals are rounded even when no lattice was named): never below it
    moves = np.abs(np.diff(y))
    lsb = max(lsb, float(moves[moves > 0].min()) if np.any(moves > 0) else 0.0)
    p = float(2.0 * stats.norm.cdf(lsb / (2.0 * np.sqrt(sigma2))) - 1.0) if lsb > 0 else 0.0
    logp = 0.0 if p >= 1.0 else (
        -np.inf if p <= 0.0 else min(0.0, float(np.log(n) + longest * np.log(p))))
    logp = max(logp, -745.0)  # a finite log p: exp() of it is still a float (0)
    when = f"t = {run.tcol[where]:.4g} s" if run.time_unit == "s" else f"sample {where}"
    total = int(np.sum(ends - starts + 1))
    return Check("frozen", axis, float(longest + 1), logp,
                 f"longest run of identical readings, P ≤ N·p^(L-1), p = {p:.3g}",
                 float(longest + 1), "samples",
                 f"the output on {axis} is frozen: {longest + 1} identical readings in a row "
                 f"from {when} ({total} repeated samples in all; zero local variance) — a stuck "
                 "output or dropped updates")


def mechanism_checks(ext: Extensions, state: ModelState, k: int, lattice_lsb: float = 0.0,
                     space: AxisSpace | None = None, drive_gains: np.ndarray | None = None
                     ) -> list[Check]:
    """The four checks on axis k of the final model (those that apply to this run);
    ``lattice_lsb`` the step of the lattice found on the readings (0: none); ``space`` the
    axis' :class:`AxisSpace` and ``drive_gains`` its drive-angle scan
    (:func:`drive_scans`), when already made."""
    axis = AXES[k]
    st = state.axes[k]
    run = ext.run
    space = AxisSpace(ext, state, k) if space is None else space
    found = [ringing(space, run, axis), settling(space, run, axis),
             drive_angle(space, run, axis, drive_gains),
             frozen(run.datos[:, k], st.sigma2, max(st.lsb, lattice_lsb), run, axis)]
    return [c for c in found if c is not None]
