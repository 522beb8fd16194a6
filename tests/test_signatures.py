"""Long positional calls are not written: in the files below, a function with more than
:data:`MAX_POSITIONAL` parameters takes the rest by keyword (``*,``), and a dataclass with more
than that many fields is ``kw_only`` (checked on the source with ``ast``; the checker itself is
tried on a synthetic file). The files are the fusion wing, the N analysis and the validation
result; the other long signatures of the tree are listed in the house report (issue 21)."""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
MAX_POSITIONAL = 8
CHECKED = ["calib/fusion/kalman.py", "calib/fusion/linear.py", "calib/fusion/turning.py",
           "calib/vehicle/arrival.py", "calib/vehicle/region.py",
           "calib/vehicle/turning_trajectory.py",
           "calib/numerics.py", *sorted(str(p.relative_to(REPO))
                                        for p in (REPO / "calib/vehicle/nmin").glob("*.py")),
           "bench/cli/fuse.py", "bench/cli/nmin.py", "bench/record/fusion.py",
           "bench/validate.py", "bench/validate_inputs.py", "bench/limits.py"]


def long_signatures(source: str, name: str) -> list[str]:
    """``name:line what`` for each function with more than MAX_POSITIONAL positional
    parameters (``self``/``cls`` not counted) and each positional dataclass with more fields."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            pos = [a.arg for a in node.args.posonlyargs + node.args.args
                   if a.arg not in ("self", "cls")]
            if len(pos) > MAX_POSITIONAL:
                out.append(f"{name}:{node.lineno} def {node.name}: {len(pos)} positional")
        elif isinstance(node, ast.ClassDef):
            for dec in node.decorator_list:
                call = dec if isinstance(dec, ast.Call) else None
                func = call.func if call else dec
                if getattr(func, "id", getattr(func, "attr", "")) != "dataclass":
                    continue
                kw_only = call is not None and any(
                    k.arg == "kw_only" and getattr(k.value, "value", False) is True
                    for k in call.keywords)
                n = sum(isinstance(s, ast.AnnAssign) for s in node.body)
                if n > MAX_POSITIONAL and not kw_only:
                    out.append(f"{name}:{node.lineno} class {node.name}: {n} positional fields")
    return out


def test_no_long_positional_signatures():
    bad = [x for rel in CHECKED
           for x in long_signatures((REPO / rel).read_text(encoding="utf-8"), rel)]
    assert not bad, "take keywords past eight parameters (*, or kw_only=True):\n" + \
        "\n".join(bad)


def test_checker_finds_long_functions_and_dataclasses():
    src = '''
from dataclasses import dataclass
def ok(a, b, c, d, e, f, g, h, *, i, j): ...
def long(a, b, c, d, e, f, g, h, i): ...
class K:
    def method(self, a, b, c, d, e, f, g, h): ...
    def too_long(self, a, b, c, d, e, f, g, h, i): ...
@dataclass(frozen=True)
class Wide:
    a: int; b: int; c: int; d: int; e: int; f: int; g: int; h: int; i: int
@dataclass(frozen=True, kw_only=True)
class WideKw:
    a: int; b: int; c: int; d: int; e: int; f: int; g: int; h: int; i: int
@dataclass
class Bare:
    a: int; b: int; c: int; d: int; e: int; f: int; g: int; h: int; i: int
'''
    assert sorted(long_signatures(src, "x.py")) == sorted([
        "x.py:4 def long: 9 positional", "x.py:7 def too_long: 9 positional",
        "x.py:9 class Wide: 9 positional fields", "x.py:15 class Bare: 9 positional fields"])
