"""The import rules of the architecture, checked on the source (``ast``, no import is executed).

(a) ``calib`` never imports ``bench``, ``mujoco``, ``argparse``, ``matplotlib`` or ``rerun``
    (an estimator must not be able to peek at the simulation or the truth);
(b) no module outside ``bench/cli/`` imports ``bench.cli`` (or a ``bench.cli_*`` module) or
    ``argparse``;
(c) no ``importlib`` / ``__import__`` in ``bench`` or ``calib`` (dynamic imports would hide
    edges from these checks);
(d) no import circles between modules, ``if TYPE_CHECKING:`` imports included: a tie needed
    only for annotations is still a tie in the design (type against a protocol instead);
(e) the generator modules of ``validation/`` (every module but the scorer,
    :data:`VALIDATION_SCORING`) import neither ``bench`` nor ``calib`` nor the scorer: the
    validation set is written from the physics, so the bench's effect code cannot appear on
    both sides of the comparison. (c) and (d) hold in ``validation/`` too;
(f) no private name (``_x``, dunders excepted) crosses a file: neither ``from p import _x``
    (any layout, relative too) nor ``m._x`` on a project module bound by ``import p as m``,
    ``import p.q`` or ``from p import m`` — what another file needs is public there;
(g) the second, independent generator ``validation/independent/`` imports nothing of
    ``validation`` outside itself (written from the physics alone, it must not share the first
    generator's effects, designs or cases); the same for the drive part ``validation/drive/``
    (:data:`SEPARATE_SETS`);
(h) ``calib`` is built of wings: its top level holds ``__init__.py``, the ground modules
    (:data:`CALIB_GROUND`, at most 8) and the wing packages of :data:`WING_USES`, each with a
    docstring that says what it holds. The ground imports only the ground; a wing imports the
    ground, itself and the wings :data:`WING_USES` lists for it — nothing else, so the wings
    stack without arrows back up (``TYPE_CHECKING`` imports count: a tie is a tie).

Every import counts, also inside functions (a deferred import is still a dependency); only
``if TYPE_CHECKING:`` blocks are skipped by (a), (b), (e) and (g) (annotations, never
executed); (d) and (f) count them too. Edges of the module
graph: ``import a.b`` → ``a.b``; ``from p import n`` → ``p.n`` when that is a module, else
``p`` (its ``__init__``); relative imports are resolved first. Each checker is also run on a
small synthetic tree below, so a check that can never fail would show.
"""

from __future__ import annotations

import ast
import functools
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("bench", "calib")
CALIB_FORBIDDEN = ("bench", "mujoco", "argparse", "matplotlib", "rerun")
VALIDATION_SCORING = ("validation.score", "validation.independent.score",
                      "validation.drive.score", "validation.noise_independent.score",
                      "validation.switching.score", "validation.asymmetry.score")
"""The only modules of ``validation/`` that may import ``calib`` (they run the analysis)."""
GENERATOR_FORBIDDEN = ("bench", "calib", *VALIDATION_SCORING)


