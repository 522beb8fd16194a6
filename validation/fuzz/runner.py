"""Run one fuzz case as subprocesses and classify what happened (table in the package doc)."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

TIMEOUT = 60.0
"""Seconds after which a run is a hang (the issue's bound)."""

LAST_RESORT = ("please report", "would be nan", "singular matrix", "overflowerror")
"""Messages that mean a check is missing (case-insensitive)."""

FAULTS = ("traceback", "last_resort", "multi_line", "wide_line", "hang", "leftover",
          "result_lost", "bad_exit", "silent_wrong", "vague", "refused_valid")

WIDTH = 100
"""Widest line a command may print, in columns (the README's promise; issue 29)."""

Check = Callable[[int, str, str, Path], "str | None"]
"""Truth check of a finished run: (exit code, stdout, stderr, case dir) → why it is wrong."""


@dataclass
class Case:
    """One fuzz case.

    ``argv``: the ``tiltbench`` arguments (paths relative to the case folder); ``files``:
    inputs copied into the case folder before the run ({name in case: source path});
    ``expect``: ``"refuse"`` (exit 2 expected: exit 0 is silent_wrong), ``"any"`` (exit 0 or
    2), ``"truth"`` (exit 0 must pass ``check``), ``"valid"`` (a valid input: exit 0 expected
    and ``check`` passed; a refusal is ``refused_valid``); ``says``: a pattern (regular
    expression, case ignored) that the error message of a refusal (exit 2) must hold — the
    likely unit, the file and field, the line number —, else ``vague``; ``parallel``: more
    argvs started at the
    same moment (concurrent writers); ``kill_after``: seconds after which the first run is
    killed (SIGKILL), then run again to see that start-up removes its temporaries;
    ``inputs_unchanged``: files that the run must not modify.
    """

    kind: str
    name: str
    argv: list[str]
    files: dict[str, Path] = field(default_factory=dict)
    expect: str = "any"
    check: Check | None = None
    parallel: list[list[str]] = field(default_factory=list)
    kill_after: float | None = None
    inputs_unchanged: tuple[str, ...] = ()
    ok_codes: tuple[int, ...] = (0, 2)
    says: str | None = None

    def __post_init__(self) -> None:
        verdict = VERDICT_EXIT.get(self.argv[0] if self.argv else "")
        if verdict is not None and verdict not in self.ok_codes:  # a verdict is never a fault
            self.ok_codes = (*self.ok_codes, verdict)


VERDICT_EXIT = {"validate": 1, "fuse": 3}
"""Documented exits that are verdicts, not errors: ``validate``'s FAIL and ``fuse``'s
INCONSISTENT (its windowed NIS out of band: the result printed, no region)."""


@dataclass
class Outcome:
    kind: str
    name: str
    argv: list[str]
    codes: list[int | None]
    seconds: float
    faults: list[str]
    detail: str
    stderr_tail: str
    widest: int = 0
    """Widest line of the run's stderr and readable (non-JSON) stdout, columns: a line that
    could be broken (more than one word), the ones :data:`WIDTH` limits."""
    widest_word: int = 0
    """Widest line that is a single word (a long path: allowed wider than :data:`WIDTH`)."""

    def to_dict(self) -> dict:
        return self.__dict__.copy()


def _hidden(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob(".*")
            if not p.name.endswith(".lock")}


def _spawn(argv: list[str], cwd: Path, env: dict) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "bench.cli", *argv], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)


def _wait(proc: subprocess.Popen, timeout: float) -> tuple[int | None, str, str]:
    """(exit code or None for a hang, stdout, stderr); a hang is killed with its group."""
    try:
        out, err = proc.communicate(timeout=timeout)
        return proc.returncode, out, err
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        return None, out, err


def error_lines(err: str) -> list[str]:
    """The messages on stderr that are not notes, warnings or progress, each as one line: a
    message wrapped at :data:`WIDTH` columns goes on in lines indented 4 spaces, joined back
    here (with one space, as the wrap took it)."""
    lines: list[str] = []
    skipping = False
    for ln in err.strip().splitlines():
        if ln.startswith("    ") and (skipping or lines):  # a continuation line
            if not skipping:
                lines[-1] += " " + ln.strip()
            continue
        skipping = ln.startswith(("note:", "warning:", "["))
        if not skipping and ln.strip():
            lines.append(ln)
    return lines


