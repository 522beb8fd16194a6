"""Does a named bias random walk earn its place? Generic rivals and a battery on its own path.

A random walk can follow almost any slow residual: a transient, a jump, a box, two tones in
time, an error near 0 g, a vibration of the drive — and the residuals *after* it are then
white, so the adequacy battery on them sees nothing. Two things are asked of a walk the
selection named on an axis before it may explain anything (issue 20, item 1):

1. **It beats generic rivals of comparable flexibility by the same charged likelihood.** With
   the walk removed (the other named effects kept, their linear parameters refitted), each
   rival shape is added to the axis' whitened system (:class:`calib.gap.space.AxisSpace`);
   its gain ``LR_r`` in ``-2 log L`` is compared with the walk's ``LR_w`` (marginal
   likelihood: the path integrated out) by AIC: the walk keeps its place only when
   ``LR_w - 2·c_w > LR_r - 2·c_r`` for every rival, ``c`` the parameters charged — for a
   rival its coefficients **plus every searched location or frequency** (a searched
   frequency, a step's place, a bump's centre and width count one each), for the walk its q
   (1; 0 when q is fixed by a sensor profile, :mod:`calib.gap.walk` docs below). Rivals:

   ==================  ===========================================================  ======
   rival               columns (in time unless said)                                charge
   ==================  ===========================================================  ======
   ``polynomial``      Legendre P1 … P3 of time                                     3
   ``sinusoid``        cos, sin at the periodogram peak (refined) in the walk's     3
                       band (:func:`walk_band`: the frequencies a walk can follow)
   ``two_sinusoids``   the two strongest peaks in that band                         6
   ``direction``       direction of the last motion (±1)                            1
   ``backlash``        d and ``d·dA_r/dθ``, d the direction of the last motion      2
                       (an offset and a tilt that depend on it: backlash)
   ``gain_drift``      ``A_r·P1``, ``A_r·P2`` of time (a gain drifting in time)     2
   ``gain_step``       ``A_r`` times a step, at the best of a grid of places        2
   ``tilt_drift``      ``dA_r/dθ·P1``, ``dA_r/dθ·P2`` of time (a creeping tilt)     2
   ``warm_up``         ``e^{-(t - t₀)/T}`` from the start, T on a grid              2
   ``heating``         the travel so far ``∫|dθ|`` (normalised), timed moving runs  1
   ``step``            one step of the bias, at the best of a grid of places        2
   ``two_steps``       two steps (greedy on the grid, then the first re-placed)     4
   ``bump``            a Gaussian bump, centre and width on a grid                  3
   ``near_zero_g``     ``exp(-(A_r/w)²/2)`` of the axis' own reference, w on a grid 2
   ``drive_angle``     cos νθ, sin νθ at a searched order ν (not 1–6)               3
   ``settling``        signed and unsigned ``e^{-τ/T}`` after each stop, T on a grid 3
   ``response_bend``   ``max(A_r - κ, 0)`` or ``clip(A_r, -w, w)`` of the axis' own     2
                       specific force, κ or w on a grid (a bend, a dead zone)
   ==================  ===========================================================  ======

2. **Its own path passes a battery.** With the linear parameters at their final values,
   ``e = y - mean`` (no bias) is a local-level model ``e_k = b_k + v_k``: ``Δe`` has the
   tridiagonal covariance ``Σ_Δ = σ² T + diag(r)``, ``r_k = q² Δt_k``. Checks (each a
   p-value, judged in the adequacy battery at its Bonferroni level: family α over the whole
   battery):

   * ``walk_normality`` — D'Agostino-Pearson K² of the filter's normalised innovations
     (N(0, 1), independent under the model): ``χ²(2)``;
   * ``walk_whiteness`` — Ljung-Box of the innovations (:mod:`calib.gap.adequacy`);
   * ``walk_period`` — Fisher's g of the innovations' periodogram (exact for white noise);
   * ``walk_jump`` — the largest standardised smoothed increment ("auxiliary residual",
     Harvey & Koopman 1992, de Jong & Penzer 1998) ``u_k = (Σ_Δ⁻¹Δe)_k / sqrt((Σ_Δ⁻¹)_kk)``,
     exactly N(0, 1) each under the model: ``P(max|u| > x) ≤ m·2Φ(-x)`` (Bonferroni over the
     m increments; the extreme-value law of correlated normals is below it);
   * ``walk_stationarity`` — q fitted separately on the two halves of the run against one q
     for both (the increments' variance ratio between halves, by likelihood):
     ``LR ~ χ²(1)``;
   * ``walk_spectrum`` — the Allan variance of the path (:func:`flicker_test`, the GLS fit of
     :mod:`calib.noise.allan`): a walk's deviation rises as τ^½ beside the white noise's τ^-½; a
     flat flicker (1/f) floor B beside them is tested by its score z (one-sided normal).

A walk that loses to a rival or fails a check is **not named**: the verdict is "unexplained"
with a ``drifting_structure`` entry (reason "drifting structure") that says what the drift
looks like in words (the winning rival's shape, or the failed check's: "a step of 0.12 m/s² at
t = 41 s", "an oscillation of 0.3 Hz, 0.05 m/s²"). A rival that wins is never named either: it
is not in the catalog. The walk stays in the model while the other effects are estimated (it
keeps them from bending to the drift), so their estimates are reported, tentative.

A sensor profile (``gap --sensor``) fixes q: the walk is then part of the known noise, not a
free explanation, and is charged 0 parameters (:func:`walk_charge`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy import linalg as sla
from scipy import optimize

from calib import distributions as stats
from calib.conventions import AXES
from calib.effects import Extensions, ModelState
from calib.gap.flexibility import tridiagonal_inverse_diagonal
from calib.gap.mechanisms import (
    drive_orders,
    resolved_order,
    settle_times,
    settling_columns,
    stops,
)
from calib.gap.space import (
    AxisSpace,
    Check,
    backlash_columns,
    drift_extent,
    fisher_g_logp,
    gain_drift_columns,
    gain_drift_words,
    legendre_in_time,
    motion_direction,
    order_columns,
    spectral_peak,
    tilt_drift_columns,
)
from calib.gap.steps import describe, optimal_steps, two_level, walk_unlike
from calib.gap.switching import SWITCH_CHARGE, block_means, block_size, fit_switching
from calib.input_rules import DataError
from calib.noise.allan import MAX_FIT_SAMPLES, AxisNoise, fit_axis_noise

GRID = 120
"""Places on the grid of the step, two-step and bump rivals."""

WARM_UP = (0.01, 0.02, 0.04, 0.08, 0.15, 0.3, 0.6)
"""Time constants of the warm-up rival, fractions of the run."""

WIDTHS = (0.01, 0.03, 0.08, 0.2)
"""Widths of the bump rival, fractions of the run."""

ZERO_G_WIDTHS = (0.3, 0.6, 1.2, 2.4)
"""Widths w (m/s²) of the near-0 g rival ``exp(-(A_r/w)²/2)``."""

BEND_KNOTS = 24
"""Knots of the response-bend rival's hinge (quantiles 5 %–95 % of the axis' own A_r)."""

WALK_CHECKS = ("walk_normality", "walk_whiteness", "walk_period", "walk_jump",
               "walk_stationarity", "walk_spectrum", "walk_rivals")

SLOWEST_CYCLES = 1.0 / 3.0
"""Fewest cycles per run of the sinusoid rivals: periods up to three times the run (a
thermal cycle slower than the run bends the bias like a walk's slowest mode)."""

CYCLE_MARGIN = 12.0
"""AIC gain of a slow cycle over the walk beyond which the cycle may be preferred (when the
walk adds nothing beyond it, :func:`walk_beyond`, and the gain is also beyond
:data:`CYCLE_SHARE`); its false-reject rate on true walks is in :func:`slow_cycle`."""

CYCLE_SHARE = 0.15
"""The cycle's AIC gain over the walk as a share of the walk's own (``LR_w - 2·c_w``) beyond
which the cycle may be preferred: a strong walk's slowest mode is one tone's worth, so the
gain of a tone over a walk grows with the walk, and an absolute margin alone would reject
strong walks."""

WALK_BEYOND_ALPHA = 0.05
"""Level at which a walk is still needed beyond a slow cycle (then the walk is kept)."""

LEAN_MARGIN = 6.0
"""AIC gain of one column over the named effects it stands for (:mod:`calib.gap.swaps`: the
scale asymmetry against K2, K3 against the named set, a bias tied to the drive against the
lever arm) beyond which those effects are no longer presented as the explanation: the verdict
is "unexplained" and says the run cannot tell the two apart (decision ``"leans"``). A gain of
6 is a likelihood ratio of e³ ≈ 20 after the charges; Burnham & Anderson (2002, §2.6) give
ΔAIC 4–7 as "considerably less support" for the model behind. One column against one is a
difference of two nearly equal χ² gains, which a true catalog effect loses by chance now and
then: hence a wide margin (the studies in ``docs/gap.md``)."""

WALK_LEAN_MARGIN = 2.0
"""AIC gain of steps or two-level switching over the walk (:func:`step_drift`,
:func:`switching_drift`) beyond which the walk is no longer presented as the explanation,
even within the margin at which the steps replace it: the verdict is "unexplained" and says
the run cannot tell the two apart (decision ``"leans"``); at most 2 both are about as well
supported (Burnham & Anderson 2002, §2.6: ΔAIC 0–2) and the walk, the catalog's, is named
with the pair listed (``"describes"``). Narrower than :data:`LEAN_MARGIN`: a true walk rarely
fits worse than steps after their place charges (``python -m validation.switching.score
--analysis``, ``docs/gap.md``, "Steps or switching ahead of the walk"), while faint
telegraphs and staircases land between 2 and 6 often (seeds 3 and 4 of the drive part: 5 of
their 24 step-like runs were named a walk at gains 2.6–5.9)."""

NEAR_STEPS_MARGIN = 15.0
"""How far (AIC units, after their place charges) steps may fall short of the walk and still
stand beside it (decision ``"leans"``: the walk not named, the verdict says the two are not
told apart) — only when a walk adds **nothing** beyond the steps (its q fits 0 once they are in
the model: LR ≤ :data:`NOTHING_BEYOND_LR`) and the steps have a shape a walk has no reason to
make (:func:`calib.gap.steps.walk_unlike`: three or more of one sign, or two-level
switching). Each step pays ``2·(1 + ln N)`` for its size and place (18.6 at N = 4001), so a
staircase of four 0.4 σ steps that the path shows plainly fell 9.4 short of the walk that
follows it (seed 5 of the drive part). On the switching study's paths (``docs/gap.md``, *The
near tier*; seeds 2033 and 7033, N ≤ 6001) the tier took 0 + 1 more of 446 true walks at any
margin from 6 to 15 — 1, 2 or 3 steps of mixed signs are what a walk's path is cut into —
and 27 + 22 more of 237 staircases at 15 (20 + 16 at 10). Without the shape condition, 10
would have taken 11 walks; the validation set's 60 true walks (8–20 σ) lost 4."""

NOTHING_BEYOND_LR = 1e-6
"""LR of a walk beyond the steps at or below which it adds nothing (its q at the boundary, 0;
a threshold rather than exact 0 so rounding cannot flip the tier)."""

NESTED_TOP = 3
"""Rivals (those beating the walk by AIC, best first) tested on top of it."""

TIE_LOGP = 1e-9
"""Relative difference of two rivals' log p on top of the walk within which they fit alike
(the same shape in this run): ``walk_rivals`` says both."""

DRIVE_ORDERS = (0.5, 12.0)
"""Range of the orders ν of the drive-angle grid, spaced by half a cycle over the run's
angle range (``0.5/turns``, between 0.02 and 0.25); the integers are excluded (harmonics of
θ are the catalog's and the battery's)."""


@dataclass(frozen=True)
class Rival:
    """One rival shape in place of the walk: its gain in -2 log L, its charge, its words."""

    name: str
    lr: float
    charge: float
    size: float
    description: str
    cols: np.ndarray | None = field(default=None, compare=False, repr=False)
    searched: int = 1
    """How many shapes of this family were searched (grid places × frequencies …)."""

    @property
    def criterion(self) -> float:
        """AIC gain ``LR - 2·charge`` (larger is better)."""
        return float(self.lr - 2.0 * self.charge)

    def to_dict(self) -> dict:
        return {"name": self.name, "lr": float(self.lr), "charge": float(self.charge),
                "criterion": self.criterion, "size": float(self.size),
                "description": self.description}


@dataclass(frozen=True)
class WalkReview:
    """What :func:`review_walk` found on one axis.

    axis : "x" or "y".  lr : the walk's gain in -2 log L (marginal).  charge : parameters
    charged for it.  rivals : every rival tried.  checks : the battery on its own path
    (judged in the adequacy battery).  profile : q came from a sensor profile.
    """

    axis: str
    lr: float
    charge: float
    rivals: tuple[Rival, ...]
    checks: tuple[Check, ...]
    profile: bool = False
    failed: tuple[str, ...] = field(default=())
    cycle: dict | None = None
    """A structured drift or a slow cycle in time against the walk (:func:`structured_drift`,
    :func:`slow_cycle`): ``{"decision": "structure" | "slow_cycle" | "cannot_tell", "gain",
    "walk_beyond_lr", "walk_beyond_p", "description"}``, or None when the walk beats them by
    AIC or is needed beyond them."""
    steps: dict | None = None
    """Steps of the bias against the walk (:func:`step_drift`): ``{"decision": "steps" |
    "leans" | "describes" (:func:`steps_decision`), "pair" (the name beside the walk in
    ``not_identifiable``), "margin", "count", "gain", "share", "walk_beyond_lr",
    "walk_beyond_p", "size", "description", "cannot_tell"}``, or two-level switching
    (:func:`switching_drift`: the same keys and ``"model": "two_level_markov"``, ``"levels"``
    m/s², ``"rates_per_sample"``), or None when the walk beats them or is needed beyond them."""

    @property
    def cycle_wins(self) -> bool:
        """A slow cycle or a fixed shape (:func:`structured_drift`) is preferred to the walk
        by the charged likelihood (beyond :data:`CYCLE_MARGIN`) and the walk adds nothing
        beyond it."""
        return self.cycle is not None and self.cycle["decision"] in ("slow_cycle", "structure")

    @property
    def criterion(self) -> float:
        return float(self.lr - 2.0 * self.charge)

    @property
    def best_rival(self) -> Rival | None:
        return max(self.rivals, key=lambda r: r.criterion, default=None)

    @property
    def rival_wins(self) -> bool:
        """A rival beats the walk by AIC in its place **and** adds significantly on top of it
        (the ``walk_rivals`` check failed in the battery)."""
        return "walk_rivals" in self.failed

    def with_failed(self, failed: tuple[str, ...]) -> WalkReview:
        """The review with the names of its checks that failed in the battery."""
        return replace(self, failed=tuple(failed))

    @property
    def steps_win(self) -> bool:
        """Steps of the bias describe the drift better than the walk by the slow cycle's
        margins and a walk adds nothing beyond them (:func:`step_drift`)."""
        return self.steps is not None and self.steps["decision"] == "steps"

    @property
    def steps_lead(self) -> bool:
        """Steps or switching beat the walk by more than :data:`WALK_LEAN_MARGIN` (whether or not
        by the margin at which they replace it) and a walk adds nothing beyond them: the walk
        is not presented as the explanation."""
        return self.steps is not None and self.steps["decision"] in ("steps", "leans")

    @property
    def step_shaped(self) -> bool:
        """The drift is step-like: steps beat the walk by the charged likelihood and a walk
        adds nothing beyond them (whether or not by the margins)."""
        return self.steps is not None

    @property
    def earned(self) -> bool:
        """The walk may explain: no rival beats it, no steps describe the drift better and its
        own path passed every check."""
        return (not self.rival_wins and not self.failed and not self.cycle_wins
                and not self.steps_lead)

    def shape(self) -> str:
        """The drift in words: the steps' shape when the drift is step-like (one step, a
        staircase, two-level switching: :mod:`calib.gap.steps`), else the winning rival's,
        else the failed checks'."""
        if self.step_shaped and not self.earned:
            physical = max((r for r in self.rivals if r.name in STRUCTURED),
                           key=lambda r: r.criterion, default=None)
            steps_criterion = self.criterion + self.steps["gain"]
            if physical is None or physical.criterion <= steps_criterion:
                return self.steps["description"]
            return physical.description  # a physical shape fits better than bias steps
        if self.cycle_wins and not self.rival_wins and not self.failed:
            return self.cycle["description"]
        if self.rival_wins:
            return self.best_rival.description
        words = [c.description for c in self.checks if c.name in self.failed]
        return "; ".join(words) or "a drift the walk does not describe"

    def signature(self) -> dict:
        """The ``unexplained`` entry of a walk that did not earn its place."""
        best = self.best_rival
        if self.steps_lead and not self.rival_wins and not self.failed:
            st = self.steps
            what = ("two-level switching (a hidden Markov level, its switches integrated out)"
                    " beats" if st["pair"] == "bias_switching"
                    else f"{st['count']} step(s) beat")
            by = (f"more than {st['margin']:g}" if st["decision"] == "steps" else
                  f"more than {WALK_LEAN_MARGIN:g}, though within the margin "
                  f"{st['margin']:g} at which they would replace it: this run cannot tell "
                  "them apart, and the walk has less support")
            why = (f"{what} the random walk by {st['gain']:.4g} after "
                   f"their charges ({by}) and "
                   f"{_beyond_steps(st['walk_beyond_lr'], st['walk_beyond_p'])}")
            if st.get("near"):
                why = (f"{st['count']} step(s) come within {-st['gain']:.3g} of the random "
                       f"walk after their place charges (within {NEAR_STEPS_MARGIN:g}) and a "
                       f"walk adds nothing at all beyond them (its q fits 0, LR "
                       f"{st['walk_beyond_lr']:.3g}): this run cannot tell them apart"
                       if st["gain"] <= 0 else
                       f"{st['count']} step(s) fit as well as the random walk after their "
                       f"place charges (AIC gain {st['gain']:.3g}) and a walk adds nothing at "
                       f"all beyond them (its q fits 0): this run cannot tell them apart")
            size, stat = st["size"], st["gain"]
        elif self.rival_wins:
            why = (f"{best.name} (AIC gain {best.criterion:.4g}) beats the random walk "
                   f"({self.criterion:.4g}) and adds to it beyond chance")
            size, stat = best.size, best.criterion - self.criterion
        elif self.cycle_wins and not self.failed:
            what = ("a slow cycle" if self.cycle["decision"] == "slow_cycle"
                    else "a fixed shape")
            why = (f"{what} beats the random walk by {self.cycle['gain']:.4g} after "
                   f"their charges (more than {CYCLE_MARGIN:g} and {self.cycle['share']:.0%} of "
                   f"the walk's own gain) and a walk adds nothing beyond it "
                   f"(LR {self.cycle['walk_beyond_lr']:.3g})")
            size, stat = self.cycle["size"], self.cycle["gain"]
        else:
            why = "the random walk's own path fails " + ", ".join(self.failed)
            failed = [c for c in self.checks if c.name in self.failed]
            size, stat = (failed[0].size, failed[0].statistic) if failed else (0.0, 0.0)
        return {"axis": self.axis, "signature": "drifting_structure",
                "reason": "drifting structure", "size": float(size), "unit": "m/s²",
                "statistic": float(stat), "p_value": None,
                "description": f"drifting structure on {self.axis}: {self.shape()} "
                               f"({why}; the random walk is not named)"}

    def to_dict(self) -> dict:
        return {"axis": self.axis, "lr": float(self.lr), "charge": float(self.charge),
                "criterion": self.criterion, "profile": bool(self.profile),
                "earned": bool(self.earned), "rival_wins": bool(self.rival_wins),
                "failed_checks": list(self.failed), "cycle": self.cycle,
                "steps": self.steps,
                "rivals": [r.to_dict() for r in sorted(self.rivals,
                                                       key=lambda r: -r.criterion)]}


def walk_charge(ext: Extensions, k: int) -> float:
    """Parameters a walk on axis k is charged: its q (1), or 0 when a sensor profile states
    q (``ext.walk_bounds[k]``: measured, not fitted to these data)."""
    return 0.0 if k in getattr(ext, "walk_bounds", {}) else 1.0


# ----------------------------------------------------------------------------- rivals

def _where(run, i: int) -> str:
    return f"t = {run.tcol[i]:.4g} s" if run.time_unit == "s" else f"sample {i}"


def _time_unit(run) -> str:
    return "s" if run.time_unit == "s" else "samples"


def _best_on_grid(space: AxisSpace, make, grid) -> tuple[float, object, np.ndarray] | None:
    """(ΔRSS, grid point, coefficients) of the best column block ``make(point)`` (the grid
    scanned in one batch, :meth:`AxisSpace.scan`; the best refitted by :meth:`AxisSpace.test`)."""
    grid = list(grid)
    if not grid:
        return None
    gains = space.scan(make, grid)
    g = grid[int(np.argmax(gains))]
    fit = space.test(make(g))
    return None if fit is None else (fit[0], g, fit[2])


def _steps(space: AxisSpace, run) -> list[Rival]:
    n = run.n
    grid = np.unique(np.linspace(2, n - 3, GRID).astype(int))

    def step(i):
        return (np.arange(n) > i).astype(float)[:, None]

    one = _best_on_grid(space, step, grid)
    out = []
    if one is None:
        return out
    i1 = int(one[1])
    out.append(Rival("step", one[0], 2.0, abs(float(one[2][0])),
                     f"a step of {float(one[2][0]):+.3g} m/s² at {_where(run, i1)}",
                     step(i1), grid.size))
    two = _best_on_grid(space, lambda i: np.column_stack([step(i1), step(i)]),
                        grid[np.abs(grid - i1) > 1])
    if two is None:
        return out
    i2 = int(two[1])
    again = _best_on_grid(space, lambda i: np.column_stack([step(i), step(i2)]),
                          grid[np.abs(grid - i2) > 1])
    if again is not None and again[0] >= two[0]:
        two, i1 = again, int(again[1])
    (a, b), (first, second) = two[2], sorted([(i1, 0), (i2, 1)])
    sizes = (float(two[2][first[1]]), float(two[2][second[1]]))
    out.append(Rival("two_steps", two[0], 4.0, float(max(abs(a), abs(b))),
                     f"two steps of the bias: {sizes[0]:+.3g} m/s² at "
                     f"{_where(run, first[0])} and {sizes[1]:+.3g} m/s² at "
                     f"{_where(run, second[0])}",
                     np.column_stack([step(i1), step(i2)]), grid.size ** 2))
    return out


def _bump(space: AxisSpace, run) -> Rival | None:
    tc = run.tcol - run.tcol[0]
    span = float(tc[-1]) or 1.0
    centres = np.linspace(0.0, span, GRID // 2)
    grid = [(c, w * span) for w in WIDTHS for c in centres]
    best = _best_on_grid(space, lambda cw: np.exp(-0.5 * ((tc - cw[0]) / cw[1]) ** 2)[:, None],
                         grid)
    if best is None:
        return None
    (c, w), amp = best[1], float(best[2][0])
    unit = _time_unit(run)
    return Rival("bump", best[0], 3.0, abs(amp),
                 f"a transient of {amp:+.3g} m/s² around {_where(run, int(np.argmin(abs(tc - c))))}"
                 f" (width {w:.3g} {unit})",
                 np.exp(-0.5 * ((tc - c) / w) ** 2)[:, None], len(grid))


def walk_band(run, q: float, sigma2: float) -> float:
    """Cycles per run below which the walk's path can follow a shape: an octave above the
    corner where its steps' spectrum ``q²Δt`` meets the differenced noise's
    ``σ²·|2 sin πf|²`` (``2 sin πf_c = q√Δt/σ``), at least 4. Above it the walk absorbs
    little: a faster oscillation is the ``periodic`` / ``walk_period`` checks' business, so the
    sinusoid rivals search (and are charged for) the band only."""
    dt = float(np.median(np.asarray(run.dt_walk, dtype=float)))
    x = min(1.0, q * np.sqrt(dt) / (2.0 * np.sqrt(max(sigma2, 1e-300))))
    return float(max(4.0, 2.0 * np.arcsin(x) / np.pi * (run.n - 1)))


def _sinusoids(space: AxisSpace, run, band: float | None = None) -> list[Rival]:
    peak = spectral_peak(space, run, min_cycles=SLOWEST_CYCLES, max_cycles=band)
    if peak is None:
        return []
    cols1, period1 = peak[4], peak[3]
    fit1 = space.test(cols1)
    if fit1 is None:
        return []
    unit = _time_unit(run)

    def words(period: float, amp: float) -> str:
        if run.time_unit == "s":
            return f"an oscillation of {1.0 / period:.3g} Hz (period {period:.4g} s), " \
                   f"{amp:.3g} m/s²"
        return f"an oscillation with period {period:.4g} {unit}, {amp:.3g} m/s²"

    amp1 = float(np.hypot(*fit1[2]))
    m = 2 * peak[2]  # Fourier frequencies, each refined between its neighbours
    out = [Rival("sinusoid", fit1[0], 3.0, amp1, words(period1, amp1), cols1, m)]
    # the second tone: the periodogram peak of what the first leaves
    peak2 = spectral_peak(space.without(cols1), run, min_cycles=SLOWEST_CYCLES,
                          max_cycles=band)
    if peak2 is None:
        return out
    cols = np.column_stack([cols1, peak2[4]])
    fit = space.test(cols)
    if fit is not None:
        amp2 = float(np.hypot(*fit[2][2:4]))
        out.append(Rival("two_sinusoids", fit[0], 6.0, max(amp1, amp2),
                         "two oscillations: " + words(period1, amp1) + " and "
                         + words(peak2[3], amp2), cols, m * m))
    return out


def _drive_angle(space: AxisSpace, run) -> Rival | None:
    th = run.tita
    turns = float(np.ptp(th)) / (2.0 * np.pi)
    if turns < 0.5:
        return None
    top = resolved_order(th)
    orders = [v for v in drive_orders(turns) if v * turns >= 1.0 and v <= top]
    best = _best_on_grid(space, order_columns(th), orders)
    if best is None:
        return None
    amp, v = float(np.hypot(*best[2])), float(best[1])
    return Rival("drive_angle", best[0], 3.0, amp,
                 f"a vibration tied to the drive angle: order {v:.3g} of θ (a tooth count or "
                 f"a gear ratio), {amp:.3g} m/s²",
                 np.column_stack([np.cos(v * th), np.sin(v * th)]), len(orders))


def _backlash(space: AxisSpace, run, k: int) -> Rival | None:
    """The reading depends on the direction of the last motion as an offset and as an angle
    (:func:`calib.gap.space.backlash_columns`): a drive's backlash, which a walk follows move
    by move on a back-and-forth run."""
    cols = backlash_columns(run, k)
    fit = None if cols is None else space.test(cols)
    if fit is None:
        return None
    off, ang = 2.0 * float(fit[2][0]), 2.0 * float(fit[2][1])
    return Rival("backlash", fit[0], float(fit[1]), float(2.0 * np.max(np.abs(cols @ fit[2]))),
                 f"the reading on {AXES[k]} depends on the direction of the last motion: up "
                 f"minus down {off:+.3g} m/s² and {np.degrees(ang):+.3g}° of tilt (backlash "
                 "of the drive, or hysteresis)", cols, 1)


def _gain_step(space: AxisSpace, run, k: int) -> Rival | None:
    """The axis' gain steps once during the run: ``A_r·[sample > i]`` at the best of the step
    grid (charge 2: the size and the place)."""
    n = run.n
    a = run.a_ref[:, k]
    grid = np.unique(np.linspace(2, n - 3, GRID).astype(int))

    def col(i):
        return (a * (np.arange(n) > i))[:, None]

    best = _best_on_grid(space, col, grid)
    if best is None:
        return None
    i, c = int(best[1]), float(best[2][0])
    return Rival("gain_step", best[0], 2.0, abs(c) * float(np.max(np.abs(a))),
                 f"the gain on {AXES[k]} steps by {c:+.3g} ({1e6 * c:+.0f} ppm) at "
                 f"{_where(run, i)}", col(i), grid.size)


def _in_time(space: AxisSpace, run, name: str, cols: np.ndarray, words) -> Rival | None:
    """A rival whose columns are a signature times ``P1(t)``, ``P2(t)`` (a creeping tilt, a
    drifting gain): ``words(c)`` says it with ``c`` the largest change over the run of the
    parameter that drifts (the coefficient polynomial's largest |value|)."""
    fit = space.test(cols)
    if fit is None:
        return None
    return Rival(name, fit[0], float(fit[1]), float(np.max(np.abs(cols @ fit[2]))),
                 words(drift_extent(run, fit[2])), cols, 1)


def _tilt_drift(space: AxisSpace, run, k: int) -> Rival | None:
    """A tilt that creeps during the run (:func:`calib.gap.space.tilt_drift_columns`)."""
    return _in_time(space, run, "tilt_drift", tilt_drift_columns(run, k),
                    lambda c: f"the tilt of {AXES[k]} creeps during the run by up to "
                              f"{np.degrees(c):.3g}° (the mount or the sensor turning slowly)")


def _warm_up(space: AxisSpace, run) -> Rival | None:
    """A transient from the start of the run, ``e^{-(t - t₀)/T}`` with T on a grid of
    :data:`WARM_UP` fractions of the run (charge 2: the size and T): a sensor warming up
    after power-on, which a walk follows as a drift that slows down."""
    tc = run.tcol - run.tcol[0]
    span = float(tc[-1]) or 1.0
    grid = [f * span for f in WARM_UP]
    best = _best_on_grid(space, lambda tconst: np.exp(-tc / tconst)[:, None], grid)
    if best is None:
        return None
    tconst, amp = float(best[1]), float(best[2][0])
    return Rival("warm_up", best[0], 2.0, abs(amp),
                 f"a transient from the start: {amp:+.3g} m/s² at the start, decaying with a "
                 f"time constant of about {tconst:.3g} {_time_unit(run)} (a warm-up after "
                 "power-on)", np.exp(-tc / tconst)[:, None], len(grid))


def _heating(space: AxisSpace, run) -> Rival | None:
    """A bias that follows the motion done so far, ``∫|ω|dt`` normalised to 1 at the end
    (charge 1, no search): a motor or bearing that warms the sensor while the table moves,
    and not while it holds. Only for runs with rates that hold and move."""
    if run.omega is None or np.ptp(np.abs(run.omega)) <= 1e-9:
        return None
    h = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(run.tita)))])
    if not h[-1] > 0:
        return None
    col = (h / h[-1])[:, None]
    fit = space.test(col)
    if fit is None:
        return None
    amp = float(fit[2][0])
    return Rival("heating", fit[0], 1.0, abs(amp),
                 f"a bias that grows with the motion done so far ({amp:+.3g} m/s² over the "
                 "run's total travel, nothing while the table holds): the drive warming the "
                 "sensor", col, 1)