@dataclass
class Module:
    name: str
    path: Path
    is_package: bool
    imports: list[tuple[str, tuple[str, ...], int]] = field(default_factory=list)
    """(imported module, names taken from it by ``from … import``, line)."""
    typing_imports: list[tuple[str, tuple[str, ...], int]] = field(default_factory=list)
    """The same, for the imports inside ``if TYPE_CHECKING:`` blocks."""
    dynamic: list[tuple[str, int]] = field(default_factory=list)
    """Uses of ``importlib`` / ``__import__`` (what, line)."""
    tree: ast.Module | None = None


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _walk(node: ast.AST):
    """All nodes below ``node`` except the bodies of ``if TYPE_CHECKING:`` (its ``else`` runs)."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, ast.If) and _is_type_checking(child.test):
            for sub in child.orelse:
                yield sub
                yield from _walk(sub)
            continue
        yield child
        yield from _walk(child)


def _typing_blocks(node: ast.AST):
    """Every node inside the bodies of ``if TYPE_CHECKING:`` blocks below ``node``."""
    for sub in ast.walk(node):
        if isinstance(sub, ast.If) and _is_type_checking(sub.test):
            for stmt in sub.body:
                yield from ast.walk(stmt)


def _resolve(mod: Module, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    base = mod.name.split(".")
    if not mod.is_package:
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def scan(root: Path, packages: tuple[str, ...] = PACKAGES) -> dict[str, Module]:
    """Parse every ``.py`` of ``packages`` under ``root``: module name → :class:`Module`."""
    mods: dict[str, Module] = {}
    for pkg in packages:
        for path in sorted((root / pkg).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            is_pkg = parts[-1] == "__init__"
            if is_pkg:
                parts = parts[:-1]
            mods[".".join(parts)] = Module(".".join(parts), path, is_pkg)
    for mod in mods.values():
        tree = ast.parse(mod.path.read_text(encoding="utf-8"), str(mod.path))
        mod.tree = tree
        for node in _walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    mod.imports.append((alias.name, (), node.lineno))
                    if alias.name.split(".")[0] == "importlib":
                        mod.dynamic.append((f"import {alias.name}", node.lineno))
            elif isinstance(node, ast.ImportFrom):
                target = _resolve(mod, node)
                mod.imports.append((target, tuple(a.name for a in node.names), node.lineno))
                if target.split(".")[0] == "importlib":
                    mod.dynamic.append((f"from {target} import …", node.lineno))
            elif isinstance(node, ast.Name) and node.id in ("__import__", "importlib"):
                mod.dynamic.append((node.id, node.lineno))
            elif isinstance(node, ast.Attribute) and node.attr == "__import__":
                mod.dynamic.append(("__import__", node.lineno))
        for node in _typing_blocks(tree):
            if isinstance(node, ast.Import):
                mod.typing_imports += [(a.name, (), node.lineno) for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                mod.typing_imports.append((_resolve(mod, node),
                                           tuple(a.name for a in node.names), node.lineno))
    return mods


def _where(mod: Module, root: Path, line: int) -> str:
    return f"{mod.path.relative_to(root)}:{line}"


def _flagged(mod: Module, root: Path, bad_name) -> list[str]:
    """One line per import statement taking a name for which ``bad_name`` holds
    (``from p import n`` is checked as ``p`` and as ``p.n``: n may be a module)."""
    out = []
    for target, names, line in mod.imports:
        for name in [target, *(f"{target}.{n}" for n in names if n != "*")]:
            if bad_name(name):
                out.append(f"{_where(mod, root, line)} imports {name}")
                break
    return out


def _under(name: str, prefix: str) -> bool:
    return name == prefix or name.startswith(prefix + ".")


def check_calib_imports(mods: dict[str, Module], root: Path) -> list[str]:
    """(a) ``calib`` imports none of :data:`CALIB_FORBIDDEN`."""
    bad = []
    for mod in mods.values():
        if _under(mod.name, "calib"):
            bad += _flagged(mod, root, lambda n: any(_under(n, f) for f in CALIB_FORBIDDEN))
    return sorted(set(bad))


def _is_cli(name: str) -> bool:
    return _under(name, "bench.cli") or name.startswith("bench.cli_")


def check_cli_imports(mods: dict[str, Module], root: Path) -> list[str]:
    """(b) only ``bench/cli/`` imports ``bench.cli`` or ``argparse``."""
    bad = []
    for mod in mods.values():
        if not _under(mod.name, "bench.cli"):  # the bench/cli/ package itself may
            bad += _flagged(mod, root, lambda n: _under(n, "argparse") or _is_cli(n))
    return sorted(set(bad))


def check_dynamic_imports(mods: dict[str, Module], root: Path) -> list[str]:
    """(c) no ``importlib`` / ``__import__``."""
    return sorted({f"{_where(m, root, line)} uses {what}"
                   for m in mods.values() for what, line in m.dynamic})


def import_graph(mods: dict[str, Module], typing: bool = True) -> dict[str, set[str]]:
    """Module → modules it imports (only modules of the scanned packages); ``typing``: with
    the imports of ``if TYPE_CHECKING:`` blocks."""
    graph: dict[str, set[str]] = {name: set() for name in mods}
    for mod in mods.values():
        for target, names, _ in mod.imports + (mod.typing_imports if typing else []):
            if names:
                for n in names:
                    sub = f"{target}.{n}"
                    if sub in mods:
                        graph[mod.name].add(sub)
                    elif target in mods:
                        graph[mod.name].add(target)
            elif target in mods:
                graph[mod.name].add(target)
        graph[mod.name].discard(mod.name)
    return graph


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components (iterative), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on.add(start)
        while work:
            v, it = work[-1]
            advanced = False
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    advanced = True
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                out.append(sorted(comp))
    return out


def check_cycles(mods: dict[str, Module], root: Path, typing: bool = True) -> list[str]:
    """(d) every strongly connected component of more than one module, with its files
    (``typing``: ``if TYPE_CHECKING:`` imports count, as rule (d) asks)."""
    graph = import_graph(mods, typing)
    return sorted(
        "circle: " + ", ".join(str(mods[n].path.relative_to(root)) for n in comp)
        for comp in strongly_connected(graph) if len(comp) > 1)


def check_validation_imports(mods: dict[str, Module], root: Path) -> list[str]:
    """(e) the generator modules of ``validation`` import none of :data:`GENERATOR_FORBIDDEN`."""
    bad = []
    for mod in mods.values():
        if _under(mod.name, "validation") and mod.name not in VALIDATION_SCORING:
            bad += _flagged(mod, root, lambda n: any(_under(n, f) for f in GENERATOR_FORBIDDEN))
    return sorted(set(bad))


INDEPENDENT = "validation.independent"
DRIVE = "validation.drive"
SEPARATE_SETS = (INDEPENDENT, DRIVE)
"""Validation parts written apart from the rest of ``validation/`` (rule g)."""


def check_independent_imports(mods: dict[str, Module], root: Path,
                              prefix: str = INDEPENDENT) -> list[str]:
    """(g) ``prefix`` (a package of :data:`SEPARATE_SETS`) imports no module of
    ``validation`` outside itself."""
    bad = []
    for mod in mods.values():
        if _under(mod.name, prefix):
            bad += _flagged(mod, root, lambda n: _under(n, "validation")
                            and n != "validation" and not _under(n, prefix))
    return sorted(set(bad))


CALIB_GROUND = frozenset({"conventions", "numerics", "filters", "results", "units", "exports",
                          "input_rules", "distributions"})
"""The ground of ``calib``: modules at its top level that every wing may use."""

WING_USES: dict[str, frozenset[str]] = {
    "stats": frozenset(),
    "files": frozenset(),
    "logs": frozenset({"files"}),
    "noise": frozenset({"files", "logs"}),
    "calibration": frozenset({"stats", "files", "logs"}),
    "fusion": frozenset(),
    "vehicle": frozenset({"stats", "files", "calibration", "fusion"}),
    "effects": frozenset({"stats", "calibration"}),
    "gap": frozenset({"stats", "files", "noise", "calibration", "effects"}),
    "design": frozenset({"stats", "files", "calibration", "effects", "gap"}),
}
"""Wing of ``calib`` → the other wings it may import (besides the ground and itself)."""


def _wing(name: str) -> str | None:
    """``calib.<wing>…`` → the wing or ground module name; None for ``calib`` itself."""
    parts = name.split(".")
    return parts[1] if len(parts) > 1 else None


def check_wing_layout(root: Path, ground=CALIB_GROUND, uses=WING_USES) -> list[str]:
    """(h), the layout: only ``__init__.py``, ground modules and documented wings at the top."""
    bad = []
    if len(ground) > 8:
        bad.append(f"{len(ground)} ground modules (at most 8)")
    for path in sorted((root / "calib").iterdir()):
        if path.name.startswith((".", "__pycache__")) or path.name == "__init__.py":
            continue
        if path.is_file() and path.suffix == ".py":
            if path.stem not in ground:
                bad.append(f"calib/{path.name} is neither ground nor inside a wing")
        elif path.is_dir():
            init = path / "__init__.py"
            if path.name not in uses:
                bad.append(f"calib/{path.name}/ is not a wing of WING_USES")
            elif not init.exists() or not ast.get_docstring(ast.parse(init.read_text("utf-8"))):
                bad.append(f"calib/{path.name}/__init__.py has no docstring saying what it holds")
    return bad


def check_wing_imports(mods: dict[str, Module], root: Path, ground=CALIB_GROUND,
                       uses=WING_USES) -> list[str]:
    """(h), the arrows: every import of a ``calib`` module by a ground module or a wing."""
    bad = []
    graph = import_graph(mods, typing=True)
    for name, targets in graph.items():
        if not _under(name, "calib") or name == "calib":
            continue
        own = _wing(name)
        for target in sorted(targets):
            if not _under(target, "calib"):
                continue
            other = _wing(target)
            if other == own or other in ground:
                continue
            if own in ground:
                why = "the ground imports only the ground"
            elif other is None:
                why = "a wing does not import the package's lazy exports"
            elif other not in uses.get(own, ()):
                why = f"wing {own!r} may use only {sorted(uses.get(own, ()))} and the ground"
            else:
                continue
            bad.append(f"{mods[name].path.relative_to(root)} imports {target}: {why}")
    return sorted(set(bad))


# --- the rules on the real tree -------------------------------------------------------------

def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _dotted(node: ast.expr) -> list[str] | None:
    """``a.b.c`` as ``["a", "b", "c"]``; None for anything but names and attributes."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    return [node.id, *reversed(parts)]


