"""The one progress reporter of the long commands: lines on stderr, stdout stays for results.

What users see (``fusion-study``, ``design``, ``nmin``, ``generate class``, ``demo``):

* a step line ``[COMMAND  12.3 s] message`` (time since the command started);
* on a terminal, a counted step is a `tqdm <https://tqdm.github.io>`_ bar redrawn in place,
  with its count, rate and ETA, e.g.
  ``[fusion-study] tasks  40%|████▍      | 35/88 [01:10<01:46, 0.50 tasks/s]``, never wider
  than 100 columns;
* when stderr is not a terminal (a pipe, a log file, CI), a counted step prints plain lines,
  at most one per 10 % of the count (and the last), each with its rate and ETA:
  ``[fusion-study  70.1 s] tasks 35/88 (39 %), 0.50/s, ETA 106 s``;
* nothing at all with ``--quiet``.

Reading a long measured log (``import``, ``calibrate``, ``noise`` and every command that reads
one: :func:`log_progress`) is counted in bytes of the file: on a terminal a bar with MiB, rate
and ETA, shown once the reading has taken :data:`BAR_DELAY` s (a short log shows nothing);
elsewhere plain lines, ``[import  3.1 s] reading log.csv 118/236 MiB (50 %), 75.9 MiB/s, ETA
2 s``, only for a log of :data:`LONG_LOG_BYTES` or more. All of it goes to stderr: stdout stays
the command's (one JSON object with ``--json``).

Domain functions never print: they take a callback ``progress: Callable[[str], None] | None``
(and a counter ``count(done, total)``) and the command passes a :class:`Progress`. tqdm draws
the terminal bar (rate smoothing, ETA, terminal width) because it does that well and is
widely kept; the plain lines are written here because tqdm's non-terminal output is a stream
of carriage-return redraws that fills a log.
"""

from __future__ import annotations

import re
import sys
import time
from collections.abc import Callable
from typing import IO

#: widest bar drawn on a terminal (the 100-column rule of every command's output).
MAX_COLUMNS = 100
#: the plain (non-terminal) counter prints at most one line per this share of the count.
STEP_SHARE = 0.10
#: a log at least this large (bytes) prints its reading progress when stderr is not a
#: terminal (≈ 1.5 s of reading).
LONG_LOG_BYTES = 64 << 20
#: on a terminal, a log's reading bar appears once the reading has taken this long, s.
BAR_DELAY = 0.5
#: a line-callback message that is a count: ``"Monte Carlo chunks 3/40"``.
_COUNT = re.compile(r"^(?P<what>[A-Za-z][\w \-]*?) (?P<done>\d+)/(?P<total>[1-9]\d*)$")