def _gain_drift(space: AxisSpace, run, k: int) -> Rival | None:
    """The axis' gain changes during the run (:func:`calib.gap.space.gain_drift_columns`): a
    temperature coefficient of the scale factor, which a walk follows as a bias that swings
    with the specific force."""
    return _in_time(space, run, "gain_drift", gain_drift_columns(run, k),
                    lambda c: gain_drift_words(AXES[k], c))


def _settling(space: AxisSpace, run) -> Rival | None:
    """A settling transient after the stops (:func:`calib.gap.mechanisms.settling`)."""
    hold = stops(run)
    grid = settle_times(run)
    if not hold or grid.size == 0:
        return None
    best = _best_on_grid(space, lambda c: settling_columns(run, hold, c), grid)
    if best is None:
        return None
    tconst, amp = float(best[1]), float(np.max(np.abs(best[2])))
    return Rival("settling", best[0], 3.0, amp,
                 f"a settling transient after each of {len(hold)} stops: {amp:.3g} m/s² at "
                 f"the stop, time constant about {tconst:.3g} {_time_unit(run)}",
                 settling_columns(run, hold, tconst), grid.size)


def _bend_column(a: np.ndarray, g: tuple[str, float]) -> np.ndarray:
    kind, v = g
    return (np.maximum(a - v, 0.0) if kind == "hinge" else np.clip(a, -v, v))[:, None]


