"""The ``tiltbench`` command line: parse, call the library, print. The only place with argparse.

One module per command (:data:`COMMANDS`); each has ``register(subparsers)``, which adds its
parser and sets ``handler``: a function of the parsed args that returns the exit code.
Bad input (:class:`calib.files.course.DataError` and other ``ValueError``, ``OSError`` such as a
directory given for a file) is one error message on stderr and exit code 2; an existing output
without ``--force`` (``FileExistsError`` from the library) says "pass --force to overwrite".
Every stderr line fits 100 columns, error messages included: a longer one goes on in lines
indented 4 spaces, broken at spaces only (:func:`bench.cli.output.fit_line`).
Exit 1 is a graded FAIL (``validate``), exit 3 a result its own consistency check rejects
(``fuse``: windowed NIS out of its band, docs/fusion.md).

Start-up time: this package imports no domain module at import time (no numpy, scipy, mujoco,
matplotlib or rerun); each handler imports what it needs when it runs, and option defaults
that are domain constants are read late (:class:`bench.cli.options.Deferred`).
``benchmarks/cli_startup.py`` measures it.
"""

from __future__ import annotations

import os

# numpy and scipy each bundle an OpenBLAS; on small matrices their thread pools fight and a
# calibration runs ~10x slower (measured: 49 ms vs 5.5 ms at N = 20001). Our problems are small:
# one BLAS thread per process. Must run before numpy is imported; the user can override it.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import gc  # noqa: E402
import sys  # noqa: E402
import warnings  # noqa: E402

from bench import __version__  # noqa: E402
from bench.cli import (  # noqa: E402
    apply,
    calibrate,
    demo,
    design,
    examples,
    fuse,
    fusion_study,
    gap,
    generate,
    importlog,
    nmin,
    noise,
    record,
    trajectory,
    validate,
)
from bench.cli.options import Parser, refuse_numbers, resolve_deferred  # noqa: E402
from bench.cli.output import command_outputs, fit_columns, forget_logs_read  # noqa: E402

BY_NAME = {"generate": generate, "calibrate": calibrate, "apply": apply,
           "trajectory": trajectory, "nmin": nmin, "design": design, "fuse": fuse,
           "fusion-study": fusion_study, "record": record, "validate": validate, "gap": gap,
           "import": importlog, "noise": noise, "demo": demo, "examples": examples}
