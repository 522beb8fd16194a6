"""Every stderr line fits 100 columns, error lines included (issue 29, item 5).

The refusals of the fuzz corpus (:mod:`validation.fuzz`: every case that must be refused, and
the kind ``message``, a refusal of each kind on every command) run here, in this process, on
the corpus's own inputs (built once, in this process too: about 10 s). Each must end in one
error message, wrapped at 100 columns like every other line (continuation lines indented 4,
broken at spaces only; a single word wider than 100 columns, a long path, stays whole on its
own line), that still names what it refuses: the option, the file or the value.

The checker is :func:`validation.fuzz.runner.wide_lines`, the one the full corpus uses
(``python -m validation.fuzz --out DIR``: fault ``wide_line``, and the widest line printed);
it is tested here on planted lines, so that it cannot silently pass everything.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import re
from collections import Counter

import pytest

from bench.cli import build_parser, main
from validation.fuzz.cases import all_cases
from validation.fuzz.fixtures import build
from validation.fuzz.runner import WIDTH, Case, error_lines, stage, wide_lines


def _in_process(argv: list[str], cwd) -> tuple[int, str, str]:
    """``tiltbench ARGV`` in this process, in ``cwd``: exit code, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.chdir(cwd), contextlib.redirect_stdout(out), \
            contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in argv])
        except SystemExit as exc:  # argparse: --help or its own error
            rc = exc.code
    return rc, out.getvalue(), err.getvalue()


def _build_step(argv: list[str], cwd, env) -> None:
    rc, _, err = _in_process(argv, cwd)
    assert rc == 0, f"fixture `tiltbench {' '.join(argv)}`: {err}"


@pytest.fixture(scope="module")
def refusals(tmp_path_factory) -> list[Case]:
    """The corpus's cases that must be refused, on inputs of seed 0 (no concurrent writers,
    no killed runs: those are the corpus's, in subprocesses)."""
    files = build(tmp_path_factory.mktemp("fuzz-inputs"), 0, {}, run=_build_step)
    # cases with their own pattern of what the refusal says (the front-door kinds) are run,
    # width and one-line rules included, by tests/test_fuzz_front_door.py
    return [c for c in all_cases(files) if c.expect == "refuse" and not c.parallel
            and c.kill_after is None and c.says is None]


def named(case: Case) -> list[str]:
    """What the refusal of ``case`` must name: the option given as ``--opt=value``, the file
    a ``cal_file`` / ``truth_file`` / ``gps_fault`` case edited, or what a ``message`` case
    got wrong (the unknown word, the missing file, the existing output)."""
    given = [a.split("=", 1)[0] for a in case.argv if re.match(r"^--[\w-]+=", a)]
    if given:
        return given
    edited = {"cal_file": ("cal.json", "cal.mat"), "truth_file": ("bad_truth.json",),
              "gps_fault": ("gps.mat",), "turning": ("acel.mat",)}.get(case.kind)
    if edited:
        return [a for a in case.argv if a in edited]
    return list(MESSAGE_NAMES.get(case.name, ()))


MESSAGE_NAMES = {
    "unknown command": ("'calibrat'",), "unknown option": ("--noise-variance",),
    "invalid choice": ("--method", "'ml'"), "required options missing": ("--acel", "--puntos"),
    "not an integer": ("--students", "'many'"), "unknown generate kind": ("'calibratoin'",),
    "unknown record action": ("'write'",), "unknown effect": ("--effects", "'misalignmnet'"),
    "runs below the minimum": ("--runs",), "level out of range": ("--level",),
    "calibrate missing input": ("missing.mat",), "gap missing input": ("missing.mat",),
    "trajectory missing input": ("missing.mat",), "nmin missing input": ("missing.mat",),
    "fuse missing input": ("missing.mat",), "validate missing input": ("missing.json",),
    "noise missing input": ("missing.csv",), "import missing input": ("missing.csv",),
    "apply missing input": ("missing.csv",),
    "record missing input": ("missing.rrd",), "demo missing course data": ("nowhere",),
    "a folder for a file": (".:",), "a JSON file for a recording": ("truth.json",),
    "a JSON file for a .mat": ("truth.json",), "a path wider than the terminal": ("--noise-var",),
    "a missing path wider than the terminal": ("a-folder-whose-name-is-long-enough/",),
    "existing output without --force": ("cal.json", "--force"),
    "existing outputs without --force": ("ensayo.mat", "--force"),
    "existing example without --force": ("README.md", "--force"),
    "fusion-study table without --force": ("fusion-study.md", "--force"),
    "output onto its input": ("ensayo.mat", "input"),
}
"""What each refusal of the kind ``message`` names (its unknown word, file or option)."""