def _response_bend(space: AxisSpace, ext: Extensions, k: int) -> Rival | None:
    """The response bends at a level of the axis' own specific force ``A_r``: a hinge
    ``max(A_r - κ, 0)`` (the gain changes at κ: a scale asymmetry at κ = 0) at κ on the
    quantiles of ``A_r``, or a band ``clip(A_r, -w, w)`` (the gain differs within ±w: a dead
    zone) at w on the near-0 g grid. A walk follows it where ``A_r`` moves slowly; it is a
    fixed function of the specific force, which a walk is not."""
    a = ext.run.a_ref[:, k]
    grid = ([("hinge", float(v)) for v in np.quantile(a, np.linspace(0.05, 0.95, BEND_KNOTS))]
            + [("band", float(w)) for w in ZERO_G_WIDTHS if w < float(np.max(np.abs(a)))])
    best = _best_on_grid(space, lambda g: _bend_column(a, g), grid)
    if best is None:
        return None
    (kind, v), c = best[1], float(best[2][0])
    words = (f"the gain on {AXES[k]} changes by {c:+.3g} where the specific force exceeds "
             f"{v:.3g} m/s² (a bend of the response)" if kind == "hinge" else
             f"the gain on {AXES[k]} differs by {c:+.3g} within ±{v:.2g} m/s² of 0 g (a dead "
             "zone or a bend of the response near 0 g)")
    return Rival("response_bend", best[0], 2.0, abs(c) * v if kind == "band" else abs(c),
                 words, _bend_column(a, (kind, v)), len(grid))


