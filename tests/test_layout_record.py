"""bench/record/ and bench/figures/: no module imports its own package (a circle), the
modules' imports form no cycle, and ``import bench`` loads neither."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def _imports(path: Path) -> set[str]:
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.add(node.module)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out


@pytest.mark.parametrize("package", ["bench.record", "bench.figures"])
def test_no_import_circle(package):
    folder = REPO.joinpath(*package.split("."))
    mods = {f"{package}.{p.stem}": _imports(p) for p in folder.glob("*.py")
            if p.stem not in ("__init__", "__main__")}
    assert mods
    for name, deps in mods.items():
        assert package not in deps, f"{name} imports its own package {package}"
    graph = {name: {d for d in deps if d in mods} for name, deps in mods.items()}
    done: set[str] = set()

    def visit(name: str, path: tuple[str, ...]) -> None:
        assert name not in path, f"import circle: {' -> '.join(path + (name,))}"
        if name in done:
            return
        for dep in graph[name]:
            visit(dep, path + (name,))
        done.add(name)

    for name in graph:
        visit(name, ())


def test_bench_loads_neither_package():
    code = ("import sys, bench; bad = [m for m in sys.modules if m.startswith("
            "('bench.record', 'bench.figures', 'rerun', 'matplotlib'))]; assert not bad, bad")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_equations_moved_to_calib_have_one_home():
    import bench.record
    from bench.figures import FORMATS, save_figure, save_trajectory_plot, trajectory_figure

    for name in ("binned_mean", "position_cov_along", "trajectory_tree"):
        assert not hasattr(bench.record, name), f"bench.record still carries {name}"
    assert FORMATS and callable(save_figure) and callable(trajectory_figure)
    assert callable(save_trajectory_plot)