def private_imports(mods: dict[str, Module], root: Path) -> list[tuple[str, str, str]]:
    """Every private name one module takes from another project module (rule f): (file,
    imported module, name), the file as ``path:line``. Checks every import (also inside
    functions and ``if TYPE_CHECKING:``) and attribute access on module aliases."""
    out = []
    for mod in mods.values():
        aliases: dict[str, str] = {}  # local name → project module it is bound to
        for node in ast.walk(mod.tree):
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.asname:
                        aliases[a.asname] = a.name
                    else:  # `import p.q` binds p; `p.q._x` is resolved below
                        aliases[a.name.split(".")[0]] = a.name.split(".")[0]
            elif isinstance(node, ast.ImportFrom):
                target = _resolve(mod, node)
                for a in node.names:
                    if _private(a.name) and target in mods and target != mod.name:
                        out.append((_where(mod, root, node.lineno), target, a.name))
                    if f"{target}.{a.name}" in mods:  # `from p import m`: a module
                        aliases[a.asname or a.name] = f"{target}.{a.name}"
        for node in ast.walk(mod.tree):
            if not isinstance(node, ast.Attribute) or not _private(node.attr):
                continue
            parts = _dotted(node.value)
            if parts is None or parts[0] not in aliases:
                continue
            target = ".".join([aliases[parts[0]], *parts[1:]])
            if target in mods and target != mod.name:
                out.append((_where(mod, root, node.lineno), target, node.attr))
    return out


