"""One vocabulary (issue 29): an option name means one thing, in one unit, in every command.

The table of every option of every command is derived from the argument parsers themselves
(``build_parser()``, :func:`bench.cli.vocabulary.option_table`); each option carries the term it
was added with, declared once in :data:`bench.cli.vocabulary.VOCABULARY`. The check
(:func:`bench.cli.vocabulary.vocabulary_problems`) is also run on small planted parsers: a name
reused with another meaning or unit, an option with no declared meaning, a help that states
another unit, a name declared twice, an alias nobody listed — each must be caught, so a check
that can never fail would show. Renamed options keep their old spelling as a hidden alias that
says the new one on stderr.
"""

from __future__ import annotations

import argparse
import json
import re

import pytest

from bench.cli import build_parser, main
from bench.cli.generate import GPS_MAGNITUDE_LIMITS
from bench.cli.options import MAGNITUDE_LIMITS, Parser
from bench.cli.output import COLUMNS
from bench.cli.vocabulary import (
    RENAMED,
    TERMS,
    VOCABULARY,
    Term,
    add_option,
    option_table,
    states_unit,
    unused_terms,
    vocabulary_problems,
)


@pytest.fixture(scope="module")
def table():
    return option_table(build_parser())


def _commands(parser: argparse.ArgumentParser, prefix: str = "") -> list[str]:
    """Every leaf command (``generate calibration``, ``record read``, ``design``, …)."""
    out = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                path = f"{prefix} {name}".strip()
                out += _commands(sub, path) or [path]
    return out


# ------------------------------------------------------------------ the real parsers
def test_every_option_of_every_command_means_one_thing(table):
    assert vocabulary_problems(table) == []


def test_the_table_covers_every_command_and_every_declared_name(table):
    commands = _commands(build_parser())
    assert {"generate calibration", "generate static", "record read", "design", "noise",
            "fuse", "examples"} <= set(commands)
    with_options = {r.command for r in table}
    assert with_options == set(commands)  # every command has options, and is in the table
    assert unused_terms(table) == []  # nothing declared that no command uses
    assert len({t.name for t in VOCABULARY}) == len(VOCABULARY)


@pytest.mark.parametrize("name, unit", [("--rate", "Hz"), ("--sweep-rate", "rad/s"),
                                        ("--count", "count"), ("--scale", "1"),
                                        ("--level", "1"), ("--static-window", "s"),
                                        ("--profile", "s : m/s²")])
def test_the_names_of_the_issue_have_one_unit(table, name, unit):
    rows = [r for r in table if r.name == name and r.renamed_to is None]
    assert rows and {r.term.unit for r in rows} == {unit}


def test_differing_numeric_defaults_say_why(table):
    """A default may differ between commands where the task differs; the term says why."""
    parser_defaults: dict[str, set] = {}

    def walk(p):
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                for sub in a.choices.values():
                    walk(sub)
            elif a.option_strings and getattr(a, "term", None) is not None:
                value = a.default.read() if hasattr(a.default, "read") else a.default
                if isinstance(value, str):
                    try:
                        value = float(value)
                    except ValueError:
                        continue
                if isinstance(value, (int, float)) and not isinstance(value, bool):
                    parser_defaults.setdefault(a.option_strings[0], set()).add(float(value))

    walk(build_parser())
    differing = sorted(n for n, values in parser_defaults.items() if len(values) > 1)
    assert {"--level", "--alpha", "--count", "--duration", "--runs"} <= set(differing)
    assert [n for n in differing if not TERMS[n].defaults] == []
    # --static-window: the pose detector's default is built in (0.5 s), noise's is 1 s
    assert "0.5 s" in TERMS["--static-window"].defaults
    assert "1 s" in TERMS["--static-window"].defaults


def test_magnitude_limits_name_declared_options():
    """The limits of numeric options are keyed by names with one meaning."""
    assert set(MAGNITUDE_LIMITS) | set(GPS_MAGNITUDE_LIMITS) <= set(TERMS)


def test_calibrate_prints_its_intervals_with_their_level(capsys, tmp_path):
    """Every interval printed says its level (here the table's columns)."""
    import numpy as np
    import scipy.io

    rng = np.random.default_rng(3)
    tita = np.repeat(np.linspace(0.0, 2 * np.pi, 8, endpoint=False), 25)
    ref = np.column_stack([-9.8 * np.sin(tita), -9.8 * np.cos(tita)])
    path = tmp_path / "ensayo.mat"
    scipy.io.savemat(path, {"tita": tita[:, None],
                            "datos": 1.01 * ref + 0.05 + rng.normal(0.0, 0.5, ref.shape)})
    for method in ("ols", "multiposition"):
        assert main(["calibrate", str(path), "--noise-var", "0.25,0.25", "--level", "0.9",
                     "--method", method]) == 0
        out = capsys.readouterr().out
        assert "[90%" in out and "95%" not in out, method


# ------------------------------------------------------------------ planted parsers
def _two_commands():
    parser = Parser(prog="t")
    sub = parser.add_subparsers(dest="command")
    return parser, sub.add_parser("sample"), sub.add_parser("sweep")


def test_a_name_reused_with_another_meaning_is_caught():
    parser, sample, sweep = _two_commands()
    add_option(sample, "--rate", type=float, default=100.0)
    planted = sweep.add_argument("--rate", help="mean sweep rate, rad/s")
    planted.term = Term("--rate", "mean sweep rate", "rad/s")  # its own idea of --rate
    problems = vocabulary_problems(option_table(parser), renamed=())
    assert any(p.startswith("--rate has 2 meanings") and "(Hz) in sample" in p
               and "'mean sweep rate' (rad/s) in sweep" in p for p in problems), problems
    assert any("sweep: --rate means 'mean sweep rate' (rad/s)" in p for p in problems)