class Progress:
    """Progress of one command (module docstring). ``quiet`` silences it.

    ``progress(msg)`` writes a step line; ``progress.count(done, total, what)`` advances the
    counter named ``what`` (a new ``what`` or ``total`` starts a new counter); with
    ``in_bytes`` the counts are bytes, drawn in KiB/MiB.
    """

    def __init__(self, command: str, stream: IO[str] | None = None, quiet: bool = False
                 ) -> None:
        self.command = command
        self.stream = stream if stream is not None else sys.stderr
        self.quiet = quiet
        self.t0 = time.perf_counter()
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self._bar = None  # the tqdm bar of the open counter (terminal)
        self._key: tuple[str, int] | None = None  # (what, total) of the open counter
        self._start = 0.0  # when the open counter started (perf_counter)
        self._first = 0  # its count when it started (a resumed count)
        self._decile = -1  # the last tenth printed by the plain counter
        self._bytes = False  # the open counter counts bytes

    def _head(self) -> str:
        return f"[{self.command} {time.perf_counter() - self.t0:5.1f} s]"

    def __call__(self, message: str) -> None:
        """One step line (closes an open bar first).

        A message ``"WHAT k/n"`` is a count (:meth:`count`): library functions that take only
        a line callback (``calib.design``'s Monte Carlo chunks) report their progress so, and
        are drawn as a bar too without knowing this class.
        """
        if self.quiet:
            return
        m = _COUNT.match(message)
        if m and 0 <= int(m["done"]) <= int(m["total"]):
            self.count(int(m["done"]), int(m["total"]), m["what"])
            return
        self.close()
        self.stream.write(f"{self._head()} {message}\n")
        self.stream.flush()

    def count(self, done: int, total: int, what: str, *, in_bytes: bool = False) -> None:
        """``what done/total``: a bar on a terminal, a line per 10 % otherwise; ``in_bytes``:
        the counts are bytes (a bar in MiB that shows after :data:`BAR_DELAY` s)."""
        if self.quiet or total <= 0:
            return
        if self._key != (what, total) or (self._bar is not None and done < self._bar.n):
            self.close()
            self._key = (what, total)
            self._start = time.perf_counter()
            self._first = done
            self._decile = -1
            self._bytes = in_bytes
            if self.tty:
                self._bar = self._new_bar(total, what)
        if self._bar is not None:
            self._bar.update(max(0, done - self._bar.n))
        else:
            self._plain(done, total, what)
        if done >= total:
            self.close()

    def _new_bar(self, total: int, what: str):
        from tqdm import tqdm  # only on a terminal: start-up time of the other commands

        width = min(MAX_COLUMNS, _terminal_columns(self.stream))
        unit = ({"unit": "B", "unit_scale": True, "unit_divisor": 1024, "delay": BAR_DELAY}
                if self._bytes else {"unit": f" {what}"})
        # nrows given: tqdm otherwise asks the terminal, and a pseudo-terminal without a
        # window reports 0 rows, which hides the bar
        return tqdm(total=total, desc=f"[{self.command}] {what}", file=self.stream,
                    ncols=width, nrows=24, leave=True, mininterval=0.2, smoothing=0.1, **unit)

    def _plain(self, done: int, total: int, what: str) -> None:
        decile = min(10, int(done / (STEP_SHARE * total) + 1e-12))
        if decile <= self._decile and done < total:
            return
        self._decile = decile if done < total else 11
        elapsed = time.perf_counter() - self._start
        moved = done - self._first
        if self._bytes:
            line = f"{what} {_sizes(done, total)} ({100 * done // total} %)"
        else:
            line = f"{what} {done}/{total} ({100 * done / total:.0f} %)"
        if moved > 0 and elapsed > 0:
            rate = moved / elapsed
            line += f", {rate / 2**20:.3g} MiB/s" if self._bytes else f", {rate:.3g}/s"
            if done < total:
                line += f", ETA {(total - done) / rate:.0f} s"
        self.stream.write(f"{self._head()} {line}\n")
        self.stream.flush()

    def close(self) -> None:
        """End the open counter (its bar stays on screen)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        self._key = None


def log_progress(command: str, path, stream: IO[str] | None = None, quiet: bool = False
                 ) -> Callable[[int, int], None] | None:
    """The ``progress(done, total)`` callback of reading the log ``path`` (bytes of the file:
    :func:`calib.logs.reader.read_log`), or None when nothing would be shown: ``quiet``, or
    stderr not a terminal and the log shorter than :data:`LONG_LOG_BYTES` (module
    docstring)."""
    import os

    if quiet:
        return None
    progress = Progress(command, stream)
    try:
        size = os.path.getsize(path)
    except OSError:  # a ROS 2 bag folder, a missing file: the reader says what is wrong
        size = 0
    if not progress.tty and size < LONG_LOG_BYTES:
        return None
    what = f"reading {os.path.basename(os.fspath(path).rstrip(os.sep)) or path}"

    def report(done: int, total: int) -> None:
        progress.count(done, total, what, in_bytes=True)

    return report


def _sizes(done: int, total: int) -> str:
    """``done/total`` bytes in the unit of ``total``: ``"118/236 MiB"``, ``"2.5/9.8 MiB"``,
    ``"12/40 KiB"``."""
    if total < 2**20:
        return f"{done / 2**10:.0f}/{total / 2**10:.0f} KiB"
    digits = 0 if total >= 10 * 2**20 else 1
    return f"{done / 2**20:.{digits}f}/{total / 2**20:.{digits}f} MiB"


def _terminal_columns(stream: IO[str]) -> int:
    """Columns of the terminal behind ``stream`` (at least 40; unknown: 100)."""
    import os
    import shutil

    try:
        cols = os.get_terminal_size(stream.fileno()).columns
    except (AttributeError, OSError, ValueError):
        cols = shutil.get_terminal_size((MAX_COLUMNS, 24)).columns
    # a terminal that reports no size (0 columns: a pseudo-terminal without a window) would
    # get an empty bar
    return cols if cols >= 40 else MAX_COLUMNS
