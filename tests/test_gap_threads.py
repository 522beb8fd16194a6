"""``tiltbench gap``'s second thread never imports a module.

:func:`bench.gap.run_gap` simulates the nominal bench on a worker thread while the main
thread imports the analysis side and analyses. Two threads importing into one package's
import cycle at the same time can deadlock; Python then raises ``_DeadlockError`` in one of
them (it did, in 2 of 822 drive-validation runs, seeds 7 and 8: the worker imported
``bench.gap.prediction``, which imports ``calib.gap``, while the main thread was importing
``calib.gap``). The rule in ``bench.gap.run``: the worker uses only modules that are already
imported when its job is queued.

Checked in a fresh interpreter (in this one every module is imported already) with an import
finder that records the imports made off the main thread, on a short timed sweep (its replay
is done early, while the main thread still imports: the case that raced) and on held poses
(a static replay), and on a sweep with a misalignment: the analysis names it, and its
``mujoco.sysid`` refinement and the extended re-simulation then run on the worker thread beside
the adequacy checks. The finder sees every import of a module not yet loaded, so the check
fails whenever the worker would import anything, whichever thread got there first.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

PROBE = """
import json, sys, threading

off_main = []


class Recorder:
    def find_spec(self, name, path=None, target=None):
        if threading.current_thread() is not threading.main_thread():
            off_main.append([threading.current_thread().name, name])
        return None  # the usual finders do the import


sys.meta_path.insert(0, Recorder())
import numpy as np

from tests.gap_synthetic import STATED, synth
from calib.files.course import Ensayo
from bench.gap import run_gap

effects = json.loads(sys.argv[3])
th, y, t = synth(sys.argv[1], int(sys.argv[2]), np.random.default_rng(5), effects)
report = run_gap(Ensayo(th, y, t), STATED)
print(json.dumps({"mode": report.replay.mode, "off_main": off_main,
                  "named": [e.name for e in report.effects], "sysid": len(report.sysid)}))
"""

MISALIGNED = [["misalignment", "x", {"delta": 0.02}]]


@pytest.mark.parametrize(("design", "n", "mode", "effects"), [
    ("sine", 1500, "sweep", []),
    ("held", 600, "static", []),
    ("sine", 1500, "sweep", MISALIGNED)])
def test_the_worker_thread_imports_nothing(design, n, mode, effects):
    env = dict(os.environ, PYTHONPATH=str(REPO), OPENBLAS_NUM_THREADS="1",
               MUJOCO_GL="disable")
    done = subprocess.run([sys.executable, "-c", PROBE, design, str(n), json.dumps(effects)],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    got = json.loads(done.stdout.strip().splitlines()[-1])
    assert got["mode"] == mode
    assert got["off_main"] == [], got["off_main"]
    if effects:  # the refinement ran (on the worker thread, beside the checks)
        assert got["named"] == ["misalignment"] and got["sysid"] == 1
