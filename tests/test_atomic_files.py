"""Single-file outputs written like sets (issue 23, part 3): a lock per output path held by the
command from start-up, atomic replace, never an input as the output, temporaries private and
cleaned by the next run.

Concurrent runs and kills use real ``tiltbench`` processes started through a small runner
(:data:`RUNNER`) that patches ``os.replace`` / ``os.rename`` for one target name only: ``wait``
holds the final rename until the test says go (so "both runs reached the rename" is
observable, not a matter of timing), ``kill`` sends SIGKILL to its own process at the moment
before the rename. Read-only and full disks are injected in process (``os.open`` → EROFS,
``os.fsync`` → ENOSPC) under one folder, so they work whoever runs the tests.
"""

from __future__ import annotations

import errno
import os
import shutil
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bench.cli import main
from calib.files import atomic
from tests.cli import one_line_error, run, unwrap

NV = ("--noise-var", "0.25,0.64")

RUNNER = r"""
import os, signal, sys, time
from pathlib import Path

hook, name = os.environ["HOOK"], os.environ["HOOK_TARGET"]


def hooked(real):
    def call(src, dst, *args, **kwargs):
        if os.path.basename(os.fspath(dst)) == name:
            if hook == "kill":
                os.kill(os.getpid(), signal.SIGKILL)
            go, end = Path(os.environ["HOOK_GO"]), time.monotonic() + 60
            while not go.exists() and time.monotonic() < end:
                time.sleep(0.01)
        return real(src, dst, *args, **kwargs)
    return call


os.replace, os.rename = hooked(os.replace), hooked(os.rename)
from bench.cli import main
sys.exit(main(sys.argv[1:]))
"""

HOLDER = ("import sys\nfrom calib.files.atomic import output_lock\n"
          "with output_lock(sys.argv[1]):\n"
          "    print('locked', flush=True)\n"
          "    sys.stdin.read()\n")


def _env() -> dict[str, str]:
    return dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]),
                OPENBLAS_NUM_THREADS="1")