PRIVATE_ALLOWED: frozenset[tuple[str, str, str]] = frozenset()
"""(importing file, module, name) still allowed by rule (f): none. An entry that no longer
occurs would fail too (the list only shrinks)."""


def check_private_imports(mods: dict[str, Module], root: Path,
                          allowed: set[tuple[str, str, str]] = frozenset()) -> list[str]:
    return [f"{where} imports {name} from {target}"
            for where, target, name in private_imports(mods, root)
            if (where.split(":")[0], target, name) not in allowed]


@functools.cache
def _real() -> dict[str, Module]:
    """The repository's modules, scanned once per test process (the checks only read them)."""
    return scan(REPO)


def test_calib_never_imports_the_simulation_or_ui():
    bad = check_calib_imports(_real(), REPO)
    assert not bad, "calib must not import bench/mujoco/argparse/matplotlib/rerun:\n" + \
        "\n".join(bad)


def test_only_the_cli_package_parses_arguments():
    bad = check_cli_imports(_real(), REPO)
    assert not bad, "only bench/cli/ may import bench.cli or argparse:\n" + "\n".join(bad)


def test_no_dynamic_imports():
    bad = check_dynamic_imports(_real(), REPO)
    assert not bad, "importlib / __import__ hide imports from these checks:\n" + \
        "\n".join(bad)


def test_no_import_circles():
    bad = check_cycles(_real(), REPO)
    assert not bad, "import circles (strongly connected modules):\n" + "\n".join(bad)


def test_no_private_name_crosses_a_file():
    mods = _real()
    bad = check_private_imports(mods, REPO, PRIVATE_ALLOWED)
    assert not bad, ("private names imported from another file (make them public where they "
                     "live):\n" + "\n".join(bad))
    seen = {(w.split(":")[0], t, n) for w, t, n in private_imports(mods, REPO)}
    assert PRIVATE_ALLOWED <= seen, f"remove from PRIVATE_ALLOWED: {PRIVATE_ALLOWED - seen}"


