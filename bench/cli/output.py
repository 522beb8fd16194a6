"""What commands print and the checks they make on their outputs before any work.

``--json``: one JSON object on stdout and nothing else there (:func:`print_json`). Readable
output names every file the command wrote (:func:`print_summary`, :func:`print_files`) and
fits 100 columns, and so does every line on stderr, error lines included: ``main`` runs
inside :func:`fit_columns`, which breaks a longer line at spaces with a hanging indent, never
inside a word, a path or a URL (a single word wider than 100 columns stays whole on its own
line).

Outputs are claimed before any work (:func:`command_outputs`, around every command in
``main``): each output named on the command line (:data:`OUTPUT_OPTIONS`) is locked
(:func:`calib.files.atomic.holding`) until the command ends, so a second run writing the same file
or folder is refused at once ("another tiltbench run is writing F (pid N)") instead of
replacing the first one's result; stale temporaries of killed runs are removed; and no
output may be one of the command's input files (same file by inode: another spelling, a
symbolic or a hard link), not even with ``--force``.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
import warnings
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import IO, Any, TypeVar

T = TypeVar("T")


class NonFiniteError(ValueError):
    """An output that would hold NaN or Infinity; the message names the field and why."""


def _non_finite_path(obj: Any, path: str = "") -> tuple[str, Any] | None:
    """Path (``a.b[3]``) and value of the first NaN/±Infinity in a JSON-like tree, or None.
    Iterative (a deep tree cannot exhaust the recursion limit)."""
    import math

    stack = [(path, obj)]
    while stack:
        where, node = stack.pop()
        if isinstance(node, float) and not math.isfinite(node):
            return where or "(the value)", node
        if isinstance(node, dict):
            stack += [(f"{where}.{k}" if where else str(k), v)
                      for k, v in reversed(list(node.items()))]
        elif isinstance(node, (list, tuple)):
            stack += [(f"{where}[{i}]", v) for i, v in reversed(list(enumerate(node)))]
        elif hasattr(node, "dtype") and hasattr(node, "shape"):  # a numpy array or scalar
            import numpy as np

            if node.dtype.kind in "fc":
                bad = np.argwhere(~np.isfinite(np.asarray(node)))
                if bad.size:
                    idx = tuple(int(i) for i in bad[0])
                    return f"{where}{list(idx) if idx else ''}", np.asarray(node)[idx]
    return None


def check_finite(obj: Any, what: str) -> None:
    """Refuse (:class:`NonFiniteError`) an output ``obj`` (JSON tree, arrays or a mapping of
    arrays) holding NaN or ±Infinity, naming ``what`` (the output) and the field. JSON has no
    such numbers (``json.dumps(..., allow_nan=False)`` would refuse them without saying
    where); a non-finite result means an input out of the range the options allow."""
    found = _non_finite_path(obj)
    if found is not None:
        field, value = found
        raise NonFiniteError(f"{what}: {field} would be {value} (not a finite number): the "
                             "computation overflowed or is undefined for these inputs; "
                             "nothing was written")


def json_text(obj: Any, what: str = "the JSON output") -> str:
    """``obj`` as stable JSON (:func:`calib.files.course.dumps`), refused if a number is not
    finite."""
    import json

    from calib.files.course import dumps

    text = dumps(obj)
    if "NaN" in text or "Infinity" in text:  # the only spellings json.dumps gives them
        check_finite(json.loads(text), what)  # (or a string that holds the word: passes)
    return text


_LOGS_READ: dict[str, dict] = {}
"""Provenance records of the logs the running command read, by role (``log``, ``ensayo``,
``acel``): :func:`note_log_read` fills it, :func:`print_json` writes it, ``main`` empties it
before each command."""


def note_log_read(role: str, provenance: dict) -> None:
    """Remember how a log was read (``role``: ``log``, ``ensayo`` or ``acel``) for the
    command's ``--json`` output (:func:`print_json`)."""
    _LOGS_READ[role] = provenance


def forget_logs_read() -> None:
    """Start a command with no log read (``main``: one process may run several commands)."""
    _LOGS_READ.clear()


def logs_read_provenance() -> dict | None:
    """What the ``provenance`` key of a command's JSON holds: the record of its one log, or
    ``{role: record}`` when it read two (``ensayo`` and ``acel``); None when it read none."""
    if not _LOGS_READ:
        return None
    if len(_LOGS_READ) == 1:
        return next(iter(_LOGS_READ.values()))
    return dict(_LOGS_READ)


def print_json(obj: Any) -> None:
    """``obj`` as stable JSON (:func:`calib.files.course.dumps`) on stdout; NaN or ±Infinity
    anywhere is an error naming the field (:func:`check_finite`), and nothing is printed.

    A command that read a measured log (through :func:`bench.cli.logopts.read_log_from_args`)
    gets its provenance — source and sha256, which column became what, units and factors —
    under ``provenance`` (:func:`logs_read_provenance`), unless ``obj`` has its own, and the
    units of its numbers in ``units`` (:func:`calib.logs.reader.provenance_units`).
    """
    provenance = logs_read_provenance()
    if isinstance(obj, dict) and provenance is not None and "provenance" not in obj:
        from calib.logs.reader import provenance_units

        units = dict(obj.get("units") or {})
        for role, record in _LOGS_READ.items():
            units.update(provenance_units(record, "provenance" if len(_LOGS_READ) == 1
                                          else f"provenance.{role}"))
        obj = {**{k: v for k, v in obj.items() if k != "units"}, "provenance": provenance,
               "units": units}
    print(json_text(obj), end="")


