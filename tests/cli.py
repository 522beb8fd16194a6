"""Running ``tiltbench`` in this process from a test: its exit code and output, and the check
every bad-input test makes (exit 2, nothing on stdout, one error line on stderr)."""

from __future__ import annotations

from bench.cli import main


def run(capsys, *argv) -> tuple[int, str, str]:
    """``tiltbench ARGV`` (items turned to str): exit code, stdout, stderr."""
    rc = main([str(a) for a in argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def one_line_error(capsys, *argv, prefix: str = "tiltbench ",
                   ignore: tuple[str, ...] = ()) -> str:
    """Run a command that must fail on bad input: exit 2, nothing on stdout, no traceback,
    one line on stderr (lines starting with ``ignore`` aside) that starts with ``prefix`` and
    says ``error:``; return that line."""
    rc, out, err = run(capsys, *argv)
    assert rc == 2, err
    assert out == ""
    assert "Traceback" not in err
    lines, skipping = [], False
    for ln in err.strip().splitlines():
        # an ignored line and its continuation lines (wrapped at 100 columns, indented)
        skipping = ln.startswith(ignore or ("\0",)) or (skipping and ln.startswith("    "))
        if not skipping:
            lines.append(ln)
    assert len(lines) == 1, err
    assert lines[0].startswith(prefix) and "error:" in lines[0]
    return lines[0]