"""The module of each command name, in the order of the help (tests/test_cli_parser.py checks
it against the parsers)."""
COMMANDS = tuple(BY_NAME.values())
"""Command modules, in the order of the help."""


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The parser of every command, or of the command ``only`` alone (what ``main`` builds when
    the command line names one: the other fourteen parsers cost ≈ 15 ms of each run)."""
    parser = Parser(
        prog="tiltbench",
        description="Simulated-hardware accelerometer test bench (MuJoCo tilt table + LS).",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for command in (COMMANDS if only not in BY_NAME else (BY_NAME[only],)):
        command.register(sub)
    return parser


def _os_error_message(exc: OSError) -> str:
    """One line naming the path: a directory where a file is expected, permissions, an
    existing output (the library raises ``FileExistsError``; the remedy is a flag)."""
    if exc.filename is None or not exc.strerror:
        text = str(exc)
        if isinstance(exc, FileExistsError) and "--force" not in text:
            text += "; pass --force to overwrite"
        return text
    hint = {IsADirectoryError: "; expected a file",
            NotADirectoryError: "; a part of the path is a file, not a directory",
            FileExistsError: " and is not a directory"}.get(type(exc), "")
    return f"{exc.filename}: {exc.strerror}{hint}"


def _warning_to_stderr(message, category, filename, lineno, file=None, line=None):
    print(f"warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    words = sys.argv[1:] if argv is None else argv
    parser = build_parser(only=words[0] if words else None)
    try:
        # every stderr line fits 100 columns: argparse's errors, the error line of a refused
        # input, warnings, notes and progress (bench.cli.output.fit_columns)
        with fit_columns(stdout=False):
            return _run(parser, argv)
    except BrokenPipeError:  # output piped into `head`: not an error
        sys.stderr.close()
        return 0


GC_YOUNG = 10_000
"""New container objects between two collections of the youngest generation (CPython: 700)."""


def console() -> int:
    """The ``tiltbench`` program (its console script and ``python -m bench.cli``):
    :func:`main`, then an exit that does not trace every object the imports left alive.

    At exit CPython clears every module and collects the reference cycles among what they
    held: after ``tiltbench gap`` that is ≈ 1300 modules (scipy, MuJoCo, mujoco.sysid, …) and
    ≈ 130 000 objects, 0.2–0.35 s of the command's wall time, spent after its last line is
    printed. So the command's own garbage is collected here (``gc.collect``: its finalizers
    run as they always did) and what is still alive is then frozen (``gc.freeze``), which
    leaves it out of the exit's collections: the exit takes ≈ 0.03 s. atexit handlers (a
    recording's flush) and the flush of stdout and stderr run as before; the commands close
    their own files (atomic writes). Library callers of :func:`main` (tests, scripts) keep
    their process's collector untouched.

    No command draws with MuJoCo's OpenGL, so its GL loader (glfw: ≈ 0.05 s of the import of
    ``mujoco``) is switched off unless the environment chose one (``MUJOCO_GL``).

    The collector's youngest generation is collected every :data:`GC_YOUNG` new objects
    instead of 700: a command's imports create ≈ 10⁵ objects, none of them garbage, and the
    collections they triggered cost ≈ 0.08 s of the ≈ 1 s import of ``tiltbench gap``
    (median of 8 alternating fresh processes). The process's memory is kept where it was
    freed (:func:`keep_freed_memory`)."""
    os.environ.setdefault("MUJOCO_GL", "disable")
    gc.set_threshold(GC_YOUNG, *gc.get_threshold()[1:])
    keep_freed_memory()
    code = main()
    gc.collect()
    gc.freeze()
    return code


MMAP_THRESHOLD = 32 << 20
"""Bytes: glibc's largest fixed ``M_MMAP_THRESHOLD`` (``DEFAULT_MMAP_THRESHOLD_MAX`` on 64-bit
systems); a block at least this big is still mapped and unmapped on its own."""
TRIM_THRESHOLD = 1 << 30
"""Bytes of free memory at the top of the heap before glibc hands it back (``M_TRIM_THRESHOLD``)."""


def keep_freed_memory() -> bool:
    """Freed arrays stay in the process for the next ones, instead of going back to the kernel.

    The commands allocate and free thousands of N-long temporaries (at N = 60001 one column is
    0.48 MB; a design of ten, 4.8 MB). glibc maps a block that large on its own and unmaps it
    when freed, so the next array faults every page in again; and numpy asks for transparent
    huge pages on arrays of 4 MB or more (``madvise``), which on a kernel whose THP defrag is
    ``madvise`` compacts memory in the page fault. Measured on ``tiltbench gap`` at N = 60001
    (2 cores, old and new code alternating, 6 runs each): median 4.29 → 3.04 s wall, 1.27 →
    0.36 s of system time (``docs/development.md``). So: a fixed mmap threshold
    (:data:`MMAP_THRESHOLD`), the top of the heap kept up to :data:`TRIM_THRESHOLD`
    (``mallopt``, glibc only: elsewhere nothing changes), and
    ``NUMPY_MADVISE_HUGEPAGE=0`` unless the environment sets it (read when numpy is imported,
    which no command has done yet). The peak memory is the same; it is returned at exit.
    The program alone does this (:func:`console`): library callers keep their process's.
    Returns whether the allocator took both settings (False where there is no ``mallopt``)."""
    os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # not glibc (macOS, musl): its allocator's defaults
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    # M_MMAP_THRESHOLD and M_TRIM_THRESHOLD of malloc.h; mallopt returns 1 on success
    return bool(mallopt(-3, MMAP_THRESHOLD)) and bool(mallopt(-1, TRIM_THRESHOLD))


def _run(parser: argparse.ArgumentParser, argv: list[str] | None) -> int:
    """Parse, run the command, turn bad input into one error message and exit code 2."""
    args = parser.parse_args(argv)
    if args.command is None:  # `tiltbench` alone: the help, not an error
        parser.print_help()
        return 0
    resolve_deferred(args)
    forget_logs_read()  # the provenance in --json is this command's logs' only
    warnings.showwarning = _warning_to_stderr
    try:
        # readable stdout fits 100 columns too (--json is machine text, left whole)
        with fit_columns(stdout=not getattr(args, "json", False), stderr=False):
            refuse_numbers(args)  # NaN / Inf / absurd numbers, before any work
            with command_outputs(args):  # outputs locked, inputs protected, until the end
                return int(args.handler(args) or 0)
    except BrokenPipeError:  # an OSError, but not bad input: main's
        raise
    except OSError as exc:  # FileExistsError, FileNotFoundError, IsADirectoryError, …
        print(f"tiltbench {args.command}: error: {_os_error_message(exc)}", file=sys.stderr)
        return 2
    except ModuleNotFoundError as exc:  # an optional extra that is not installed
        if not (exc.name or "").startswith("rerun"):
            raise
        print(f"tiltbench {args.command}: error: recordings need rerun-sdk, an optional "
              "extra: pip install \"tiltbench[rrd]\"", file=sys.stderr)
        return 2
    except ValueError as exc:  # calib.files.course.DataError, bench.cli.options.OptionError, …
        print(f"tiltbench {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except (MemoryError, OverflowError, ZeroDivisionError, FloatingPointError,
            RecursionError) as exc:
        # Last resort: options and sizes are checked before work starts (bench.cli.options,
        # bench.limits), so reaching this is a bug; still one line, never a traceback.
        name = " ".join(filter(None, (args.command, getattr(args, "kind", None))))
        detail = f": {exc}" if str(exc) else ""
        print(f"tiltbench {args.command}: error: {type(exc).__name__}{detail} — the inputs of "
              f"'tiltbench {name}' are outside what it can compute; please report this "
              "command line", file=sys.stderr)
        return 2