def test_calib_is_built_of_wings_that_import_only_downwards():
    assert not check_wing_layout(REPO), "\n".join(check_wing_layout(REPO))
    bad = check_wing_imports(_real(), REPO)
    assert not bad, "imports across the wings of calib (rule h):\n" + "\n".join(bad)


def test_validation_generators_import_neither_bench_nor_calib():
    mods = scan(REPO, ("validation",))
    assert "validation.cases" in mods and "validation.score" in mods  # the rule sees the files
    bad = check_validation_imports(mods, REPO)
    assert not bad, ("validation/ generators must not import bench, calib or the scorer:\n"
                     + "\n".join(bad))
    bad = check_dynamic_imports(mods, REPO) + check_cycles(mods, REPO)
    assert not bad, "\n".join(bad)


def test_the_independent_generator_shares_nothing_with_the_first():
    mods = scan(REPO, ("validation",))
    for prefix in SEPARATE_SETS:
        assert f"{prefix}.generate" in mods and f"{prefix}.score" in mods
        bad = check_independent_imports(mods, REPO, prefix)
        where = prefix.replace(".", "/")
        assert not bad, (f"{where}/ must not import the rest of validation/:\n"
                         + "\n".join(bad))


# --- each checker can fail: a synthetic tree ------------------------------------------------

def _tree(root: Path, files: dict[str, str]) -> dict[str, Module]:
    for rel, text in files.items():
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(textwrap.dedent(text), encoding="utf-8")
    for pkg in PACKAGES:
        (root / pkg).mkdir(exist_ok=True)
        (root / pkg / "__init__.py").touch()
    return scan(root)


def test_checker_a_finds_forbidden_imports_in_calib_even_inside_functions(tmp_path):
    mods = _tree(tmp_path, {
        "calib/est.py": """
            from typing import TYPE_CHECKING
            import numpy as np
            if TYPE_CHECKING:
                import matplotlib  # annotations only: allowed
            def plot():
                import rerun as rr
            from bench import tilt
            """,
        "calib/ok.py": "from calib import est\nimport scipy\n",
        "bench/tilt.py": "import mujoco\nimport calib.est\n",  # bench may import these
    })
    bad = check_calib_imports(mods, tmp_path)
    assert any("calib/est.py:7 imports rerun" in b for b in bad), bad
    assert any("calib/est.py:8 imports bench" in b for b in bad), bad
    assert not any("matplotlib" in b or "ok.py" in b or "tilt.py" in b for b in bad), bad


def test_checker_b_finds_argparse_and_cli_imports_outside_the_cli_package(tmp_path):
    mods = _tree(tmp_path, {
        "bench/cli/__init__.py": "import argparse\nfrom bench.cli import generate\n",
        "bench/cli/generate.py": "import argparse\nfrom bench import vehicle\n",
        "bench/vehicle.py": "def add_options(p):\n    from bench.cli.generate import x\n",
        "bench/course.py": "from argparse import Namespace\n",
        "calib/files/course.py": "import numpy\n",
    })
    bad = check_cli_imports(mods, tmp_path)
    assert bad == ["bench/course.py:1 imports argparse",
                   "bench/vehicle.py:2 imports bench.cli.generate"], bad


def test_checker_c_finds_importlib_and_dunder_import(tmp_path):
    mods = _tree(tmp_path, {
        "bench/a.py": "import importlib\nm = importlib.import_module('calib')\n",
        "bench/b.py": "def f():\n    return __import__('calib.files.course')\n",
        "calib/c.py": "from importlib import import_module\n",
        "calib/d.py": "import builtins\nx = builtins.__import__\n",
        "calib/ok.py": "import numpy as np\n",
    })
    bad = check_dynamic_imports(mods, tmp_path)
    files = {b.split(":")[0] for b in bad}
    assert files == {"bench/a.py", "bench/b.py", "calib/c.py", "calib/d.py"}, bad


