"""The command line builds only the parser of the command it runs (start-up time): the name →
module table must name every command the full parser has, and a command parsed alone must
parse as it does among all of them."""

from __future__ import annotations

import pytest

from bench.cli import BY_NAME, COMMANDS, build_parser


def _names(parser) -> list[str]:
    sub = next(a for a in parser._actions if a.dest == "command")
    return list(sub.choices)


def test_the_table_names_every_command_once():
    assert sorted(_names(build_parser())) == sorted(BY_NAME)
    assert set(BY_NAME.values()) == set(COMMANDS)


@pytest.mark.parametrize("name", sorted(BY_NAME))
def test_a_command_alone_registers_only_itself(name):
    assert _names(build_parser(only=name)) == [name]


@pytest.mark.parametrize("argv", [
    ["noise", "log.csv", "--level", "0.9", "--json"],
    ["calibrate", "ensayo.mat", "--noise-var", "0.25,0.64"],
    ["gap", "ensayo.mat", "--rate", "100"],
])
def test_parsed_alone_as_among_all(argv):
    alone = vars(build_parser(only=argv[0]).parse_args(argv))
    among = vars(build_parser().parse_args(argv))
    assert alone.keys() == among.keys()
    assert {k: v for k, v in alone.items() if k != "handler"} == \
        {k: v for k, v in among.items() if k != "handler"}
    assert alone["handler"] is among["handler"]


def test_an_unknown_word_builds_the_whole_parser():
    assert sorted(_names(build_parser(only="nosuch"))) == sorted(BY_NAME)
