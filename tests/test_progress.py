"""The progress helper (bench/cli/progress.py): a tqdm bar with rate and ETA on a terminal,
at most one plain line per 10 % when piped, nothing with ``quiet``."""

from __future__ import annotations

import io
import re

import pytest

from bench.cli.progress import MAX_COLUMNS, Progress

HEAD = re.compile(r"^\[generate class +\d+\.\d s\] ")


class Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.mark.parametrize("total", [3, 10, 88, 1000])
def test_piped_counter_prints_at_most_one_line_per_tenth(total):
    log = io.StringIO()
    p = Progress("generate class", log)
    p("starting")
    for k in range(total + 1):
        p.count(k, total, "course sets")
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue()
    assert all(HEAD.match(ln) for ln in lines)
    counts = [ln.split("] ", 1)[1] for ln in lines[1:]]
    assert 2 <= len(counts) <= 11 + 1  # 0 %, each tenth, the end
    done = [int(re.search(r"course sets (\d+)/", c).group(1)) for c in counts]
    tenths = [10 * d // total for d in done]
    assert len(set(tenths)) == len(tenths)  # never two lines in one tenth
    assert done[-1] == total and counts[-1].startswith(f"course sets {total}/{total} (100 %)")
    # a rate and an ETA once something has moved (not on the last line: nothing is left)
    assert all(", ETA " in c and "/s" in c for c in counts[1:-1])


def test_terminal_counter_is_a_tqdm_bar_with_rate_and_eta():
    term = Tty()
    p = Progress("fusion-study", term)
    for k in range(1, 89):
        p.count(k, 88, "tasks")
    p("done")
    text = term.getvalue()
    assert "\r" in text and "88/88" in text and "tasks/s" in text
    assert "<" in text  # tqdm's "[elapsed<remaining" ETA field
    assert all(len(seg) <= MAX_COLUMNS for ln in text.split("\n") for seg in ln.split("\r"))
    assert text.rstrip("\n").splitlines()[-1].startswith("[fusion-study")


def test_a_new_counter_restarts_and_a_step_line_closes_the_bar():
    log = io.StringIO()
    p = Progress("design", log)
    for k in (0, 5, 10):
        p.count(k, 10, "cells")
    p("fitting")
    for k in (0, 2):
        p.count(k, 2, "runs")
    counts = [ln.split("] ", 1)[1] for ln in log.getvalue().splitlines()]
    assert counts[0].startswith("cells 0/10") and counts[2].startswith("cells 10/10")
    assert counts[3] == "fitting" and counts[-1].startswith("runs 2/2 (100 %)")


def test_quiet_prints_nothing():
    for stream in (io.StringIO(), Tty()):
        p = Progress("x", stream, quiet=True)
        p("nothing")
        for k in range(4):
            p.count(k, 3, "things")
        assert stream.getvalue() == ""


def test_a_count_message_from_a_line_callback_is_a_counter():
    """calib.design reports its Monte Carlo chunks as lines "Monte Carlo chunks k/n"."""
    log = io.StringIO()
    p = Progress("design", log)
    for k in range(1, 41):
        p(f"Monte Carlo chunks {k}/40")
    p("2 experiment(s): nominal fits 3/4 done")  # not a bare count: a step line
    counts = [ln.split("] ", 1)[1] for ln in log.getvalue().splitlines()]
    assert len(counts) == 12 and counts[-2].startswith("Monte Carlo chunks 40/40 (100 %)")
    assert counts[-1] == "2 experiment(s): nominal fits 3/4 done"


@pytest.mark.parametrize("argv", [
    ["design"], ["nmin", "--ensayo", "e", "--acel", "a", "--puntos", "p"],
    ["generate", "class", "--students", "1", "--out", "c"], ["fusion-study"]])
def test_long_commands_take_quiet(argv):
    from bench.cli import build_parser

    args = build_parser().parse_args([*argv, "--quiet"])
    assert args.quiet is True