def _near_zero_g(space: AxisSpace, ext: Extensions, k: int) -> Rival | None:
    a = ext.run.a_ref[:, k]
    best = _best_on_grid(space, lambda w: np.exp(-0.5 * (a / w) ** 2)[:, None], ZERO_G_WIDTHS)
    if best is None:
        return None
    amp, w = float(best[2][0]), float(best[1])
    return Rival("near_zero_g", best[0], 2.0, abs(amp),
                 f"an error near 0 g on {AXES[k]}: {amp:+.3g} m/s² where the specific force "
                 f"is within about {w:.2g} m/s² of zero",
                 np.exp(-0.5 * (a / w) ** 2)[:, None], len(ZERO_G_WIDTHS))


def rivals(ext: Extensions, reduced: ModelState, k: int, band: float | None = None
           ) -> list[Rival]:
    """Every rival shape on axis k of ``reduced`` (the model without the walk); ``band``: the
    cycles per run the sinusoids search (:func:`walk_band`; None: every frequency)."""
    run = ext.run
    space = AxisSpace(ext, reduced, k)
    out: list[Rival] = []
    poly = space.test(legendre_in_time(run, (1, 2, 3)))
    if poly is not None:
        cols = legendre_in_time(run, (1, 2, 3))
        out.append(Rival("polynomial", poly[0], float(poly[1]),
                         float(np.ptp(cols @ poly[2])),
                         f"a smooth drift in time (polynomial, range "
                         f"{float(np.ptp(cols @ poly[2])):.3g} m/s²)", cols, 1))
    out += _sinusoids(space, run, band)
    d = motion_direction(run.tita)
    if d is not None:
        fit = space.test(d[:, None])
        if fit is not None:
            out.append(Rival("direction", fit[0], 1.0, abs(2.0 * float(fit[2][0])),
                             f"the reading depends on the direction of the last motion (up "
                             f"minus down {2.0 * float(fit[2][0]):+.3g} m/s²)", d[:, None], 1))
    out += [r for r in (_backlash(space, run, k), _gain_drift(space, run, k),
                        _gain_step(space, run, k), _tilt_drift(space, run, k),
                        _warm_up(space, run), _heating(space, run)) if r is not None]
    out += _steps(space, run)
    for r in (_bump(space, run), _near_zero_g(space, ext, k), _drive_angle(space, run),
              _settling(space, run), _response_bend(space, ext, k)):
        if r is not None:
            out.append(r)
    return out


