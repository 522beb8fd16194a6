"""The ``tiltbench`` command line: parse, call the library, print.

Each feature registers its sub-commands from its own ``bench/cli_*.py`` module through a
``register(subparsers)`` function; a handler receives the parsed args and returns an exit code.
Errors from bad input (:class:`calib.io.DataError`, ``ValueError``, ``OSError`` such as
``FileExistsError`` or a directory given for a file) are printed to stderr as one line and give
exit code 2.
"""

from __future__ import annotations

import os

# numpy and scipy each bundle an OpenBLAS; on small matrices their thread pools fight and a
# calibration runs ~10x slower (measured: 49 ms vs 5.5 ms at N = 20001). Our problems are small:
# one BLAS thread per process. Must run before numpy is imported; the user can override it.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import importlib
import re
import sys
import warnings

from calib.io import DataError  # noqa: E402

COMMAND_MODULES = (
    "bench.cli_generate",
    "bench.cli_calibrate",
    "bench.cli_trajectory",
    "bench.cli_record",
    "bench.cli_validate",
    "bench.cli_gap",
    "bench.cli_demo",
)


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Shows an option's default when it has one worth showing (not None, not a flag's False)
    and its help text does not already state it."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if any(action.default is v for v in (None, False, argparse.SUPPRESS)) or "default" in text:
            return text
        return super()._get_help_string(action)


class RawDescriptionHelpFormatter(argparse.RawDescriptionHelpFormatter, HelpFormatter):
    """:class:`HelpFormatter` that keeps the description's and epilog's line breaks."""


class _Parser(argparse.ArgumentParser):
    """argparse that takes negative number pairs as option values: ``--bias -0.02,0.08``.

    Plain argparse (< 3.13) only treats ``-5`` or ``-0.5`` as a value, so ``--p0 -5,3`` was an
    "expected one argument" error. Sub-parsers inherit the class (and the help formatter).
    """

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-\.?\d[\d.eE+\-,\s]*$")


def _os_error_message(exc: OSError) -> str:
    """One line naming the path: a directory where a file is expected, permissions, …"""
    if exc.filename is None or not exc.strerror:
        return str(exc)
    hint = {IsADirectoryError: "; expected a file",
            NotADirectoryError: "; a part of the path is a file, not a directory",
            FileExistsError: " and is not a directory"}.get(type(exc), "")
    return f"{exc.filename}: {exc.strerror}{hint}"


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="tiltbench",
        description="Simulated-hardware accelerometer test bench (MuJoCo tilt table + LS).",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:  # feature not built yet
                continue
            raise
        module.register(sub)
    return parser


def _warning_to_stderr(message, category, filename, lineno, file=None, line=None):
    print(f"warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    warnings.showwarning = _warning_to_stderr
    try:
        return int(args.handler(args) or 0)
    except BrokenPipeError:  # output piped into `head`: not an error
        sys.stderr.close()
        return 0
    except OSError as exc:  # FileExistsError, FileNotFoundError, IsADirectoryError, …
        print(f"tiltbench {args.command}: error: {_os_error_message(exc)}", file=sys.stderr)
        return 2
    except (DataError, ValueError) as exc:
        print(f"tiltbench {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
