"""The ``tiltbench`` program's exit (:func:`bench.cli.console`): the command's garbage is
collected (its finalizers run), then what is still alive is frozen out of the interpreter's
exit collections; the process keeps freed memory for the next arrays; the exit code is the
command's; in-process callers of ``main`` keep their collector untouched; and nothing printed
is lost on the way out."""

from __future__ import annotations

import gc
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

import bench.cli as cli

REPO = Path(__file__).resolve().parents[1]


def test_console_collects_then_freezes_and_returns_the_commands_code(monkeypatch):
    calls: list[str] = []
    monkeypatch.setattr(cli, "keep_freed_memory", lambda: calls.append("memory") or True)
    monkeypatch.setattr(gc, "set_threshold", lambda *a: calls.append(("threshold", a[0])))
    monkeypatch.setattr(cli, "main", lambda: calls.append("main") or 3)
    monkeypatch.setattr(gc, "collect", lambda *a: calls.append("collect") or 0)
    monkeypatch.setattr(gc, "freeze", lambda: calls.append("freeze"))
    assert cli.console() == 3
    assert calls == [("threshold", cli.GC_YOUNG), "memory", "main", "collect", "freeze"]


def test_main_in_process_leaves_the_collector_alone(capsys):
    before = gc.get_freeze_count()
    assert cli.main([]) == 0  # `tiltbench` alone: the help
    assert "usage" in capsys.readouterr().out
    assert gc.get_freeze_count() == before


def test_a_long_output_and_a_finalizer_survive_the_exit(tmp_path):
    """A child that runs a command through ``console`` with a finalizer in a reference cycle
    left by the command: the JSON on stdout is whole and the finalizer ran (the cycle was
    garbage when the command ended, so the collection before the freeze ran it; frozen, it
    would never be)."""
    marker = tmp_path / "finalized"
    child = f"""
import sys
import bench.cli as cli

class Cycle:
    def __init__(self):
        self.me = self
    def __del__(self):
        open({str(marker)!r}, "w").close()

real = cli.main
def main():
    code = real()
    Cycle()  # garbage in a cycle when the command ends: only a collection finalizes it
    return code
cli.main = main
sys.argv = ["tiltbench", "generate", "class", "--students", "2", "--seed", "1", "--out",
            {str(tmp_path / "class")!r}, "--json"]
sys.exit(cli.console())
"""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, (str(REPO),
                                                                  os.environ.get("PYTHONPATH")))))
    done = subprocess.run([sys.executable, "-c", child], env=env, capture_output=True,
                          text=True, check=True, cwd=tmp_path)
    assert isinstance(json.loads(done.stdout), dict)
    assert marker.exists()


def _child_env() -> dict[str, str]:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, (str(REPO),
                                                                  os.environ.get("PYTHONPATH")))))
    env.pop("NUMPY_MADVISE_HUGEPAGE", None)
    return env


def test_the_program_keeps_freed_memory_and_asks_numpy_for_no_huge_pages(tmp_path):
    """In a fresh process (what ``console`` does first): glibc takes the fixed mmap and trim
    thresholds, and numpy, imported after, does not madvise huge pages; a user's own
    ``NUMPY_MADVISE_HUGEPAGE`` is kept."""
    child = """
import sys
import bench.cli as cli
ok = cli.keep_freed_memory()
import numpy
print(ok, numpy._core.multiarray._get_madvise_hugepage())
"""
    done = subprocess.run([sys.executable, "-c", child], env=_child_env(), capture_output=True,
                          text=True, check=True, cwd=tmp_path)
    took, huge = done.stdout.split()
    assert huge == "False"
    if platform.libc_ver()[0] == "glibc":
        assert took == "True"
    mine = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True,
                          check=True, cwd=tmp_path,
                          env=dict(_child_env(), NUMPY_MADVISE_HUGEPAGE="1"))
    assert mine.stdout.split()[1] == "True"
