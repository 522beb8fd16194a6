"""The gap run's extension started ahead, beside the analysis' checks (``bench.gap.run._Ahead``).

:func:`bench.gap.run_gap` refines the named physical effects with ``mujoco.sysid`` and reads
the extended table on its worker thread as soon as the analysis has named them
(``analyze_gap(on_named=…)``), while the analysis runs its adequacy checks. The checks may
still withdraw an effect; then the final model is extended afterwards. Either way the report
must be the one of the final effects: checked here against the same run with the extension
made afterwards (the path without the head start), value for value, and on a run whose
head start is given an effect the analysis does not end with.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import bench.gap.run as gap_run
from bench.gap import run_gap
from calib.files.course import Ensayo
from tests.gap_synthetic import STATED, synth

MISALIGNED = [("misalignment", "x", {"delta": 0.02})]


@pytest.fixture(scope="module")
def misaligned() -> Ensayo:
    th, y, t = synth("sine", 1500, np.random.default_rng(5), MISALIGNED)
    return Ensayo(th, y, t)


def _report(ensayo: Ensayo) -> dict:
    # through JSON: the report as a user reads it (floats compared exactly below)
    return json.loads(json.dumps(run_gap(ensayo, STATED).to_dict()))


@pytest.fixture(scope="module")
def afterwards(misaligned) -> dict:
    """The report with the extension made after the analysis (no head start)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gap_run._Ahead, "result", lambda self, named: None)
        return _report(misaligned)


def test_the_head_start_gives_the_same_report(misaligned, afterwards):
    used = []
    real = gap_run._Ahead.result

    def result(self, named):
        got = real(self, named)
        used.append(got is not None)
        return got

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gap_run._Ahead, "result", result)
        ahead = _report(misaligned)
    assert used == [True]  # the head start was used, not redone
    assert [e["name"] for e in ahead["effects"]] == ["misalignment"]
    assert "params" in ahead["effects"][0]["sysid"]  # refined by mujoco.sysid
    assert ahead == afterwards


def test_an_effect_withdrawn_after_the_head_start_is_not_in_the_report(misaligned,
                                                                        afterwards):
    """The head start is given an extra effect (as if the checks withdrew it afterwards):
    its work is not used, and the report is that of the final effects."""
    from calib.gap import analysis as gap_analysis

    real = gap_analysis.analyze_gap

    def analyze(*args, on_named=None, **kwargs):
        def named(effects, reported):
            extra = {"name": "lever_arm", "axis": "y",
                     "params": {"pos_x": 0.01, "pos_z": 0.02}}
            on_named(effects, [*reported, extra])
        return real(*args, on_named=named, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("calib.gap.analyze_gap", analyze)
        report = _report(misaligned)
    assert report == afterwards