def columns(line: str) -> int:
    """Terminal columns of ``line``: one per character (what we print is Latin, Greek and
    math signs, one column each; no tabs)."""
    return len(line)


def wide_lines(text: str, width: int = WIDTH) -> list[str]:
    """The lines of ``text`` wider than ``width`` columns, except a line that holds a single
    token (after its indent): a path or URL longer than the width, which must stay whole.
    Progress redrawn in place (``\\r``) counts each redraw as a line."""
    return [ln for ln in text.splitlines() if columns(ln) > width and len(ln.split()) > 1]


def max_columns(text: str, words: str = "many") -> int:
    """Columns of the widest line of ``text`` that holds more than one word (``words="many"``)
    or a single word (``"one"``); 0 if there is none."""
    return max((columns(ln) for ln in text.splitlines()
                if (len(ln.split()) > 1) == (words == "many")), default=0)


def stage(case: Case, root: Path) -> None:
    """Make ``root`` the case's fresh folder: emptied, its input files copied in."""
    if root.exists():
        shutil.rmtree(root)
    root.mkdir(parents=True)
    for name, src in case.files.items():
        dst = root / name
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, dst)


def before(case: Case, root: Path) -> tuple[set[str], dict[str, bytes]]:
    """What :func:`classify` compares after the runs: the hidden files of the staged folder
    ``root`` and the bytes of ``case.inputs_unchanged``."""
    return _hidden(root), {n: (root / n).read_bytes() for n in case.inputs_unchanged}


def run_case(case: Case, root: Path, env: dict) -> Outcome:
    """Run ``case`` in ``root`` (created, inputs copied) and classify it."""
    stage(case, root)
    before_hidden, before_bytes = before(case, root)
    details: list[str] = []
    t0 = time.monotonic()
    if case.kill_after is not None:
        proc = _spawn(case.argv, root, env)
        time.sleep(case.kill_after)
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        details.append(f"killed at {case.kill_after} s")
        # start-up of the next run must clean what the killed one left
    procs = [_spawn(a, root, env) for a in [case.argv, *case.parallel]]
    results = []
    for p in procs:
        left = max(1.0, TIMEOUT - (time.monotonic() - t0))
        results.append(_wait(p, left if case.kill_after is None else TIMEOUT))
    seconds = time.monotonic() - t0
    return classify(case, root, results, seconds, before_hidden, before_bytes, details)


def classify(case: Case, root: Path, results: list[tuple[int | None, str, str]],
             seconds: float, before_hidden: set[str], before_bytes: dict[str, bytes],
             details: list[str] | None = None) -> Outcome:
    """The :class:`Outcome` of ``case`` from its runs' ``(exit code or None for a hang,
    stdout, stderr)`` (the first: ``case.argv``; then ``case.parallel``), the hidden files
    and the ``inputs_unchanged`` bytes of ``root`` before the runs (the table in the package
    doc). Shared by :func:`run_case` (subprocesses) and any other way of running a case."""
    faults: list[str] = []
    details = list(details or [])
    codes = [r[0] for r in results]
    out, err = results[0][1], "\n".join(r[2] for r in results)
    if "Traceback" in err:
        faults.append("traceback")
    low = err.lower()
    if any(m in low for m in LAST_RESORT):
        faults.append("last_resort")
    if any(c is None for c in codes):
        faults.append("hang")
    for code, _, e in results:
        # an error exit (2, or any undocumented code; validate's 1 and fuse's 3 are verdicts)
        verdict = VERDICT_EXIT.get(case.argv[0] if case.argv else "")
        if code not in (None, 0, verdict) and len(error_lines(e)) != 1:
            faults.append("multi_line")
            break
    readable = [e for _, _, e in results] + ([out] if _json(out) is None else [])
    wide = [ln for text in readable for ln in wide_lines(text)]
    if wide:
        faults.append("wide_line")
        details.append(f"{len(wide)} line(s) over {WIDTH} columns, e.g. {wide[0][:120]!r}")
    if any(c is not None and c not in case.ok_codes for c in codes):
        faults.append("bad_exit")
    new_hidden = sorted(_hidden(root) - before_hidden)
    if new_hidden:
        faults.append("leftover")
        details.append("hidden: " + ", ".join(new_hidden[:4]))
    if case.parallel and sum(c == 0 for c in codes) > 1:
        faults.append("result_lost")
        details.append(f"{sum(c == 0 for c in codes)} writers of one path exit 0")
    for n, data in before_bytes.items():
        if not (root / n).exists() or (root / n).read_bytes() != data:
            faults.append("result_lost")
            details.append(f"input {n} overwritten")
            break
    if codes[0] == 0 and case.expect == "refuse":
        faults.append("silent_wrong")
        details.append("accepted an input that must be refused")
    if codes[0] == 2 and case.expect == "valid":
        faults.append("refused_valid")
        details.append("refused a valid input")
    if codes[0] == 2 and case.says is not None:
        said = " ".join(error_lines(results[0][2]))
        if not re.search(case.says, said, re.IGNORECASE):
            faults.append("vague")
            details.append(f"the refusal does not say /{case.says}/")
    if codes[0] == 0 and case.check is not None:
        try:
            why = case.check(0, out, err, root)
        except Exception as exc:  # an answer the check cannot read is no answer
            why = f"the truth check cannot read the answer: {exc!r}"
        if why:
            faults.append("silent_wrong")
            details.append(why)
    tail = " | ".join(error_lines(err)[-2:])[:300]
    return Outcome(case.kind, case.name, case.argv, codes, round(seconds, 2),
                   sorted(set(faults), key=FAULTS.index), "; ".join(details), tail,
                   widest=max(max_columns(t) for t in readable),
                   widest_word=max(max_columns(t, "one") for t in readable))


