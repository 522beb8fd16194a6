"""Nothing changes for users when code moves: every generated file kind and the ``--json``
output of every command give the checksums recorded in ``tests/reference/snapshot.json``
(made by ``tools/snapshot.py`` before the move; see that script for what is compared)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))

import snapshot  # noqa: E402


@pytest.mark.slow
def test_outputs_are_byte_identical_to_the_recorded_snapshot(tmp_path, course_dir):
    expected = json.loads(snapshot.SNAPSHOT.read_text())
    got = snapshot.snapshot(tmp_path, course_dir)
    assert set(got) == set(expected), {"missing": sorted(set(expected) - set(got)),
                                       "new": sorted(set(got) - set(expected))}
    changed = sorted(k for k in expected if got[k] != expected[k])
    assert not changed, f"outputs changed (rerun tools/snapshot.py only if meant): {changed}"