def _hooked(hook: str, target_name: str, *argv, go: Path | None = None) -> subprocess.Popen:
    env = dict(_env(), HOOK=hook, HOOK_TARGET=target_name, HOOK_GO=str(go or "/nonexistent"))
    return subprocess.Popen([sys.executable, "-c", RUNNER, *map(str, argv)], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def _leftovers(root: Path) -> list[str]:
    """Our temporary and lock names anywhere under ``root``."""
    return sorted(str(p.relative_to(root)) for p in root.rglob(".*")
                  if p.name.endswith((".tmp", ".lock")))


@pytest.fixture
def files(tmp_path, course_dir) -> Path:
    """Private copies of the course files (an input never touches the shared data)."""
    d = tmp_path / "in"
    d.mkdir()
    for f in ("ensayo.mat", "acel.mat", "puntos.mat", "datos.txt"):
        shutil.copyfile(course_dir / f, d / f)
    return d


# ---------------------------------------------------------------- two writers at once
def test_two_writers_of_one_file_one_wins_the_other_is_refused(tmp_path, files, capsys):
    """Both runs start together and would each replace ``cal.json`` (``--force``). Each
    holds its final rename until the test says go, so if both got past their lock the test
    sees two temporaries (the bug); with the lock one run is refused at start-up."""
    nvs = ("0.25,0.64", "0.36,0.81")
    refs = {}
    for nv in nvs:  # what each run alone writes
        ref = tmp_path / f"ref-{nv}.json"
        assert run(capsys, "calibrate", files / "ensayo.mat", "--noise-var", nv, "--save",
                   ref)[0] == 0
        refs[nv] = ref.read_bytes()
    assert refs[nvs[0]] != refs[nvs[1]]
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    out, go = out_dir / "cal.json", tmp_path / "go"
    procs = {nv: _hooked("wait", "cal.json", "calibrate", files / "ensayo.mat", "--noise-var",
                         nv, "--save", out, "--force", go=go) for nv in nvs}
    end = time.monotonic() + 90
    while time.monotonic() < end:  # one refused, or both at the rename (no lock)
        ended = sum(p.poll() is not None for p in procs.values())
        if ended + len(list(out_dir.glob(".cal.json.*.tmp"))) >= 2:
            break
        time.sleep(0.01)
    go.touch()
    rcs = {nv: p.wait(timeout=90) for nv, p in procs.items()}
    errs = {nv: p.stderr.read().decode() for nv, p in procs.items()}
    for p in procs.values():
        p.stderr.close()
    assert sorted(rcs.values()) == [0, 2], errs
    win = next(nv for nv in nvs if rcs[nv] == 0)
    lose = next(nv for nv in nvs if rcs[nv] == 2)
    line, = unwrap(errs[lose]).splitlines()
    assert line.startswith("tiltbench calibrate: error: ")
    assert f"another tiltbench run is writing {out} (pid {procs[win].pid})" in line
    assert "nothing was written by this run" in line and "run it again" in line
    assert out.read_bytes() == refs[win]  # one complete result, the winner's
    assert _leftovers(tmp_path) == []


@pytest.fixture
def holder(tmp_path):
    """Start a process holding the output lock of a path; yields a function path → pid."""
    procs = []

    def hold(path: Path) -> int:
        p = subprocess.Popen([sys.executable, "-c", HOLDER, str(path)], env=_env(),
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        procs.append(p)
        assert p.stdout.readline().strip() == "locked"
        return p.pid

    yield hold
    for p in procs:
        p.stdin.close()
        assert p.wait(timeout=30) == 0
        p.stdout.close()


BUSY = {  # command line → the output another run holds
    "calibrate --save": (["calibrate", "{in}/ensayo.mat", *NV, "--save", "{out}/cal.json"],
                         "cal.json"),
    "calibrate --save .mat": (["calibrate", "{in}/ensayo.mat", *NV, "--save", "{out}/c.mat"],
                              "c.mat"),
    "calibrate --plot": (["calibrate", "{in}/ensayo.mat", *NV, "--plot", "{out}/fit.png"],
                         "fit.png"),
    "calibrate --rrd": (["calibrate", "{in}/ensayo.mat", *NV, "--rrd", "{out}/fit.rrd"],
                        "fit.rrd"),
    "trajectory --plot": (["trajectory", "--ensayo", "{in}/ensayo.mat", "--acel",
                           "{in}/acel.mat", "--puntos", "{in}/puntos.mat", "--plot",
                           "{out}/t.svg"], "t.svg"),
    "noise --save": (["noise", "{in}/ensayo.mat", "--save", "{out}/sensor.json"],
                     "sensor.json"),
    "gap --rrd": (["gap", "{in}/ensayo.mat", *NV, "--rrd", "{out}/gap.rrd"], "gap.rrd"),
    "generate --rrd": (["generate", "calibration", "--out", "{out}/set", "--rrd",
                        "{out}/truth.rrd"], "truth.rrd"),
}


@pytest.mark.parametrize("case", BUSY, ids=str)
def test_an_output_held_by_another_run_is_refused_before_any_work(case, tmp_path, files,
                                                                  holder, capsys):
    """The lock is taken at start-up: the refused run computes nothing and loses nothing;
    the held file keeps its content."""
    argv, name = BUSY[case]
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    target = out_dir / name
    target.write_bytes(b"the other run's result")
    pid = holder(target)
    argv = [a.format(**{"in": files, "out": out_dir}) for a in argv]
    t0 = time.monotonic()
    line = one_line_error(capsys, *argv, "--force")
    assert time.monotonic() - t0 < 5  # refused at start-up, not after the work
    assert f"another tiltbench run is writing {target} (pid {pid})" in line
    assert target.read_bytes() == b"the other run's result"
    assert not (out_dir / "set").exists()
    assert sorted(p.name for p in out_dir.iterdir()) == sorted([name, f".{name}.lock"])


# ---------------------------------------------------------------- kill before the rename
@pytest.mark.parametrize("option, name", [("--save", "cal.json"), ("--save", "cal.mat")])
def test_kill_before_the_rename_leaves_the_old_file_and_the_next_run_cleans(
        option, name, tmp_path, files, capsys):
    out = tmp_path / "out" / name
    out.parent.mkdir()
    out.write_bytes(b"the previous result")
    proc = _hooked("kill", name, "calibrate", files / "ensayo.mat", *NV, option, out,
                   "--force")
    assert proc.wait(timeout=90) == -signal.SIGKILL, proc.stderr.read().decode()
    proc.stderr.close()
    assert out.read_bytes() == b"the previous result"  # never a partial target
    left = _leftovers(out.parent)
    assert any(n.startswith(f".{name}.{proc.pid}-") and n.endswith(".tmp") for n in left)
    rc, _, err = run(capsys, "calibrate", files / "ensayo.mat", *NV, option, out, "--force")
    assert rc == 0, err
    assert _leftovers(tmp_path) == []  # the killed run's temporary and lock are gone
    from calib.calibration.calfile import load_calibration

    assert load_calibration(out).fits["x"].params.shape == (2,)  # one whole result


@pytest.mark.slow  # ~11 s here: a class set is written twice, once by a subprocess
def test_killed_class_leaves_no_readable_key_and_the_next_run_removes_it(tmp_path, capsys):
    """SIGKILL at the set's final rename: the class (answer key included) is left in a
    temporary folder beside OUT, never in a student folder, that only its owner can open
    (0700, key files 0600); the next run removes it at start-up."""
    work = tmp_path / "w"
    work.mkdir()
    target = work / "class"
    proc = _hooked("kill", "class", "generate", "class", "--students", "2", "--seed", "1",
                   "--out", target)
    assert proc.wait(timeout=90) == -signal.SIGKILL, proc.stderr.read().decode()
    proc.stderr.close()
    assert not target.exists()
    tmp, = [p for p in work.iterdir() if p.name.endswith(".tmp")]
    assert tmp.name.startswith(f".class.{proc.pid}-") and tmp.is_dir()
    assert stat.S_IMODE(tmp.stat().st_mode) == 0o700
    keys = sorted(tmp.glob("answer_key.*"))
    assert [k.name for k in keys] == ["answer_key.csv", "answer_key.json"]
    assert all(stat.S_IMODE(k.stat().st_mode) == 0o600 for k in keys)
    assert not list(work.rglob("student_*/answer_key*"))
    assert not list(work.rglob("student_*/truth.json"))
    assert run(capsys, "generate", "class", "--students", "2", "--seed", "1", "--out",
               target)[0] == 0
    assert _leftovers(work) == []
    assert sorted(p.name for p in work.iterdir()) == ["class"]
    for k in ("answer_key.csv", "answer_key.json"):  # the published key stays private
        assert stat.S_IMODE((target / k).stat().st_mode) == 0o600
    umask = os.umask(0)
    os.umask(umask)
    for d in [target, *target.glob("student_*")]:  # what students get: the usual mode
        assert stat.S_IMODE(d.stat().st_mode) == 0o777 & ~umask


# ---------------------------------------------------------------- input as output
SAME = {  # command line, with "{x}" the input that is also given as the output
    "calibrate --save": ["calibrate", "{x}", *NV, "--save", "{x}"],
    "calibrate --plot": ["calibrate", "{x}", *NV, "--plot", "{x}"],
    "calibrate --rrd": ["calibrate", "{x}", *NV, "--rrd", "{x}"],
    "calibrate --datos": ["calibrate", "{in}/ensayo.mat", "--datos", "{x}", "--save", "{x}"],
    "trajectory --plot": ["trajectory", "--ensayo", "{in}/ensayo.mat", "--acel", "{x}",
                          "--puntos", "{in}/puntos.mat", "--plot", "{x}"],
    "trajectory --rrd": ["trajectory", "--ensayo", "{in}/ensayo.mat", "--acel",
                         "{in}/acel.mat", "--puntos", "{x}", "--rrd", "{x}"],
    "fuse --rrd": ["fuse", "--ensayo", "{in}/ensayo.mat", "--acel", "{in}/acel.mat",
                   "--puntos", "{in}/puntos.mat", "--gps", "{x}", "--rrd", "{x}"],
    "fuse --plot": ["fuse", "--ensayo", "{x}", "--acel", "{in}/acel.mat", "--puntos",
                    "{in}/puntos.mat", "--gps", "{in}/datos.txt", "--plot", "{x}"],
    "noise --save": ["noise", "{x}", "--save", "{x}"],
    "noise --plot": ["noise", "{in}/ensayo.mat", "--calibration", "{x}", "--plot", "{x}"],
    "gap --rrd": ["gap", "{x}", *NV, "--rrd", "{x}"],
    "generate --sensor --rrd": ["generate", "calibration", "--sensor", "{x}", "--out",
                                "{in}/set", "--rrd", "{x}"],
}


@pytest.mark.parametrize("spelling", ["same", "other", "symlink", "hardlink"])
@pytest.mark.parametrize("case", SAME, ids=str)
def test_an_input_is_never_the_output_even_with_force(case, spelling, files, capsys):
    """Refused in one line before any work, whatever the spelling of the output: the same
    name, another path to it, a symbolic link or a hard link to the input. (The refusal comes
    before anything is read, so which course file stands in for the input does not matter.)"""
    x = files / "ensayo.mat"
    before = x.read_bytes()
    out = {"same": x, "other": files / ".." / "in" / "ensayo.mat",
           "symlink": files / "link.mat", "hardlink": files / "hard.mat"}[spelling]
    if spelling == "symlink":
        out.symlink_to("ensayo.mat")
    elif spelling == "hardlink":
        os.link(x, out)
    argv = [a.replace("{in}", str(files)) for a in SAME[case]]
    argv = [str(x) if a == "{x}" else a for a in argv]
    argv[len(argv) - 1 - argv[::-1].index(str(x))] = str(out)  # the output option's value
    line = one_line_error(capsys, *argv, "--force")
    assert f"{out}: is the input {x}" in line and "not even with --force" in line
    assert x.read_bytes() == before
    assert _leftovers(files) == [] and not (files / "set").exists()


def test_import_into_the_folder_of_its_input_refuses_to_replace_it(files, capsys):
    """A folder output (here ``import``'s) refuses a run whose set would replace an input."""
    before = (files / "ensayo.mat").read_bytes()
    line = one_line_error(capsys, "import", files / "ensayo.mat", "--out", files, "--force")
    assert f"{files / 'ensayo.mat'}: is the input" in line
    assert (files / "ensayo.mat").read_bytes() == before
    assert _leftovers(files.parent) == []


def test_a_folder_replaced_whole_may_not_hold_an_input(tmp_path):
    target = tmp_path / "class"
    (target / "student_001").mkdir(parents=True)
    inp = target / "student_001" / "mine.mat"
    inp.write_bytes(b"input")
    with atomic.inputs_protected([inp]):
        with pytest.raises(atomic.InputAsOutputError, match="holds the input"):
            with atomic.atomic_dir(target, force=True, exclusive=["student_001"]) as tmp:
                (tmp / "student_001").mkdir()
    assert inp.read_bytes() == b"input"
    assert sorted(os.listdir(tmp_path)) == ["class"]


def test_protection_ends_with_the_command(tmp_path, files, capsys):
    """The inputs are protected for one command only: the next may write that name."""
    cal = tmp_path / "cal.json"
    assert run(capsys, "calibrate", files / "ensayo.mat", *NV, "--save", cal)[0] == 0
    assert atomic.input_behind(cal) is None
    rc, _, err = run(capsys, "noise", files / "ensayo.mat", "--calibration", cal,
                     "--save", tmp_path / "sensor.json")
    assert atomic.input_behind(cal) is None and "is the input" not in err


# ---------------------------------------------------------------- read-only and full disks
def _failing_under(root: Path, real, err: int, by_fd: bool):
    def call(arg, *args, **kwargs):
        where = os.readlink(f"/proc/self/fd/{arg}") if by_fd else os.fspath(arg)
        if os.path.abspath(where).startswith(str(root)):
            raise OSError(err, os.strerror(err))
        return real(arg, *args, **kwargs)
    return call


FAULTS = {  # the call that fails, whether it takes a descriptor, the errno, the message
    "read-only": ("open", False, errno.EROFS, "Read-only file system"),
    "full disk": ("fsync", True, errno.ENOSPC, "No space left on device"),
}


@pytest.mark.parametrize("fault, option, name", [
    ("read-only", "--save", "cal.json"), ("read-only", "--plot", "fit.png"),
    ("read-only", "--save", "cal.mat"), ("full disk", "--save", "cal.json"),
    ("full disk", "--plot", "fit.png")])
def test_a_failing_disk_is_one_line_and_loses_nothing(fault, option, name, tmp_path, files,
                                                       capsys, monkeypatch):
    """A read-only folder (open fails) or a full disk (fsync fails) under the output: one
    line naming the output and the system's reason, the previous file kept, no leftover."""
    call, by_fd, err, message = FAULTS[fault]
    folder = tmp_path / "out"
    folder.mkdir()
    out = folder / name
    out.write_bytes(b"the previous result")
    real = getattr(os, call)
    monkeypatch.setattr(atomic.os, call, _failing_under(folder, real, err, by_fd))
    line = one_line_error(capsys, "calibrate", files / "ensayo.mat", *NV, option, out,
                          "--force")
    monkeypatch.undo()
    assert line.endswith(f"{out}: {message}")
    assert ".tmp" not in line and ".lock" not in line
    assert out.read_bytes() == b"the previous result"
    assert sorted(os.listdir(folder)) == [name]


def test_a_refused_run_leaves_no_folder_it_created(tmp_path, files, capsys):
    """Folders made at start-up to hold an output's lock go again if nothing was written."""
    out = tmp_path / "new" / "sub" / "cal.json"
    one_line_error(capsys, "calibrate", files / "ensayo.mat", "--noise-var=-1,1", "--save", out)
    assert sorted(os.listdir(tmp_path)) == ["in"]


def test_a_nul_in_an_output_name_is_named(files, capsys):
    line = one_line_error(capsys, "calibrate", files / "ensayo.mat", *NV, "--save", "a\0b.json")
    assert "'a\\x00b.json': a file name cannot hold a NUL character" in line


# ---------------------------------------------------------------- the writer itself
def test_private_mode_from_the_first_byte_and_kept_on_replace(tmp_path, monkeypatch):
    """``mode=0o600``: the temporary is 0600 at its rename and the file stays 0600; a file
    made private by its owner stays private when replaced with ``force``."""
    seen = []
    real_replace = os.replace

    def replace(src, dst):
        seen.append(stat.S_IMODE(os.stat(src).st_mode))
        return real_replace(src, dst)

    monkeypatch.setattr(atomic.os, "replace", replace)
    key = atomic.write_text(tmp_path / "key.json", "{}", mode=0o600)
    monkeypatch.undo()
    assert seen == [0o600] and stat.S_IMODE(key.stat().st_mode) == 0o600
    mine = tmp_path / "mine.json"
    mine.write_text("old")
    mine.chmod(0o640)
    atomic.write_text(mine, "new", force=True)
    assert mine.read_text() == "new" and stat.S_IMODE(mine.stat().st_mode) == 0o640


def test_writer_keeps_no_temporary_after_any_error(tmp_path, monkeypatch):
    """An exception between the temporary and the rename (here an interrupt) removes the
    temporary and leaves the old file and no lock."""
    out = tmp_path / "x.json"
    out.write_text("old")

    def interrupted(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr(atomic.os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        atomic.write_text(out, "new", force=True)
    monkeypatch.undo()
    assert sorted(os.listdir(tmp_path)) == ["x.json"] and out.read_text() == "old"


def test_a_second_writer_in_another_process_is_refused(tmp_path, holder):
    out = tmp_path / "x.json"
    pid = holder(out)
    with pytest.raises(atomic.OutputBusyError, match=f"writing {out} \\(pid {pid}\\)"):
        atomic.write_text(out, "mine")
    assert not out.exists()


def test_main_releases_every_lock(tmp_path, files, capsys):
    out = tmp_path / "cal.json"
    assert main(["calibrate", str(files / "ensayo.mat"), *NV, "--save", str(out)]) == 0
    capsys.readouterr()
    assert not atomic.holds_lock(out) and _leftovers(tmp_path) == []
    with atomic.output_lock(out):  # free for the next run
        pass


@pytest.mark.parametrize("writes", [True, False])
def test_a_refused_run_waits_for_the_holders_pid(tmp_path, writes):
    """The holder writes its pid right after its ``flock``; a run refused in between reads
    the lock file again until the pid is there (it said "pid unknown" before, once in CI),
    and says "unknown" when it never comes."""
    import fcntl
    import threading

    out = tmp_path / "cal.json"
    fd = os.open(atomic._lock_path(out), os.O_RDWR | os.O_CREAT, 0o666)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # held, the pid not written yet
        late = threading.Timer(0.01, os.pwrite, (fd, b"424242\n" if writes else b"", 0))
        late.start()
        with pytest.raises(atomic.OutputBusyError) as err:
            with atomic.output_lock(out):
                pass
        late.join()
        assert f"(pid {'424242' if writes else 'unknown'})" in str(err.value)
    finally:
        os.close(fd)