def print_summary(args: argparse.Namespace, title: str, summary: dict,
                  units: dict[str, str] | None = None) -> None:
    """What a generate command wrote: one JSON object with ``--json`` (with ``units``, the
    unit of each numeric key: docs/units.md), else readable lines (the title, scalar entries
    as ``key: value unit``, nested mappings one entry per line)."""
    from calib.units import unit_of, with_units

    units = dict(units or {})
    if args.json:
        print_json(with_units(summary, units))
        return
    lines = [title]
    for key, value in summary.items():
        if isinstance(value, dict):
            lines.append(f"{key}:")
            width = max(map(len, value), default=0)
            lines += [f"  {k:<{width}}  {v} {_shown_unit(unit_of(units, f'{key}.{k}'))}".rstrip()
                      for k, v in value.items()]
        else:
            lines.append(f"{key}: {value} {_shown_unit(unit_of(units, key))}".rstrip())
    print("\n".join(lines))


def _shown_unit(unit: str | None) -> str:
    """A unit as printed after a number: none for counts, dimensionless and non-quantities."""
    return "" if unit in (None, "1", "count", "—") else unit


def print_files(paths: Iterable[str | Path | None]) -> None:
    """``wrote: PATH`` for each file written (None entries: options not given)."""
    for p in paths:
        if p is not None:
            print(f"wrote: {p}")


OUTPUT_OPTIONS = ("save", "plot", "rrd", "report", "out")
"""Destinations (``args`` attributes) of the options that name an output, file or folder, in
every command; :data:`OUTPUT_POSITIONALS` adds a command's positional output."""
OUTPUT_POSITIONALS = {"examples": ("dir",)}
NOT_PATHS = ("command", "kind", "action", "handler")
"""``args`` attributes that are never file names (sub-command names, the handler)."""

_SESSIONS: list[contextlib.ExitStack] = []


def output_paths(args: argparse.Namespace) -> list[str]:
    """The outputs a parsed command line names (:data:`OUTPUT_OPTIONS`), in order."""
    names = OUTPUT_OPTIONS + OUTPUT_POSITIONALS.get(getattr(args, "command", None) or "", ())
    values = (getattr(args, n, None) for n in names)
    return [os.fspath(v) for v in values if isinstance(v, (str, os.PathLike)) and os.fspath(v)]


def input_paths(args: argparse.Namespace) -> list[str]:
    """Every other value of ``args`` (lists too) that names an existing file: the inputs."""
    outputs = set(OUTPUT_OPTIONS) | set(OUTPUT_POSITIONALS.get(getattr(args, "command", None)
                                                               or "", ()))
    found = []
    for key, value in vars(args).items():
        if key in outputs or key in NOT_PATHS:
            continue
        for v in value if isinstance(value, (list, tuple)) else (value,):
            if isinstance(v, (str, os.PathLike)) and os.fspath(v) and os.path.isfile(v):
                found.append(os.fspath(v))
    return found


def _make_parents(path: Path, stack: contextlib.ExitStack) -> None:
    """Create the missing folders above ``path`` (its lock lives there); each is removed
    again when ``stack`` closes if the command left it empty (a refused run writes nothing)."""
    missing = []
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        missing.append(parent)
        parent = parent.parent
    for d in reversed(missing):
        try:
            d.mkdir()
        except FileExistsError:
            continue
        except OSError as exc:
            raise type(exc)(exc.errno, exc.strerror, str(path)) from exc
        stack.callback(_remove_if_empty, d)


def _remove_if_empty(folder: Path) -> None:
    with contextlib.suppress(OSError):  # not empty (the command wrote there) or gone
        folder.rmdir()


def _claim(path: str | Path, stack: contextlib.ExitStack) -> None:
    from calib.files.atomic import clean_stale, holding, holds_lock, refuse_input

    if "\0" in os.fspath(path):  # the system would say "embedded null byte", naming nothing
        raise ValueError(f"{os.fspath(path)!r}: a file name cannot hold a NUL character; "
                         "give another output name")
    path = Path(path)
    refuse_input(path)
    if holds_lock(path):
        return
    _make_parents(path, stack)
    stack.enter_context(holding(path))
    clean_stale(path, locked=True)


@contextlib.contextmanager
def claim_outputs(paths: Iterable[str | Path | None]) -> Iterator[None]:
    """Hold the output lock of each of ``paths`` (None skipped) for the block, after
    refusing one that is a protected input; stale temporaries of each are removed.
    :func:`refuse_overwrite` called inside the block claims its paths here too."""
    with contextlib.ExitStack() as stack:
        _SESSIONS.append(stack)
        try:
            for p in paths:
                if p is not None:
                    _claim(p, stack)
            yield
        finally:
            _SESSIONS.remove(stack)