KNOWN_VAGUE = {
    "option: nmin --steps 1e300": "names the subsampled run (ensayo.mat[::10³⁰⁰]), not --steps",
    "option: design --size misalignment=1e300": "refused by the gap check of the simulated "
                                                "run, without naming --size",
}
"""Refusals found naming neither the option nor its value (before issue 29's wrapping too):
each is still one message that fits, and stays listed here only while it is still vague."""


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    """The parsers of ``parser``'s commands (``generate``'s kinds, …) by name."""
    return {name: sub for a in parser._actions if isinstance(a, argparse._SubParsersAction)
            for name, sub in a.choices.items()}


def _aliases(argv: list[str], option: str) -> set[str]:
    """Every spelling of ``option`` in the parser of the command ``argv`` runs: the names of
    the actions that store where it stores (a renamed option and its former name)."""
    parser = build_parser()
    while (word := next((w for w in argv if w in _subcommands(parser)), None)) is not None:
        parser = _subcommands(parser)[word]
        argv = argv[argv.index(word) + 1:]
    actions = parser._actions
    dest = next((a.dest for a in actions if option in a.option_strings), None)
    return {option} | {s for a in actions if a.dest == dest for s in a.option_strings}


def problems(case: Case, rc: int, out: str, err: str) -> list[str]:
    """Why the run of a refusal breaks issue 29's rule or says less than before."""
    found = []
    readable = err if out.lstrip().startswith("{") else f"{err}\n{out}"  # --json: machine
    found += [f"{len(ln)} columns: {ln!r}" for ln in wide_lines(readable)]
    if rc != 2:
        return found + ([] if rc in case.ok_codes else [f"exit {rc}"])
    messages = error_lines(err)  # a wrapped message joined back to one line
    if len(messages) != 1:
        return found + [f"{len(messages)} error messages: {messages}"]
    message = messages[0]
    if not (message.startswith("tiltbench") and " error: " in message):
        found.append(f"not a tiltbench error line: {message!r}")
    vague = [f"does not name {what!r}: {message!r}" for what in named(case)
             if not any(spelling in message for spelling in _aliases(case.argv, what))]
    key = f"{case.kind}: {case.name}"
    if key in KNOWN_VAGUE:  # listed only while it is vague
        return found + ([] if vague else ["names it now: remove it from KNOWN_VAGUE"])
    return found + vague


def test_every_refusal_of_the_corpus_fits_and_names_what_it_refuses(refusals, tmp_path):
    report, refused = {}, Counter()
    for i, case in enumerate(refusals):
        root = tmp_path / f"{i:03d}"
        stage(case, root)
        rc, out, err = _in_process(case.argv, root)
        found = problems(case, rc, out, err)
        if found:
            report[f"{case.kind}: {case.name}"] = found
        refused[case.argv[0]] += rc == 2
    assert report == {}, json.dumps(report, indent=1, ensure_ascii=False)[:4000]
    # not vacuous: every command refuses here, every refusal names something, and the
    # names expected of the kind "message" are those of its cases
    assert set(_subcommands(build_parser())) <= {c for c, n in refused.items() if n}, refused
    assert all(named(c) for c in refusals), [c.name for c in refusals if not named(c)]
    assert {c.name for c in refusals if c.kind == "message"} == set(MESSAGE_NAMES)


# ---------------------------------------------------------------- the checker itself
def test_the_checker_fails_a_101_column_line_and_passes_100():
    line = "tiltbench calibrate: error: " + "x" * (WIDTH - 30) + " y"
    assert len(line) == WIDTH
    assert wide_lines(line) == []
    assert wide_lines(line + "z") == [line + "z"]  # 101 columns: caught
    assert wide_lines("ok\n" + line + "z\nok") == [line + "z"]  # on any line
    assert wide_lines("    " + "p" * 150) == []  # one word (a long path), alone: allowed
    assert wide_lines("wrote: /" + "p" * 150) != []  # a path after a label: not alone


def test_a_planted_wide_error_line_is_a_problem():
    case = Case("message", "unknown command", ["calibrat"], expect="refuse")
    good = ("tiltbench: error: argument COMMAND: invalid choice: 'calibrat' (choose from\n"
            "    'generate', 'calibrate', 'trajectory')\n")
    assert problems(case, 2, "", good) == []
    one_line = good.replace("\n    ", " ")  # the same message, not wrapped: 114 columns
    assert len(one_line.splitlines()[0]) > WIDTH
    assert problems(case, 2, "", one_line) and "columns" in problems(case, 2, "", one_line)[0]
    assert problems(case, 2, "", good + "tiltbench: error: again\n")  # two messages
    vague = good.replace("'calibrat'", "a word")
    assert [p.split(":")[0] for p in problems(case, 2, "", vague)] == [
        "does not name \"'calibrat'\""]
