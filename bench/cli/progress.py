"""The one progress reporter of the long commands: lines on stderr, stdout stays for results.

Every line reads ``[COMMAND  12.3 s] message`` (time since the command started). Counters
(``k/total``) are redrawn in place with a carriage return only when stderr is a terminal; in a
log every count gets its own line. Domain functions never print: they take a callback
``progress: Callable[[str], None] | None`` and the command passes a :class:`Progress`.
"""

from __future__ import annotations

import sys
import time
from typing import IO


class Progress:
    """Progress lines of one command (module docstring). ``quiet`` silences them."""

    def __init__(self, command: str, stream: IO[str] | None = None, quiet: bool = False
                 ) -> None:
        self.command = command
        self.stream = stream if stream is not None else sys.stderr
        self.quiet = quiet
        self.t0 = time.perf_counter()
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self._open = 0  # length of a line left open by a carriage-return update

    def _head(self) -> str:
        return f"[{self.command} {time.perf_counter() - self.t0:5.1f} s]"

    def __call__(self, message: str) -> None:
        """One line."""
        if self.quiet:
            return
        self._close()
        self.stream.write(f"{self._head()} {message}\n")
        self.stream.flush()

    def count(self, done: int, total: int, what: str) -> None:
        """``what done/total``: redrawn in place on a terminal, one line each otherwise."""
        if self.quiet:
            return
        if not self.tty:
            self(f"{what} {done}/{total}")
            return
        text = f"{self._head()} {what} {done}/{total}"
        self.stream.write("\r" + text + " " * max(0, self._open - len(text)))
        self._open = len(text)
        if done >= total:
            self._close()
        self.stream.flush()

    def _close(self) -> None:
        if self._open:
            self.stream.write("\n")
            self._open = 0
