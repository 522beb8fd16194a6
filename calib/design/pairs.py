"""Confusable pairs (:mod:`calib.gap.confusions`) and the power to tell them apart.

A pair (A, B): A is the true effect, B the explanation the gap may name in its place.

* Both linear: the test of A given B, ``LR_{A|B} ~ χ²_k(λ_{A|B})`` with
  ``λ_{A|B} = ‖(I - P_[H, h_B]) h_A c_A‖² / σ²`` (the component of A that B cannot mimic),
  compared with the gap's ambiguity margin ``2 ln 10`` (:data:`calib.gap.AMBIGUITY_LR`): power
  ``P(χ²_k(λ_{A|B}) > 2 ln 10)``. This is the nested form of the gap's swap test (which
  compares B *in place of* A with A; the two agree when [H, h_A, h_B] has A's extra part
  orthogonal to B); with λ = 0 it is ``P(χ²_1 > 2 ln 10) = 3.2 %``.
* A nonlinear (lag, random walk): Monte Carlo through the gap, success = A named on its axis
  and no ``not_identifiable`` entry naming both A and B (the gap's own tie rule).
"""

from __future__ import annotations

PAIRS: tuple[tuple[str, str], ...] = (
    ("misalignment", "cross_axis"),
    ("misalignment", "tilt_offset"),
    ("lowpass_lag", "misalignment"),
    ("lowpass_lag", "tilt_offset"),
    ("bias_random_walk", "bias_drift"),
)
"""(true A, look-alike B): the confusions of the gap workflow and of the issue."""


def pair_key(a: str, b: str) -> str:
    """JSON key of a pair: ``"A-vs-B"``."""
    return f"{a}-vs-{b}"


def told_apart(a: str, b: str, axis: str, named: list, confused: list) -> bool:
    """The gap's outcome on one run with A true: A named on ``axis`` (or both axes) and no
    ``not_identifiable`` entry naming both A and B."""
    hit = any(n == a and ax in (axis, "both") for n, ax in named)
    return hit and not any(a in names and b in names for names in confused)
