"""Never worse (issue 33, item 3): an addition that makes the gap after worse than the gap
before (χ²/dof or the largest |z| beyond their spread under noise alone), or a replay that
left its tracking limit, is not presented as an explanation; the verdict says what failed
(:func:`calib.gap.practical.gap_worse`, :meth:`bench.gap.GapReport.addition_problems`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from calib.files.course import Ensayo
from calib.gap.practical import NEVER_WORSE_Z, gap_worse
from calib.stats.diagnostics import GapMeasure
from tests.gap_synthetic import STATED, synth


def _gm(chi2: float, z: float, dof: int = 4000, worst: str = "h1_cos") -> GapMeasure:
    return GapMeasure(chi2_dof=chi2, max_signature_z=z, dof=dof, max_signature_p=0.5,
                      worst=worst, signatures=(("chi2", 0.0), (worst, z)))


def test_the_rule_uses_the_spread_under_noise_alone():
    spread = np.sqrt(2.0 / 4000)
    before = _gm(1.00, 2.0)
    assert gap_worse(before, _gm(1.00 + 0.9 * NEVER_WORSE_Z * spread, 2.0)) == []
    worse = gap_worse(before, _gm(1.00 + 1.1 * NEVER_WORSE_Z * spread, 2.0))
    assert len(worse) == 1 and "χ²/dof rose from 1 to" in worse[0]
    assert gap_worse(before, _gm(1.0, 4.9)) == []
    assert "largest signature |z| rose from 2 (h1_cos) to 5.1" in gap_worse(
        before, _gm(1.0, 5.1))[0]
    assert gap_worse(_gm(3.0, 40.0), _gm(1.0, 2.0)) == []  # the usual: it shrank
    # χ² after against the stated noise when given
    assert gap_worse(before, _gm(1.0, 2.0), chi2_after=1.2)


@pytest.fixture(scope="module")
def report():
    from bench.gap import run_gap

    th, y, t = synth("sine", 2000, np.random.default_rng(7),
                     [("misalignment", "x", {"delta": 0.03})])
    rep = run_gap(Ensayo(th, y, t, source="m"), STATED)
    assert rep.verdict == "explained" and rep.replay.mode == "sweep"
    return rep


def test_an_addition_that_makes_the_gap_worse_is_not_an_explanation(report):
    """The gap before made better than the (consistent) gap after on x by hand: χ²/dof
    0.90 → 1.0 on ~2000 dof (spread 0.032) and z 0.5 → 3.9, the after gap within its
    consistency band — only the never-worse rule sees it."""
    before = replace(report.gap_before["x"], chi2_dof=0.90, max_signature_z=0.5)
    after = replace(report.gap_after["x"], max_signature_z=3.9)
    worse = replace(report, gap_before={**report.gap_before, "x": before},
                    gap_after={**report.gap_after, "x": after},
                    chi2_after_stated={**report.chi2_after_stated, "x": 1.0})
    assert not worse.gap_problems("x")  # the after gap alone is consistent
    d = worse.to_dict()
    assert d["verdict"] == "unexplained"
    sig = [u for u in d["unexplained"] if u["signature"] == "gap_worse"]
    assert len(sig) == 1 and sig[0]["axis"] == "x"
    assert "adding misalignment makes the gap on x worse" in sig[0]["description"]
    assert "not an explanation" in sig[0]["description"]
    assert all(e["tentative"] for e in d["effects"])
    lines = worse.verdict_lines()
    assert lines[0].startswith("verdict: UNEXPLAINED") and any("worse" in x for x in lines)


def test_a_replay_beyond_its_tracking_limit_is_not_an_explanation(report):
    from bench.gap import TRACKING_LIMIT

    lost = replace(report, tracking_error=5 * TRACKING_LIMIT)
    d = lost.to_dict()
    assert d["verdict"] == "unexplained"
    sig = [u for u in d["unexplained"] if u["signature"] == "replay_tracking"]
    assert sig and sig[0]["unit"] == "rad" and sig[0]["size"] == pytest.approx(5e-3)
    assert "did not follow the measured θ" in sig[0]["description"]
    assert "did not follow the measured θ" in d["shrink"]["x"]["reason"]
    assert not d["consistent_after"]


def test_a_short_reversal_is_followed_and_its_effect_explained():
    """A real case: an up-then-down sweep of 12 s (1200 samples) reverses fast. The servo
    command from the interpolant's own ω and α left the replay 1.06e-3 rad behind (above the
    1e-3 limit, so the named misalignment was not presented as an explanation); the command
    of the integrator's steps through θ follows the measured θ to rounding, and the
    misalignment is the explanation, its gap after consistent. (A table that cannot follow
    is still said: ``tests/test_gap_bench.py::
    test_a_table_that_cannot_move_as_commanded_is_rolled_out_and_said``.)
    """
    from bench.gap import run_gap

    th, y, t = synth("updown", 1200, np.random.default_rng(7),
                     [("misalignment", "x", {"delta": 0.03})])
    rep = run_gap(Ensayo(th, y, t, source="m"), STATED)
    assert rep.tracking_error <= 1e-12 and not rep.tracking_failed()
    assert rep.verdict == "explained" and not rep.unexplained
    assert [(e.name, e.axis) for e in rep.effects] == [("misalignment", "x")]
    assert rep.to_dict()["consistent_after"]


def test_nothing_named_nothing_to_confirm(report):
    """Without a named effect there is no addition: a tracking problem alone does not turn
    "nothing detected" into "unexplained"."""
    calm = replace(report, effects=(), tracking_error=0.0)
    assert calm.addition_problems() == []
    assert replace(calm, tracking_error=1.0).addition_problems() == []