@contextlib.contextmanager
def command_outputs(args: argparse.Namespace) -> Iterator[None]:
    """Around a command (``main``): its input files protected
    (:func:`calib.files.atomic.inputs_protected`) and its outputs claimed (:func:`claim_outputs`)
    until it ends, before any work."""
    from calib.files.atomic import inputs_protected

    with inputs_protected(input_paths(args)), claim_outputs(output_paths(args)):
        yield


def refuse_overwrite(paths: Iterable[str | Path | None], force: bool = False) -> None:
    """Check output files before any work, so that a refused run writes nothing.

    None entries are skipped. A directory is never a valid output file (ValueError); an
    input of the command never is, even with ``--force``
    (:class:`calib.files.atomic.InputAsOutputError`); an existing file needs ``--force``
    (FileExistsError, worded by ``main``). Inside :func:`claim_outputs` (every command run by
    ``main``) each path is also locked until the command ends.
    """
    from calib.files.atomic import refuse_input

    for p in paths:
        if p is None:
            continue
        p = Path(p)
        if p.is_dir():
            raise ValueError(f"{p}: is a directory; expected an output file name")
        refuse_input(p)
        if p.exists() and not force:
            raise FileExistsError(f"{p}: exists")
        if _SESSIONS:
            _claim(p, _SESSIONS[-1])


def warnings_to_stderr(fn: Callable[[], T]) -> T:
    """Run ``fn``; print each warning it raised as ``warning: …`` on stderr (every time)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fn()
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    return result



#: widest line a command prints (a terminal of 100 columns; the README's promise).
COLUMNS = 100


def fit_line(line: str, width: int = COLUMNS) -> list[str]:
    """``line`` as lines of at most ``width`` columns, broken at spaces, each continuation
    indented 4 columns past the line's own indent (``error: …`` lines too: a reader joins a
    message back by its indented continuations).

    Never broken inside a word, so a path, a URL or an option stays whole and can be copied;
    the one line that may be wider than ``width`` holds a single word wider than it (a long
    path), alone.

    >>> [len(part) for part in fit_line("error: " + "word " * 30)]
    [96, 63]
    >>> fit_line("wrote: /" + "d" * 99) == ["wrote:", "    /" + "d" * 99]
    True
    """
    if len(line) <= width:
        return [line]
    import textwrap

    indent = line[:len(line) - len(line.lstrip(" "))]
    parts = textwrap.wrap(line, width, subsequent_indent=indent + "    ", expand_tabs=False,
                          replace_whitespace=False, break_long_words=False,
                          break_on_hyphens=False)
    return parts or [line]


class FitColumns(io.TextIOBase):
    """A text stream that writes every complete line through :func:`fit_line`.

    Installed on stdout and stderr around a command's work (:func:`fit_columns`), so every
    readable line fits 100 columns whatever library text it prints. Writes holding a
    carriage return (a progress bar redrawn in place, :mod:`bench.cli.progress`) pass
    through unchanged, after any pending text.
    """

    def __init__(self, stream: IO[str], width: int = COLUMNS) -> None:
        super().__init__()
        self.stream = stream
        self.width = width
        self._pending = ""

    def write(self, s: str) -> int:
        if "\r" in s:
            self._emit_pending()
            self.stream.write(s)
            return len(s)
        text = self._pending + s
        *lines, self._pending = text.split("\n")
        if lines:
            self.stream.write("".join(ln + "\n" for line in lines
                                      for ln in fit_line(line, self.width)))
        return len(s)

    def _emit_pending(self) -> None:
        if self._pending:
            self.stream.write("\n".join(fit_line(self._pending, self.width)))
            self._pending = ""

    def flush(self) -> None:
        self.stream.flush()

    def close_pending(self) -> None:
        """Write a last line that has no newline, and flush."""
        self._emit_pending()
        self.stream.flush()

    def isatty(self) -> bool:
        return bool(getattr(self.stream, "isatty", lambda: False)())

    def fileno(self) -> int:
        return self.stream.fileno()

    def writable(self) -> bool:
        return True


@contextlib.contextmanager
def fit_columns(stdout: bool = True, stderr: bool = True) -> Iterator[None]:
    """Within the block, stderr and stdout (each unless False) go through :class:`FitColumns`.

    ``main`` wraps stderr around all it does (argparse's errors, the error line of a refused
    input, warnings, notes, progress) and stdout around a command's work unless ``--json``
    (machine text, never re-wrapped)."""
    saved = sys.stdout, sys.stderr
    err = FitColumns(sys.stderr) if stderr else None
    out = FitColumns(sys.stdout) if stdout else None
    if err is not None:
        sys.stderr = err
    if out is not None:
        sys.stdout = out
    try:
        yield
    finally:
        sys.stdout, sys.stderr = saved
        for stream in (err, out):
            if stream is not None:
                stream.close_pending()