# ------------------------------------------------------------------ the walk's own path

def _banded(sigma2: float, r: np.ndarray) -> np.ndarray:
    """``Σ_Δ = σ² T + diag(r)`` in the upper banded form of ``scipy.linalg``."""
    ab = np.empty((2, r.size))
    ab[0, 0] = 0.0
    ab[0, 1:] = -sigma2
    ab[1] = 2.0 * sigma2 + r
    return ab


def _local_level_nll(de: np.ndarray, sigma2: float, r: np.ndarray) -> float:
    """``log det Σ_Δ + Δeᵀ Σ_Δ⁻¹ Δe`` (-2 log L of the differenced local level, no 2π)."""
    c = sla.cholesky_banded(_banded(sigma2, r))
    x = sla.cho_solve_banded((c, False), de)
    return float(2.0 * np.sum(np.log(c[1])) + de @ x)


def _stationarity(de: np.ndarray, sigma2: float, dt: np.ndarray, q: float, run, axis: str
                  ) -> Check | None:
    """One q for both halves against one q each: LR ~ χ²(1)."""
    m = de.size
    if m < 40 or q <= 0:
        return None
    h = m // 2
    parts = [(de[:h], dt[:h]), (de[h + 1:], dt[h + 1:])]
    lo, hi = np.log(q) - 10.0, np.log(q) + 6.0

    def nll(lq: float, part) -> float:
        return _local_level_nll(part[0], sigma2, np.exp(2.0 * lq) * part[1])

    def best(f) -> tuple[float, float]:
        res = optimize.minimize_scalar(f, bounds=(lo, hi), method="bounded",
                                       options={"xatol": 1e-4})
        return float(res.x), float(res.fun)

    both = best(lambda lq: nll(lq, parts[0]) + nll(lq, parts[1]))
    each = [best(lambda lq, p=p: nll(lq, p)) for p in parts]
    lr = max(both[1] - each[0][1] - each[1][1], 0.0)
    q1, q2 = np.exp(each[0][0]), np.exp(each[1][0])
    unit = "m/s²/√s" if run.time_unit == "s" else "m/s²/√sample"
    mid = _where(run, h)
    faster = "second" if q2 > q1 else "first"
    return Check("walk_stationarity", axis, lr, float(stats.chi2.logsf(lr, 1)), "chi2(1)",
                 float(abs(q2 - q1)), unit,
                 f"the bias on {axis} moves faster in the {faster} half of the run (q = "
                 f"{q1:.3g} before {mid}, {q2:.3g} after, {unit}): not a stationary walk, "
                 "a drift confined to part of the run")


FLICKER_TAIL = 4
"""Longest octaves of τ over which the Allan-deviation slope is reported (``walk_spectrum``)."""


def flicker_test(e: np.ndarray, rate: float = 1.0) -> AxisNoise | None:
    """Overlapping Allan variance of the walk's path with the flicker term resolved or not.

    ``e`` (N,) the readings minus the model's mean without the bias (m/s²): under the local
    level a white noise plus a random walk, whose Allan variance is
    ``AVAR(τ) = N²/τ + K²τ/3`` (slopes −½ and +½ of the deviation, IEEE Std 952 Annex C). A bias
    that wanders like flicker (1/f) noise adds the flat floor ``(2 ln 2/π)·B²`` (slope 0) that a
    walk has not. :func:`calib.noise.allan.fit_axis_noise` fits the three terms by GLS on the octave
    Allan variances with their full covariance and tests ``B = 0`` by a score test with the
    white and walk terms refitted (z, one-sided p); ``walk_spectrum`` is that test. Its
    false-reject rate on walks (white noise plus a walk, q√N = 1–16 σ, N = 2001 and 4001,
    even and bursty steps; 1600 runs, /tmp experiments repeated in
    ``tests/test_gap_walk.py``): 4.3 % at p < 0.05, 1.2 % at 0.01, 0.13 % at 0.001, 0 below
    1e-4. On 1/f noise of 0.27 σ on N = 4001 (the size that a walk absorbs unseen) it rejects
    at p < 5e-4 in half the runs, where a Whittle fit of the spectral exponent on the
    differenced path did in none (the white level free in both; the Allan fit's long-τ
    octaves carry the walk-versus-floor contrast).

    ``rate`` : samples per time unit (Hz, or 1 per sample). Runs longer than
    :data:`calib.noise.allan.MAX_FIT_SAMPLES` are averaged in blocks of 2^k samples first (as
    ``tiltbench noise`` does). Returns None when the run spans fewer than 5 octaves.
    """
    e = np.asarray(e, dtype=float)
    n = e.size
    block = 1
    while n // block > MAX_FIT_SAMPLES:
        block *= 2
    try:
        return fit_axis_noise(e, rate, block=block)
    except DataError:
        return None


def allan_slope(fit: AxisNoise, rate: float, tail: int = FLICKER_TAIL
                ) -> tuple[float, float, float] | None:
    """Slope of the bias' Allan deviation on log-log axes over the longest ``tail`` octaves:
    the white term of the fit (``N²/τ``) removed from the Allan variance first, so a walk
    reads +½ and a flicker floor 0 (least squares on the octaves whose excess is positive).
    ``rate`` as given to :func:`flicker_test`. Returns (slope, τ_first, τ_last), or None when
    fewer than two octaves have an excess."""
    taus, avar = np.asarray(fit.taus), np.asarray(fit.adev) ** 2
    block = 1
    while fit.n // block > MAX_FIT_SAMPLES:
        block *= 2
    excess = avar - float(fit.theta[0]) / (rate / block) / taus  # θ₀ = N²·fs of the fit
    k = min(tail, taus.size)
    keep = np.flatnonzero(excess[-k:] > 0) + taus.size - k
    if keep.size < 2:
        return None
    slope = float(np.polyfit(np.log(taus[keep]), 0.5 * np.log(excess[keep]), 1)[0])
    return slope, float(taus[keep[0]]), float(taus[keep[-1]])


def _spectrum_check(e: np.ndarray, run, axis: str) -> Check | None:
    """``walk_spectrum``: the flicker floor of the Allan variance beside white noise and a walk
    (:func:`flicker_test`)."""
    rate = 1.0
    if run.time_unit == "s":
        span = float(run.tcol[-1] - run.tcol[0])
        rate = (run.n - 1) / span if span > 0 else 1.0
    fit = flicker_test(e, rate)
    if fit is None:
        return None
    term = fit.terms[1]
    b = float(np.sqrt(max(float(fit.theta[1]), 0.0)))
    sl = allan_slope(fit, rate)
    unit = _time_unit(run)
    shape = ("no excess over the white noise at long τ" if sl is None else
             f"slope {sl[0]:+.2f} over τ {sl[1]:.3g}–{sl[2]:.3g} {unit}")
    return Check("walk_spectrum", axis, float(term.z), float(stats.norm.logsf(term.z)),
                 "Allan-variance GLS: score z of the flicker floor B = 0 beside white noise "
                 "and a walk (one-sided)", b, "m/s²",
                 f"1/f-like drift on {axis}: the Allan deviation of the bias has a flicker "
                 f"floor B ≈ {b:.3g} m/s² (Allan deviation without the white noise: {shape}; "
                 "a random walk rises as τ^+½, flicker noise is flat): the bias wanders on "
                 "every time scale with increments that are not independent, not a walk")


