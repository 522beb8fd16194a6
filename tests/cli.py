"""Running ``tiltbench`` in this process from a test: its exit code and output, and the check
every bad-input test makes (exit 2, nothing on stdout, one error message on stderr, which
:func:`unwrap` puts back on one line)."""

from __future__ import annotations

from bench.cli import main


def run(capsys, *argv) -> tuple[int, str, str]:
    """``tiltbench ARGV`` (items turned to str): exit code, stdout, stderr."""
    rc = main([str(a) for a in argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def unwrap(text: str) -> str:
    """``text`` with each message wrapped at 100 columns back on one line: a line indented 4
    spaces continues the line before it (``bench.cli.output.fit_line`` broke it at a space)."""
    lines: list[str] = []
    for ln in text.strip().splitlines():
        if ln.startswith("    ") and lines:
            lines[-1] += " " + ln.strip()
        else:
            lines.append(ln)
    return "\n".join(lines)


def one_line_error(capsys, *argv, prefix: str = "tiltbench ",
                   ignore: tuple[str, ...] = ()) -> str:
    """Run a command that must fail on bad input: exit 2, nothing on stdout, no traceback,
    one message on stderr (messages starting with ``ignore`` and the provenance note aside) that
    starts with ``prefix``
    and says ``error:``; return that message as one line (:func:`unwrap`)."""
    rc, out, err = run(capsys, *argv)
    assert rc == 2, err
    assert out == ""
    assert "Traceback" not in err
    # the provenance note (how the log was read, printed before any later refusal) is not a
    # second message
    skip = (*ignore, "note: read ")
    lines = [ln for ln in unwrap(err).splitlines() if not ln.startswith(skip)]
    assert len(lines) == 1, err
    assert lines[0].startswith(prefix) and "error:" in lines[0]
    return lines[0]