def test_checker_d_finds_circles_through_deferred_and_package_imports(tmp_path):
    mods = _tree(tmp_path, {
        "bench/x.py": "def f():\n    from bench import y\n",      # deferred still counts
        "bench/y.py": "from bench.x import f\n",
        "bench/p/__init__.py": "from bench.p.q import g\n",
        "bench/p/q.py": "from . import helper\n",                     # relative, to __init__
        "bench/z.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                      "    from bench.w import W\n",
        "bench/w.py": "from bench.z import TYPE_CHECKING\n",          # guarded: still a circle
        "calib/a.py": "from calib.b import x\n",
        "calib/b.py": "x = 1\n",
    })
    assert check_cycles(mods, tmp_path) == [
        "circle: bench/p/__init__.py, bench/p/q.py",
        "circle: bench/w.py, bench/z.py",
        "circle: bench/x.py, bench/y.py",
    ]


def test_checker_d_finds_circles_that_only_annotations_close(tmp_path):
    """The 9-file shape that calib/effects had: a plugin typed against the engine that imports
    it (typing only), through a registry module; a protocol below both breaks it."""
    mods = _tree(tmp_path, {
        "calib/fx/__init__.py": "",
        "calib/fx/engine.py": "from calib.fx import catalog\n",
        "calib/fx/catalog.py": "import calib.fx.plugin\n",
        "calib/fx/plugin.py": """
            from __future__ import annotations
            import typing
            from calib.fx.base import Effect
            if typing.TYPE_CHECKING:
                from calib.fx.engine import Engine
            """,
        "calib/fx/base.py": "from typing import Protocol\nclass Effect: ...\n",
        "calib/ok/__init__.py": "",
        "calib/ok/protocols.py": "from typing import Protocol\nclass Likelihood(Protocol): ...\n",
        "calib/ok/plugin.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                              "    from calib.ok.protocols import Likelihood\n",
        "calib/ok/engine.py": "import calib.ok.plugin\nimport calib.ok.protocols\n",
    })
    assert check_cycles(mods, tmp_path, typing=False) == []  # what rule (d) saw before
    assert check_cycles(mods, tmp_path) == [
        "circle: calib/fx/catalog.py, calib/fx/engine.py, calib/fx/plugin.py"]
    # the typing edge is recorded where it is, and the other rules still skip it
    assert [t for t, _, _ in mods["calib.fx.plugin"].typing_imports] == ["calib.fx.engine"]
    assert "calib.fx.engine" not in [t for t, _, _ in mods["calib.fx.plugin"].imports]


def test_checker_e_finds_bench_calib_and_scorer_imports_in_validation_generators(tmp_path):
    _tree(tmp_path, {
        "validation/__init__.py": "",
        "validation/effects.py": ("import numpy as np\ndef f():\n"
                                  "    from calib.files.course import Ensayo\n"),
        "validation/designs.py": "from bench import model\nimport mujoco\n",
        "validation/cases.py": "from validation import effects, score\n",
        "validation/sweep.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                               "    import calib\nimport scipy\n",
        "validation/score.py": "from calib.gap import analyze_gap\n",  # the scorer may
    })
    bad = check_validation_imports(scan(tmp_path, ("validation",)), tmp_path)
    assert bad == ["validation/cases.py:1 imports validation.score",
                   "validation/designs.py:1 imports bench",
                   "validation/effects.py:3 imports calib.files.course"], bad


def test_checker_f_finds_private_names_taken_from_another_file(tmp_path):
    mods = _tree(tmp_path, {
        "calib/core.py": "_hidden = 1\npublic = 2\ndef _helper(): ...\n",
        "calib/sub/__init__.py": "",
        "calib/sub/deep.py": "_deep = 3\n",
        "calib/user.py": """
            from calib.core import (
                public,
                _helper,
            )
            from calib.core import public as p, _hidden as h
            def later():
                from .sub.deep import _deep
            """,
        "calib/alias.py": """
            import calib.core as c
            import calib.sub.deep
            from calib import core
            from calib.sub import deep as d
            x = c._hidden + core._helper() + calib.sub.deep._deep + d._deep
            y = c.public + c.__name__
            """,
        "calib/fine.py": """
            from calib.core import public
            import numpy as np
            _mine = np._NoValue  # not a project module
            def _own(): ...
            z = _own()
            """,
        "bench/b.py": "from calib.core import _hidden\n",
    })
    got = sorted(check_private_imports(mods, tmp_path))
    assert got == sorted([
        "calib/user.py:2 imports _helper from calib.core",
        "calib/user.py:6 imports _hidden from calib.core",
        "calib/user.py:8 imports _deep from calib.sub.deep",
        "calib/alias.py:6 imports _hidden from calib.core",
        "calib/alias.py:6 imports _helper from calib.core",
        "calib/alias.py:6 imports _deep from calib.sub.deep",
        "calib/alias.py:6 imports _deep from calib.sub.deep",
        "bench/b.py:1 imports _hidden from calib.core",
    ]), got
    allowed = {("bench/b.py", "calib.core", "_hidden")}
    assert "bench/b.py:1 imports _hidden from calib.core" not in check_private_imports(
        mods, tmp_path, allowed)