# ---------------------------------------------------------------- truth checks
def _json(out: str) -> dict | None:
    try:
        obj = json.loads(out)
    except ValueError:
        return None
    return obj if isinstance(obj, dict) else None


def flagged(obj: object, rx: re.Pattern) -> bool:
    """Does a JSON answer raise the flag: a key matching ``rx`` with a true / non-empty value,
    or a string value matching it (``"status": "inconsistent"``)?"""
    if isinstance(obj, dict):
        return any((rx.search(str(k)) and bool(v) and v != "false") or flagged(v, rx)
                   for k, v in obj.items())
    if isinstance(obj, list):
        return any(flagged(v, rx) for v in obj[:50])
    return isinstance(obj, str) and bool(rx.search(obj))


def end_check(truth: Path, where: str, flag: str = "inconsisten", sigmas: float = 5.0
              ) -> Check:
    """The reported end position within ``sigmas``·σ (Mahalanobis, 2-D) of the true end,
    unless the answer is flagged (``flag`` in stderr or :func:`flagged` in the JSON);
    ``where``: ``fuse`` (``fusion.final_position[_cov]``) or ``trajectory``
    (``final_corrected``, ``cov``)."""
    import numpy as np

    true_end = np.asarray(json.loads(truth.read_text())["true_final_position"], float)
    rx = re.compile(flag, re.IGNORECASE)

    def check(code: int, out: str, err: str, root: Path) -> str | None:
        obj = _json(out)
        if obj is None:
            return "exit 0 without a JSON object on stdout"
        if rx.search(err) or flagged(obj, rx):
            return None
        try:
            if where == "fuse":
                end = np.asarray(obj["fusion"]["final_position"], float)
                cov = np.asarray(obj["fusion"]["final_position_cov"], float)
            else:
                end = np.asarray(obj["final_corrected"], float)
                cov = np.asarray(obj["cov"], float)
            e = end - true_end
            d = float(np.sqrt(e @ np.linalg.lstsq(cov, e, rcond=None)[0]))
        except (KeyError, TypeError, ValueError, np.linalg.LinAlgError) as exc:
            return f"answer unreadable: {exc}"
        if not np.isfinite(d) or d > sigmas:
            return (f"end {np.linalg.norm(e):.3g} m from the truth = {d:.3g} σ "
                    f"(σ ≈ {np.sqrt(np.trace(cov) / 2):.3g} m), not flagged")
        return None

    return check


def mention_check(pattern: str, what: str) -> Check:
    """Exit 0 must say ``pattern`` (e.g. that turning is not modelled)."""
    rx = re.compile(pattern, re.IGNORECASE)

    def check(code: int, out: str, err: str, root: Path) -> str | None:
        return None if rx.search(out + err) else f"exit 0 and silent about {what}"

    return check


def tiltbench(argv: list[str], cwd: Path, env: dict) -> None:
    """Run a fixture-building command; a failure here is the harness's, so it raises."""
    proc = subprocess.run([sys.executable, "-m", "bench.cli", *argv], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=600)
    if proc.returncode != 0:
        raise RuntimeError(f"fixture `tiltbench {' '.join(argv)}` failed:\n{proc.stderr}")