def path_checks(ext: Extensions, e: np.ndarray, innov: np.ndarray, sigma2: float, q: float,
                axis: str) -> list[Check]:
    """The battery on the walk's own path (module docstring, 2.), without Ljung-Box."""
    run = ext.run
    dt = np.asarray(run.dt_walk, dtype=float)
    r = q * q * dt
    de = np.diff(np.asarray(e, dtype=float))
    m = de.size
    out: list[Check] = []
    z = np.asarray(innov, dtype=float)[1:]
    if z.size >= 20:
        k2, p = stats.normaltest(z)
        out.append(Check("walk_normality", axis, float(k2), float(np.log(max(p, 1e-300))),
                         "D'Agostino-Pearson K², chi2(2)", float(stats.kurtosis(z)), "",
                         f"the random walk on {axis} leaves non-Gaussian innovations "
                         f"(skewness {stats.skew(z):.2g}, excess kurtosis "
                         f"{stats.kurtosis(z):.2g}): the bias moves in jumps or bursts, not "
                         "by a random walk's Gaussian steps"))
        spec = np.abs(np.fft.rfft(z - z.mean())) ** 2
        spec = spec[1:(z.size - 1) // 2 + 1]
        if spec.size > 2 and spec.sum() > 0:
            j = int(np.argmax(spec)) + 1
            g = float(spec[j - 1] / spec.sum())
            span = float(run.tcol[-1] - run.tcol[0]) * z.size / max(z.size - 1, 1)
            period = span / j
            words = (f"{1.0 / period:.3g} Hz (period {period:.4g} s)" if run.time_unit == "s"
                     else f"period {period:.4g} samples")
            out.append(Check("walk_period", axis, g, fisher_g_logp(g, spec.size),
                             f"Fisher g over {spec.size} frequencies", float(period),
                             _time_unit(run),
                             f"the random walk on {axis} leaves a periodic component "
                             f"({words}) in its innovations: an oscillation, not a walk"))
    if m >= 3 and q > 0:
        c = sla.cholesky_banded(_banded(sigma2, r))
        x = sla.cho_solve_banded((c, False), de)
        dinv = tridiagonal_inverse_diagonal(2.0 * sigma2 + r, -sigma2)
        u = x / np.sqrt(dinv)
        i = int(np.argmax(np.abs(u)))
        umax = float(abs(u[i]))
        logp = float(min(0.0, np.log(2.0 * m) + stats.norm.logsf(umax)))
        # the smoothed bias b̂ = e - σ² Dᵀ Σ_Δ⁻¹ Δe, its change across the jump
        v = np.zeros(m + 1)
        v[:-1] -= x
        v[1:] += x
        b = np.asarray(e, dtype=float) - sigma2 * v
        w = int(np.clip(np.sqrt(sigma2 / max(float(np.median(r)), 1e-300)), 1, max(m // 20, 1)))
        jump = float(b[min(i + 1 + w, m)] - b[max(i - w, 0)])
        out.append(Check("walk_jump", axis, umax, logp,
                         f"max |auxiliary residual| of {m} N(0,1), Bonferroni", abs(jump),
                         "m/s²",
                         f"the bias on {axis} jumps by {jump:+.3g} m/s² at {_where(run, i + 1)}"
                         f" ({umax:.3g} standard deviations of a walk step): a step, not a "
                         "walk"))
    st = _stationarity(de, sigma2, dt, q, run, axis)
    if st is not None:
        out.append(st)
    sp = _spectrum_check(e, run, axis)
    if sp is not None:
        out.append(sp)
    return out


def gls_nll(de: np.ndarray, dx: np.ndarray, sigma2: float, r: np.ndarray) -> float:
    """-2 log L (no 2π) of ``Δe = ΔX β + Δ(b + v)`` with β profiled: whitened by the
    banded Cholesky factor of ``Σ_Δ`` (``Σ_Δ = UᵀU``; ``Uᵀ w = ·`` is a bidiagonal solve)."""
    c = sla.cholesky_banded(_banded(sigma2, r))
    low = np.zeros_like(c)
    low[0] = c[1]
    low[1, :-1] = c[0, 1:]
    w = sla.solve_banded((1, 0), low, np.column_stack([de, dx]))
    coef = np.linalg.lstsq(w[:, 1:], w[:, 0], rcond=None)[0]
    res = w[:, 0] - w[:, 1:] @ coef
    return float(2.0 * np.sum(np.log(c[1])) + res @ res)


def walk_nll(de: np.ndarray, dx: np.ndarray, sigma2: float, dt: np.ndarray, q0: float
              ) -> float:
    """:func:`gls_nll` minimised over the walk's q (bounded search on log q around q0)."""
    def f(lq: float) -> float:
        return gls_nll(de, dx, sigma2, np.exp(2.0 * lq) * dt)

    res = optimize.minimize_scalar(f, bounds=(np.log(q0) - 8.0, np.log(q0) + 4.0),
                                   method="bounded", options={"xatol": 1e-4})
    return float(min(res.fun, f(np.log(q0))))


def rival_check(ext: Extensions, e: np.ndarray, sigma2: float, q: float, k: int,
                found: list[Rival], walk_criterion: float, fixed_q: bool) -> Check | None:
    """Do the rivals that beat the walk by AIC add to it beyond chance? (the ``walk_rivals``
    check).

    Each such rival's columns are added **on top of** the walk (q refitted, unless a sensor
    profile fixes it; the axis' own reference column refitted too; the other named effects
    at their final values in ``e``): ``LR = -2 log L(walk) + 2 log L(walk + rival) ~ χ²(c)``
    under the walk, c the rival's columns; its p-value is multiplied by the shapes searched
    (:attr:`Rival.searched`) and by the number of rival families (Bonferroni). Under a true
    walk this fails with probability ≤ the battery's per-check α — unlike the AIC comparison
    in place alone, which a true walk loses most of the time (a Brownian path has most of its
    energy in its few slowest modes, which two sinusoids or two steps capture).
    """
    winners = sorted((r for r in found if r.criterion >= walk_criterion
                      and r.cols is not None), key=lambda r: -r.criterion)
    if not winners:
        return None
    run = ext.run
    dt = np.asarray(run.dt_walk, dtype=float)
    de = np.diff(np.asarray(e, dtype=float))
    base = np.diff(run.a_ref[:, k])[:, None]
    if fixed_q:
        def nll(dx):
            return gls_nll(de, dx, sigma2, q * q * dt)
    else:
        def nll(dx):
            return walk_nll(de, dx, sigma2, dt, q)
    nll0 = nll(base)
    tested = []
    for r in winners[:NESTED_TOP]:
        dz = np.diff(r.cols, axis=0)
        lr = max(nll0 - nll(np.column_stack([base, dz])), 0.0)
        logp = min(0.0, float(np.log(len(found) * r.searched)
                              + stats.chi2.logsf(lr, r.cols.shape[1])))
        tested.append((logp, lr, r))
    logp, lr, r = min(tested, key=lambda x: x[0])
    # Two shapes the run cannot tell apart (e.g. a bias step and a gain step where the
    # specific force is constant) fit alike to the last bits, and which comes first would
    # move with the CPU's float kernels: both are said, in a fixed order.
    same = sorted((x[2] for x in tested if abs(x[0] - logp) <= TIE_LOGP * max(1.0, abs(logp))),
                  key=lambda x: x.name)
    words = " — or, fitting alike, ".join(x.description for x in same)
    return Check("walk_rivals", AXES[k], lr, logp,
                 f"LR of {'/'.join(x.name for x in same)} on top of the walk, "
                 f"chi2({r.cols.shape[1]}) × {len(found)}·{r.searched} shapes", r.size, "m/s²",
                 f"{words}: {'they beat' if len(same) > 1 else 'it beats'} the random walk on "
                 f"{AXES[k]} by AIC in {'their' if len(same) > 1 else 'its'} place and "
                 f"{'add' if len(same) > 1 else 'adds'} to it beyond chance (LR {lr:.4g} on "
                 "top of the walk)")


def walk_beyond(ext: Extensions, e: np.ndarray, sigma2: float, q: float, k: int,
                cols: np.ndarray, fixed_q: bool) -> tuple[float, float]:
    """Is a walk still needed once a rival shape is in the model? (LR, log p).

    The rival's columns (and the axis' own reference column) are fitted with the walk absent
    (``q = 0``) and with it (q refitted, or the sensor profile's q when ``fixed_q``), on the
    differenced path as :func:`rival_check`: ``LR = -2 log L(rival) + 2 log L(rival + walk)``.
    q = 0 is on the boundary: ``LR ~ ½χ²₀ + ½χ²₁`` (Self & Liang 1987), so ``p = ½ P(χ²₁ >
    LR)``; with q fixed by a profile the alternative is simple and the same bound is kept."""
    run = ext.run
    dt = np.asarray(run.dt_walk, dtype=float)
    de = np.diff(np.asarray(e, dtype=float))
    dx = np.column_stack([np.diff(run.a_ref[:, k]), np.diff(cols, axis=0)])
    nll0 = gls_nll(de, dx, sigma2, np.zeros_like(dt))
    nll1 = gls_nll(de, dx, sigma2, q * q * dt) if fixed_q else walk_nll(de, dx, sigma2, dt, q)
    lr = max(nll0 - nll1, 0.0)
    return float(lr), float(np.log(0.5) + stats.chi2.logsf(lr, 1)) if lr > 0 else 0.0


STRUCTURED = ("backlash", "gain_drift", "gain_step", "tilt_drift", "warm_up", "heating",
              "drive_angle", "settling", "response_bend", "near_zero_g", "direction")
"""Rivals with a physical shape (a function of θ, of the specific force, of the motion, or a
fixed law in time) that may replace a walk by :func:`structured_drift`; the generic ones
(polynomials, tones, steps, bumps) may not."""

Q_REFIT = (0.25, 0.5, 1.0, 2.0)
"""Factors of the walk's q over which the walk is refitted on top of a rival."""


def walk_beyond_refit(ext: Extensions, state: ModelState, reduced: ModelState, k: int,
                      cols: np.ndarray) -> tuple[float, float]:
    """Is a walk still needed once a rival shape is in the model? (LR, log p), with **every**
    linear parameter of the model refitted (unlike :func:`walk_beyond`, which keeps the other
    named effects at their values with the walk).

    ``-2 log L`` with the rival's columns added is ``nll(model) - ΔRSS`` (the columns' gain in
    the model's whitened system, :class:`calib.gap.space.AxisSpace`): without the walk
    (``reduced``) and with it, q on :data:`Q_REFIT` times its fitted value (the best of them:
    the walk's LR beyond the rival is at most this much understated by the grid). q = 0 is on
    the boundary: ``LR ~ ½χ²₀ + ½χ²₁``."""
    axis_q = state.axes[k]
    fit0 = AxisSpace(ext, reduced, k).test(cols)
    base = ext.nll(reduced) - (fit0[0] if fit0 is not None else 0.0)
    best = np.inf
    for f in Q_REFIT:
        s_q = state.with_axis(k, replace(axis_q, q=axis_q.q * f))
        val = ext.safe_nll(s_q)
        if not np.isfinite(val):
            continue
        fit = AxisSpace(ext, s_q, k).test(cols)
        best = min(best, val - (fit[0] if fit is not None else 0.0))
    lr = max(float(base - best), 0.0) if np.isfinite(best) else 0.0
    return lr, float(np.log(0.5) + stats.chi2.logsf(lr, 1)) if lr > 0 else 0.0


def structured_drift(ext: Extensions, state: ModelState, reduced: ModelState, k: int,
                     found: list[Rival], walk_criterion: float, fixed_q: bool) -> dict | None:
    """A structured rival (:data:`STRUCTURED`) that beats the walk in its place by more than
    the slow cycle's margins (``D > CYCLE_MARGIN`` and ``D > CYCLE_SHARE·(LR_w - 2·c_w)``)
    while a walk adds nothing beyond it (:func:`walk_beyond_refit` at
    :data:`WALK_BEYOND_ALPHA`): the drift is that shape, not a walk (decision
    ``"structure"``). A drift that creeps smoothly (a tilt or a gain drifting in time) is
    followed by a walk so closely that the rival adds little on top of it (``walk_rivals``
    does not fire), yet the rival alone describes all of it with a fixed shape. The margins
    are the slow cycle's (:func:`slow_cycle`), whose rival — one tone over the run — mimics a
    Brownian path far better than these shapes do. With a sensor profile (q fixed) the walk
    is known noise: nothing to decide."""
    if fixed_q:
        return None
    for r in sorted((r for r in found if r.name in STRUCTURED and r.cols is not None
                     and r.criterion > walk_criterion), key=lambda r: -r.criterion):
        gain = float(r.criterion - walk_criterion)
        share = gain / max(walk_criterion, 1e-300)
        if not (gain > CYCLE_MARGIN and share > CYCLE_SHARE):
            return None
        lr, logp = walk_beyond_refit(ext, state, reduced, k, r.cols)
        if logp >= np.log(WALK_BEYOND_ALPHA):
            return {"decision": "structure", "gain": gain, "share": float(share),
                    "walk_beyond_lr": float(lr), "walk_beyond_p": float(np.exp(logp)),
                    "size": float(r.size),
                    "description": f"{r.description}, not a walk: this fixed shape fits the "
                                   f"drift better than the walk (AIC gain {gain:.3g}) and a "
                                   "walk adds nothing beyond it"}
    return None


def slow_cycle(ext: Extensions, e: np.ndarray, sigma2: float, q: float, k: int,
               found: list[Rival], walk_criterion: float, fixed_q: bool) -> dict | None:
    """A slow cycle in time or a walk? Decided by the charged likelihood.

    The ``sinusoid`` rival (one tone, period up to three times the run) in place of the walk
    against the walk, AIC gain ``D = (LR_c - 2·3) - (LR_w - 2·c_w)``. Nothing to say when the
    walk wins (D ≤ 0) or is still needed once the cycle is in the model (:func:`walk_beyond`
    at :data:`WALK_BEYOND_ALPHA`). Otherwise the cycle describes everything the walk did:

    * ``D > CYCLE_MARGIN`` and ``D > CYCLE_SHARE·(LR_w - 2·c_w)`` — the cycle is preferred:
      the walk is not named ("a slow cycle, not a walk"). Both bounds are the charge of the
      frequency search that AIC does not see, measured on true walks: 66 named walks of the
      ``validation`` catalog (six timed designs, 2000–4000 samples over 24–80 s), where one
      tone over the run follows a Brownian path's slowest mode (≈ 80 % of its variance) and a
      walk adds nothing beyond it in a third of the runs: D reached 22.4 (walk gain 473,
      share 0.05) and the share 0.31 (D = 8.1, a faint walk), never both bounds (0 of 66;
      ``tests/test_gap_walk.py`` keeps the catalog walks named). Thermal cycles of 1–1.6
      periods per run sized 10–12 σ give D ≈ 19–27 at shares ≈ 0.17–0.21;
    * otherwise (D > 0) — this run cannot tell a walk from a slow cycle: the walk is
      named (it is the catalog's) and the pair is listed under ``not_identifiable`` ("cannot
      tell a walk from a slow cycle"; a run several periods long separates them).
    """
    cyc = next((r for r in found if r.name == "sinusoid" and r.cols is not None), None)
    if cyc is None or cyc.criterion <= walk_criterion:
        return None
    lr, logp = walk_beyond(ext, e, sigma2, q, k, cyc.cols, fixed_q)
    if logp < np.log(WALK_BEYOND_ALPHA):
        return None
    gain = float(cyc.criterion - walk_criterion)
    share = gain / max(walk_criterion, 1e-300)
    decision = ("slow_cycle" if gain > CYCLE_MARGIN and share > CYCLE_SHARE
                else "cannot_tell")
    words = (f"a slow cycle, not a walk: {cyc.description}" if decision == "slow_cycle" else
             f"cannot tell a walk from a slow cycle on {AXES[k]}: {cyc.description} fits as "
             f"well (AIC gain {gain:.3g} over the walk's {walk_criterion:.4g}, within the "
             f"search's margin) and a walk adds nothing beyond it; a run several of its "
             "periods long separates them")
    return {"decision": decision, "gain": gain, "share": float(share),
            "walk_beyond_lr": float(lr),
            "walk_beyond_p": float(np.exp(logp)), "size": float(cyc.size),
            "description": words}


def step_charge(n: int) -> float:
    """Parameters charged per step of :func:`step_drift`: its size (1) and its place, the best
    of n (ln n, the BIC's charge: the largest of n χ²(1) gains under no step is about
    2·ln n). With 2 per step (the ``step`` rival's charge) weak true walks segmented into a
    few steps beat the walk (2 of 59 walks of q√N = 1–2 σ on 4001 samples, D = 18 and 58);
    with 1 + ln n none of the 59 did, while a staircase of three 1 σ steps still wins by
    D ≈ 60."""
    return 1.0 + float(np.log(max(n, 2)))


def _beyond_steps(lr: float, p: float) -> str:
    """Why steps may stand for the walk: a walk adds nothing beyond them, or their levels
    alternate (two-level switching)."""
    if p >= WALK_BEYOND_ALPHA:
        return f"a walk adds nothing beyond them (LR {lr:.3g})"
    return "their levels alternate between two values, which a walk has no reason to revisit"


def steps_decision(gain: float, margin: float) -> str:
    """``"steps"`` beyond ``margin`` (the steps replace the walk), ``"leans"`` beyond
    :data:`WALK_LEAN_MARGIN` (the walk is not named; the two are not told apart), else
    ``"describes"`` (the walk is named; the pair listed as not identifiable)."""
    return "steps" if gain > margin else "leans" if gain > WALK_LEAN_MARGIN else "describes"


def step_drift(ext: Extensions, state: ModelState, reduced: ModelState, k: int,
               e: np.ndarray, sigma2: float, walk_criterion: float, fixed_q: bool
               ) -> dict | None:
    """Steps of the bias, not a walk? (:mod:`calib.gap.steps`).

    The steps of the walk's path ``e`` (:func:`calib.gap.steps.optimal_steps`: the
    segmentation that maximises the path's gain less :func:`step_charge` per step, the charge
    D makes) are fitted in place of the walk (their columns in the
    reduced model's whitened system, :class:`calib.gap.space.AxisSpace`), charged
    :func:`step_charge` each: AIC gain ``D = (LR_s − 2·c_s·K) − (LR_w − 2·c_w)``. When D > 0 and
    a walk adds nothing beyond the steps (:func:`walk_beyond_refit`, every linear parameter
    refitted, p ≥ :data:`WALK_BEYOND_ALPHA`) the drift is step-like (``"describes"``: its
    words are the steps'); when moreover D passes the slow cycle's margins
    (``D > CYCLE_MARGIN`` and ``D > CYCLE_SHARE·(LR_w − 2·c_w)``) the steps replace the walk
    (``"steps"``: the walk is not named); within them but beyond :data:`WALK_LEAN_MARGIN`
    (``"leans"``) the walk is not named either and the verdict says the two are not told
    apart; below (``"describes"``) the walk is named and
    the pair is listed under ``not_identifiable`` (``"cannot_tell"``). The near tier: steps
    within :data:`NEAR_STEPS_MARGIN` of the walk (D > −15, D ≤ 2 included) lean too when a walk
    adds nothing at all beyond them (LR ≤ :data:`NOTHING_BEYOND_LR`) and they have a shape a
    walk does not make (:func:`calib.gap.steps.walk_unlike`; ``"near"`` true). On weak true walks of
    4001 samples a walk adds nothing beyond one to three steps that fit about as well in a
    few runs of fifty, as on faint staircases, so such a run cannot tell them apart. A
    Brownian path segmented so leaves its walk inside
    every segment (the walk is still needed beyond the steps); two-level switching, a step or
    a staircase leaves white noise. None when there is no step, or with a sensor profile
    (q fixed: the walk is known noise)."""
    if fixed_q:
        return None
    run = ext.run
    fit = optimal_steps(e, sigma2, 2.0 * step_charge(run.n))
    if fit.count == 0:
        return None
    cols = fit.columns(run.n)
    res = AxisSpace(ext, reduced, k).test(cols)
    if res is None:
        return None
    crit = float(res[0] - 2.0 * step_charge(run.n) * fit.count)
    gain = crit - walk_criterion
    # below 0 only the near tier is left: a shape a walk does not make, nothing beyond it
    shaped = walk_unlike(fit)
    if gain <= -NEAR_STEPS_MARGIN or (gain <= 0 and not shaped):
        return None
    two = two_level(fit)
    lr, logp = walk_beyond_refit(ext, state, reduced, k, cols)
    near = shaped and lr <= NOTHING_BEYOND_LR
    if gain <= 0 and not near:
        return None
    if logp < np.log(WALK_BEYOND_ALPHA) and not two:
        return None
    share = gain / max(walk_criterion, 1e-300)
    decision = steps_decision(gain, CYCLE_MARGIN)
    near = near and decision == "describes"  # the tier it moves: "describes" to "leans"
    if near:
        decision = "leans"
    words = describe(fit, run.tcol, run.time_unit, AXES[k])
    fits = ("better" if gain > WALK_LEAN_MARGIN else "as well" if gain > 0
            else "nearly as well")
    return {"decision": decision, "pair": "bias_steps", "margin": CYCLE_MARGIN,
            "count": fit.count, "two_level": bool(two),
            "gain": float(gain), "near": bool(near),
            "share": float(share), "walk_beyond_lr": float(lr),
            "walk_beyond_p": float(np.exp(logp)), "size": float(np.max(np.abs(fit.sizes))),
            "description": words,
            "cannot_tell": (f"cannot tell a walk from steps on {AXES[k]}: {words} fits "
                            f"{fits} (AIC gain {gain:.3g} over the walk's "
                            f"{walk_criterion:.4g}, within the margin {CYCLE_MARGIN:g}) and "
                            f"{_beyond_steps(lr, float(np.exp(logp)))}; a longer run "
                            "(more steps, or a walk wandering between them) separates them")}


SWITCH_MARGIN = 12.0
"""AIC gain of two-level switching over the walk, on the walk's path (:func:`switching_drift`),
beyond which the switching replaces the walk (below it, and above 0, the pair is listed as not
told apart; above :data:`WALK_LEAN_MARGIN` the walk is not named). Measured on paths made apart
from the detector (``python -m validation.switching.score``, ``docs/gap.md``): of 400 random
walks of q√T = 0.3–4 σ none gained more than 12 (largest 9.1), while telegraphs with levels
0.2–0.6 σ apart and 4–30 switches did in 99 of 150."""


def path_walk_lr(e: np.ndarray, sigma2: float, dt: np.ndarray, m: int = 1) -> float:
    """Gain in ``-2 log L`` of a random walk over white noise on path ``e`` (m/s²; noise σ²,
    step Δt (N-1,)), q at its maximum likelihood: the differenced local level
    (:func:`_local_level_nll`) of the path's means in blocks of ``m`` samples (noise σ²/m,
    the walk's step ``q²·Δt_b`` with Δt_b the time between the blocks' mean times), as
    :func:`calib.gap.switching.fit_switching` sees the path."""
    eb = block_means(e, m)
    if eb.size < 3:
        return 0.0
    de = np.diff(eb)
    s2 = float(sigma2) / m
    dtb = np.diff(block_means(np.concatenate([[0.0], np.cumsum(dt)]), m))
    white = _local_level_nll(de, s2, np.zeros(de.size))

    def nll(lr: float) -> float:  # lr: log of q²Δt relative to σ²/m
        return _local_level_nll(de, s2, s2 * np.exp(lr) * dtb / float(np.mean(dtb)))

    res = optimize.minimize_scalar(nll, bounds=(np.log(1e-9), np.log(1e2)), method="bounded",
                                   options={"xatol": 1e-3})
    return max(white - float(min(res.fun, white)), 0.0)


def switching_drift(ext: Extensions, state: ModelState, reduced: ModelState, k: int,
                    e: np.ndarray, sigma2: float, fixed_q: bool) -> dict | None:
    """Two-level switching of the bias, not a walk? (:mod:`calib.gap.switching`).

    The walk's path ``e`` is fitted by a two-state Markov level (switching histories
    integrated out) and by a walk (:func:`path_walk_lr`) on the same points; AIC gain
    ``D = (LR_s − 2·3) − (LR_w − 2·1)``. When D > 0 and a walk adds nothing beyond the
    decoded switching (its steps as columns, :func:`walk_beyond_refit`, p ≥
    :data:`WALK_BEYOND_ALPHA`) the drift is described as switching (``"describes"``: the walk
    stays named, the pair listed as not told apart); beyond :data:`WALK_LEAN_MARGIN` the walk is
    not named (``"leans"``: the two are not told apart) and beyond :data:`SWITCH_MARGIN` the
    switching replaces the walk (``"steps"``). The same dict as :func:`step_drift`; None with
    a sensor profile (q fixed: the walk is known noise) or when the walk fits better."""
    if fixed_q:
        return None
    run = ext.run
    fit = fit_switching(e, sigma2)
    if fit is None:
        return None
    walk_lr = path_walk_lr(e, sigma2, run.dt_walk, block_size(run.n))
    gain = (fit.lr - 2.0 * SWITCH_CHARGE) - (walk_lr - 2.0)
    steps = fit.step_fit()
    if gain <= 0 or steps.count == 0:
        return None
    lr, logp = walk_beyond_refit(ext, state, reduced, k, steps.columns(run.n))
    if logp < np.log(WALK_BEYOND_ALPHA):
        return None
    words = describe(steps, run.tcol, run.time_unit, AXES[k])
    size = fit.levels[1] - fit.levels[0]
    return {"decision": steps_decision(gain, SWITCH_MARGIN),
            "pair": "bias_switching", "margin": SWITCH_MARGIN,
            "model": "two_level_markov", "count": steps.count,
            "two_level": bool(two_level(steps)), "gain": float(gain),
            "share": float(gain / max(walk_lr - 2.0, 1e-300)),
            "walk_beyond_lr": float(lr), "walk_beyond_p": float(np.exp(logp)),
            "size": float(size), "levels": [float(v) for v in fit.levels],
            "rates_per_sample": [float(v) for v in fit.rates],
            "description": words,
            "cannot_tell": (f"cannot tell a walk from two-level switching on {AXES[k]} "
                            f"(AIC gain {gain:.3g} over the walk on its path, within the "
                            f"margin {SWITCH_MARGIN:g}; a walk adds nothing beyond the "
                            f"switching, LR {lr:.3g}): {words}; a longer run (more switches, or "
                            "a walk wandering beyond two levels) separates them")}


def review_walk(ext: Extensions, state: ModelState, k: int, e: np.ndarray,
                innov: np.ndarray) -> WalkReview:
    """Rivals and path battery for the walk named on axis k of ``state``.

    e : (N,) readings minus the final model's mean without its bias, m/s².  innov : (N,) the
    walk filter's normalised innovations.
    """
    st = state.axes[k]
    axis = AXES[k]
    reduced = state.without("bias_random_walk", axis)
    lr = float(ext.nll(reduced) - ext.nll(state))
    charge = walk_charge(ext, k)
    found = rivals(ext, reduced, k, walk_band(ext.run, st.q, st.sigma2_eff))
    checks = path_checks(ext, e, innov, st.sigma2_eff, st.q, axis)
    rc = rival_check(ext, e, st.sigma2_eff, st.q, k, found, lr - 2.0 * charge,
                     k in getattr(ext, "walk_bounds", {}))
    if rc is not None:
        checks.append(rc)
    fixed = k in getattr(ext, "walk_bounds", {})
    cycle = (structured_drift(ext, state, reduced, k, found, lr - 2.0 * charge, fixed)
             or slow_cycle(ext, e, st.sigma2_eff, st.q, k, found, lr - 2.0 * charge, fixed))
    steps = step_drift(ext, state, reduced, k, e, st.sigma2_eff, lr - 2.0 * charge, fixed)
    if steps is None or steps["decision"] != "steps":  # faint switching the search missed
        switching = switching_drift(ext, state, reduced, k, e, st.sigma2_eff, fixed)
        if switching is not None and (steps is None or switching["gain"] > steps["gain"]):
            steps = switching
    return WalkReview(axis, lr, charge, tuple(found), tuple(checks), profile=fixed,
                      cycle=cycle, steps=steps)