def test_checker_g_finds_imports_of_the_first_generator_in_the_independent_one(tmp_path):
    _tree(tmp_path, {
        "validation/__init__.py": "",
        "validation/effects.py": "G = 9.8\n",
        "validation/independent/__init__.py": "",
        "validation/independent/physics.py": "from validation.effects import G\n",
        "validation/independent/cases.py": "from . import physics\nfrom .. import effects\n",
        "validation/independent/generate.py": "from validation.independent import cases\n",
        "validation/independent/score.py": "import json\n",
    })
    mods = scan(tmp_path, ("validation",))
    assert check_independent_imports(mods, tmp_path) == [
        "validation/independent/cases.py:2 imports validation.effects",
        "validation/independent/physics.py:1 imports validation.effects"]
    # the drive part: neither the first generator nor the independent one
    _tree(tmp_path, {
        "validation/drive/__init__.py": "",
        "validation/drive/motion.py": "import numpy as np\n",
        "validation/drive/cases.py": "from ..independent import physics\nfrom . import motion\n",
        "validation/drive/generate.py": "def f():\n    from validation import effects\n",
        "validation/drive/score.py": "from .cases import x\n",
    })
    mods = scan(tmp_path, ("validation",))
    assert check_independent_imports(mods, tmp_path, "validation.drive") == [
        "validation/drive/cases.py:1 imports validation.independent",
        "validation/drive/generate.py:2 imports validation.effects"]
    # the scorer of the independent set is a scorer: generators may not import it
    mods["validation.independent.generate"].imports.append(
        ("validation.independent.score", (), 9))
    assert check_validation_imports(mods, tmp_path) == [
        "validation/independent/generate.py:9 imports validation.independent.score"]


def test_checker_h_finds_arrows_across_wings_and_stray_top_level_modules(tmp_path):
    uses = {"files": frozenset(), "vehicle": frozenset({"files"}), "empty": frozenset()}
    mods = _tree(tmp_path, {
        "calib/conventions.py": "def f():\n    from calib.vehicle import region\n",
        "calib/stray.py": "",
        "calib/files/__init__.py": '"""Files."""\n',
        "calib/files/course.py": "from calib.vehicle.region import decide\nimport numpy\n",
        "calib/files/atomic.py": "from calib.files import course\nfrom calib import conventions\n",
        "calib/vehicle/__init__.py": '"""Vehicle."""\n',
        "calib/vehicle/region.py": "from calib.files.course import read\nfrom calib import x\n",
        "calib/empty/__init__.py": "",
        "calib/unknown/__init__.py": '"""Not listed."""\n',
    })
    bad = check_wing_imports(mods, tmp_path, ground=frozenset({"conventions"}), uses=uses)
    assert any("calib/files/course.py imports calib.vehicle.region" in b for b in bad), bad
    assert any("calib/conventions.py imports calib.vehicle" in b for b in bad), bad
    assert any("calib/vehicle/region.py imports calib:" in b for b in bad), bad
    assert not any("atomic.py" in b or "files.course:" in b for b in bad), bad
    layout = check_wing_layout(tmp_path, ground=frozenset({"conventions"}), uses=uses)
    assert "calib/stray.py is neither ground nor inside a wing" in layout, layout
    assert "calib/unknown/ is not a wing of WING_USES" in layout, layout
    assert any("calib/empty/__init__.py has no docstring" in b for b in layout), layout
    assert not any("files" in b or "vehicle" in b for b in layout), layout
    assert check_wing_layout(tmp_path, ground=frozenset(map(str, range(9))), uses=uses)[0] == \
        "9 ground modules (at most 8)"