def test_an_option_without_a_declared_meaning_is_caught():
    parser, sample, sweep = _two_commands()
    add_option(sample, "--rate", type=float)
    sweep.add_argument("--rate", help="mean sweep rate, rad/s")
    problems = vocabulary_problems(option_table(parser), renamed=())
    assert problems == ["sweep: --rate has no declared meaning (add it with "
                        "bench.cli.vocabulary.add_option, its term in VOCABULARY)"]


def test_a_help_that_states_another_unit_is_caught():
    parser, sample, sweep = _two_commands()
    add_option(sample, "--rate", type=float)
    add_option(sweep, "--rate", help="mean sweep rate, rad/s")
    problems = vocabulary_problems(option_table(parser), renamed=())
    assert len(problems) == 1 and "sweep: the help of --rate does not state its unit Hz" \
        in problems[0]


def test_a_name_declared_twice_is_caught():
    parser, sample, _ = _two_commands()
    add_option(sample, "--rate", type=float)
    twice = (*VOCABULARY, Term("--rate", "mean sweep rate", "rad/s"))
    assert "--rate: declared twice in the vocabulary" in vocabulary_problems(
        option_table(parser), vocabulary=twice)


def test_an_undeclared_name_cannot_be_added():
    with pytest.raises(KeyError, match="VOCABULARY"):
        add_option(argparse.ArgumentParser(), "--speed")


def test_aliases_are_checked_against_the_renamed_list():
    parser, sample, _ = _two_commands()
    add_option(sample, "--count", old="--samples")
    rows = option_table(parser)
    problems = vocabulary_problems(rows, renamed=(("sample", "--n", "--count"),))
    assert "sample: --samples is a deprecated alias of --count not listed in RENAMED" in problems
    assert any("RENAMED lists --n → --count" in p for p in problems)
    assert vocabulary_problems(rows, renamed=(("sample", "--samples", "--count"),)) == []


def test_unit_words():
    assert states_unit("run length, s", "s") and not states_unit("m/s", "s")
    assert not states_unit("samples", "s") and not states_unit("(m/s²)²", "m/s²")
    assert states_unit("in (m/s²)², e.g.", "(m/s²)²") and states_unit("(s : m/s²)", "s : m/s²")
    assert not states_unit("rad/s", "rad") and states_unit("position, m (3", "m")


# ------------------------------------------------------------------ deprecated spellings
DESIGN = ["design", "--designs", "uniform", "--effects", "misalignment", "--runs", "0",
          "--workers", "1", "--quiet", "--json"]


def test_renamed_design_options_still_work_and_say_the_new_name(capsys):
    assert main([*DESIGN, "--count", "301", "--sweep-rate", "0.5", "--scale", "0.02,0.01"]) == 0
    new = capsys.readouterr()
    assert new.err == ""
    assert main([*DESIGN, "--n", "301", "--rate", "0.5", "--scale", "0.02"]) == 0
    old = capsys.readouterr()
    assert old.out == new.out  # the same experiment, the same result
    lines = old.err.splitlines()
    assert lines == ["warning: --n is deprecated; use --count",
                     "warning: --rate is deprecated; use --sweep-rate",
                     "warning: --scale with one number (x) is deprecated; use --scale 0.02,0"]
    assert max(map(len, lines)) <= COLUMNS
    assert json.loads(new.out)["settings"]["gain"] == pytest.approx(1.02)


def test_design_scale_is_a_pair_and_the_axis_picks_its_gain(capsys):
    assert main([*DESIGN, "--count", "301", "--scale", "0.02,-0.04", "--axis", "y"]) == 0
    assert json.loads(capsys.readouterr().out)["settings"]["gain"] == pytest.approx(0.96)
    assert main([*DESIGN, "--scale", "0.02,0.6"]) == 2
    assert "--scale" in capsys.readouterr().err


def test_sweep_profile_keeps_its_old_spelling(capsys):
    p = build_parser()
    args = p.parse_args(["generate", "calibration", "--out", "o", "--profile", "sine"])
    assert args.sweep_profile == "sine"
    assert capsys.readouterr().err == "warning: --profile is deprecated; use --sweep-profile\n"
    with pytest.raises(SystemExit):  # the old spelling keeps the choices
        p.parse_args(["generate", "calibration", "--out", "o", "--profile", "spiral"])
    assert "invalid choice" in capsys.readouterr().err


@pytest.mark.parametrize("command, hidden", [(["design"], ("--n", "--rate")),
                                             (["generate", "calibration"], ("--profile",))])
def test_deprecated_spellings_are_hidden_from_help(capsys, command, hidden):
    with pytest.raises(SystemExit):
        main([*command, "--help"])
    text = capsys.readouterr().out
    for old in hidden:
        assert not re.search(rf"(?<![\w-]){re.escape(old)}\b", text), old
    for cmd, _, new in RENAMED:
        if cmd == " ".join(command):
            assert new in text


def test_renamed_names_are_the_new_ones_of_the_vocabulary():
    for _, old, new in RENAMED:
        assert new in TERMS and old != new
    # each old spelling that is still a name elsewhere keeps its own meaning there
    assert TERMS["--rate"].unit == "Hz" and TERMS["--profile"].unit == "s : m/s²"
