"""Atomic outputs: one file, one directory (a *set* of files) and the lock between runs.

Guarantees (each writer here):

* **never half written** — everything goes to a hidden temporary name beside the target
  (``.NAME.PID-XXXXXXXX.tmp``, file or directory) and is renamed into place at the end, after
  the data and the directory entries are flushed to disk (``fsync`` of every file, then of
  the directories);
* **a set is replaced as a whole** — :func:`atomic_dir` swaps the old directory for the new
  one with one ``renameat2(RENAME_EXCHANGE)`` where the filesystem has it (at every instant
  the target is the old set or the new one); elsewhere with two renames (old → backup name,
  new → target; a run killed between them leaves the old set under the backup name and the
  next run puts it back);
* **one writer per target** — :func:`output_lock` takes a non-blocking ``flock`` on
  ``.NAME.lock`` beside the target; a second run fails at once with :class:`OutputBusyError`
  ("another tiltbench run is writing OUT (pid N)"). Single files take the same lock as sets
  (:func:`write_bytes`); a command takes the locks of all its outputs at start-up
  (:func:`holding`, from ``bench.cli.output``) and keeps them until it ends, so a second run
  is refused before it computes anything and no result replaces another one silently;
* **never an input as the output** — inside :func:`inputs_protected` (a command's input
  files), writing a file that *is* one of them (same inode: the same name, a symbolic link
  or a hard link) raises :class:`InputAsOutputError`, with or without ``force``;
* **no leftovers** — every error path removes its temporary files; temporary names left by
  a killed run (its pid is gone, or we hold the target's lock) are removed by the next run;
* **errors name the target**, never a temporary name (a full disk reads
  ``OUT: No space left on device``);
* **private until published** — a temporary is created readable by its owner only (file
  0600, directory 0700) and keeps that mode until it is renamed into place; what must stay
  private (an answer key: ``mode=0o600``) keeps it for good. A run killed before its final
  rename leaves nothing that another user can read.

Exception: a target that is a mount point or holds the working directory is not swapped;
its new files are renamed into it one by one (each file atomic, the set not).

Files that are not ours are kept: entries of an existing target directory that the new set
does not write are carried into it (hard links), except inside the ``exclusive`` folders,
which the new set replaces whole.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import fcntl
import os
import re
import shutil
import stat
import tempfile
import time
from collections.abc import Iterable, Iterator
from pathlib import Path

TMP_SUFFIX = ".tmp"
BACKUP_SUFFIX = ".bak.tmp"

_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


class OutputBusyError(OSError):
    """Another process holds the lock of this output (message names it and the pid)."""


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_HELD: dict[tuple[int, str], int] = {}
"""Locks this process holds: (pid, lock path) → descriptor. The pid keeps a forked child
from believing it holds its parent's locks."""

_INPUTS: list[tuple[str, int, int]] = []
"""Files protected by :func:`inputs_protected`: (name as given, st_dev, st_ino)."""


class InputAsOutputError(ValueError):
    """An output path that is one of the command's inputs (one line at the command line)."""


def _tmp_prefix(name: str) -> str:
    return f".{name}.{os.getpid()}-"


def _stale_pattern(name: str) -> re.Pattern:
    # ours: .NAME.PID-XXXXXXXX.tmp (and .bak.tmp); older versions: .NAME.XXXXXXXX.tmp
    return re.compile(rf"^\.{re.escape(name)}\.(?:(\d+)-[A-Za-z0-9_]+|[A-Za-z0-9_]{{8}})"
                      rf"(\.bak)?\.tmp$")


_ANY_TMP = re.compile(r"^\..+\.(?:\d+-[A-Za-z0-9_]+|[A-Za-z0-9_]{8})(?:\.bak)?\.tmp$")
"""Any of our temporary names (not carried into a new set)."""
LEGACY_AGE = 3600.0
"""Seconds after which a temporary name without a pid (older versions) counts as stale."""


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()


def clean_stale(target: str | os.PathLike, locked: bool = False) -> list[Path]:
    """Remove temporary names of ``target`` left by killed runs; return what was removed.

    A temporary name is stale when the process named in it is gone (a name without a pid,
    from older versions: when untouched for :data:`LEGACY_AGE`), or when ``locked``
    (the caller holds :func:`output_lock` of ``target``, so no live run can own one). A
    backup of an interrupted swap is renamed back to ``target`` if ``target`` is missing.
    Best effort: what cannot be removed (a read-only directory) is left.
    """
    target = Path(target)
    parent = target.parent if str(target.parent) else Path(".")
    pattern = _stale_pattern(target.name)
    removed = []
    try:
        entries = sorted(os.listdir(parent))
    except OSError:
        return removed
    for entry in entries:
        m = pattern.match(entry)
        if not m:
            continue
        pid = m.group(1)
        path = parent / entry
        if not locked and pid is not None and _alive(int(pid)):
            continue
        if not locked and pid is None:
            with contextlib.suppress(OSError):
                if time.time() - os.lstat(path).st_mtime < LEGACY_AGE:
                    continue
        if m.group(2) and not os.path.lexists(target):
            with contextlib.suppress(OSError):
                os.rename(path, target)  # the old set of an interrupted swap
                _fsync_dir(parent)
                continue
        _remove(path)
        removed.append(path)
    return removed


def _named(exc: OSError, shown: str | os.PathLike, tmp: str | os.PathLike | None = None):
    """``exc`` naming ``shown`` (or the file under it) instead of a temporary name."""
    filename = exc.filename
    if tmp is not None and filename is not None and str(filename).startswith(str(tmp)):
        rel = os.path.relpath(filename, tmp)
        filename = str(shown) if rel == "." else os.path.join(str(shown), rel)
    elif tmp is None or filename is None:
        filename = str(shown)
    if isinstance(exc, OutputBusyError) or exc.errno is None or filename == exc.filename:
        return exc
    return type(exc)(exc.errno, exc.strerror or os.strerror(exc.errno), filename)


def _reraise(exc: OSError, shown, tmp=None):
    new = _named(exc, shown, tmp)
    if new is exc:
        raise exc
    raise new from exc


def _fsync_dir(path: str | os.PathLike) -> None:
    try:
        fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError as exc:  # some filesystems cannot sync a directory: not an error
        if exc.errno not in (errno.EINVAL, errno.EBADF, errno.ENOTSUP):
            raise
    finally:
        os.close(fd)


def _fsync_tree(root: Path) -> None:
    """fsync every regular file under ``root``, then every directory (deepest first)."""
    dirs = []
    for here, _, files in os.walk(root):
        dirs.append(here)
        for f in files:
            p = os.path.join(here, f)
            if os.path.islink(p):
                continue
            fd = os.open(p, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
    for d in reversed(dirs):
        _fsync_dir(d)


def write_bytes(path: str | os.PathLike, data: bytes, force: bool = False,
                mode: int | None = None) -> Path:
    """Write ``data`` to ``path`` atomically and durably (temporary file, fsync, rename).

    Under the output lock of ``path`` (:func:`holding`: the command's own if it took it at
    start-up, else taken here; another writer → :class:`OutputBusyError`). Refuses a
    directory (:class:`ValueError`), an input of the command (:class:`InputAsOutputError`,
    even with ``force``) and an existing file unless ``force`` (:class:`FileExistsError`).
    Temporary files of ``path`` left by killed runs are removed first; the temporary is
    created 0600 and removed on any error. The file gets ``mode`` if given (0o600: private),
    else the mode of the file it replaces, else what a plain ``open()`` would give.
    """
    path = Path(path)
    if path.is_dir():  # a ValueError, as calib.files.course.DataError: one line at the command line
        raise ValueError(f"{path}: is a directory; expected an output file name")
    refuse_input(path)
    parent = path.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        _reraise(exc, path)
    with holding(path):
        if path.exists() and not force:
            raise FileExistsError(f"{path}: exists")
        clean_stale(path, locked=True)
        if mode is None:
            try:
                mode = stat.S_IMODE(os.stat(path).st_mode)
            except OSError:
                mode = 0o666 & ~_umask()
        tmp = None
        try:
            fd, tmp = tempfile.mkstemp(dir=parent, prefix=_tmp_prefix(path.name),
                                       suffix=TMP_SUFFIX)
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
                fh.flush()
                os.fsync(fh.fileno())
                os.fchmod(fh.fileno(), mode)  # mkstemp creates 0600: the final mode last
            os.replace(tmp, path)
            tmp = None
            _fsync_dir(parent)
        except OSError as exc:
            _reraise(exc, path)
        finally:
            if tmp is not None:
                with contextlib.suppress(OSError):
                    os.unlink(tmp)
    return path


def write_text(path: str | os.PathLike, text: str, force: bool = False,
               mode: int | None = None) -> Path:
    """:func:`write_bytes` of ``text`` in UTF-8."""
    return write_bytes(path, text.encode("utf-8"), force=force, mode=mode)


def _lock_path(target: str | os.PathLike) -> Path:
    real = Path(os.path.realpath(target))
    return real.parent / f".{real.name}.lock"


def holds_lock(target: str | os.PathLike) -> bool:
    """True if this process holds the output lock of ``target``."""
    return (os.getpid(), str(_lock_path(target))) in _HELD


HOLDER_PID_WAIT = 0.05
"""Seconds a refused run waits for the holder's pid in the lock file: the holder writes it
right after taking the lock, and may not have yet."""


def _holder_pid(fd: int) -> str:
    """The pid the lock's holder wrote in the lock file ``fd``, read again for up to
    :data:`HOLDER_PID_WAIT` while it is still empty (the holder between its ``flock`` and its
    write); "unknown" after that (a full disk, or a holder that stopped there)."""
    end = time.monotonic() + HOLDER_PID_WAIT
    while True:
        pid = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
        if pid or time.monotonic() >= end:
            return pid or "unknown"
        time.sleep(0.002)


@contextlib.contextmanager
def output_lock(target: str | os.PathLike) -> Iterator[Path]:
    """Hold the exclusive lock of ``target`` (``.NAME.lock`` beside it; removed on release).

    Non-blocking: if another process holds it (or this one already does), raise
    :class:`OutputBusyError` at once. The lock is the kernel's ``flock``: a killed run releases
    it with its last file descriptor. Several writes under one lock: :func:`holding`.
    """
    target = Path(target)
    lock_path = _lock_path(target)
    key = (os.getpid(), str(lock_path))
    if key in _HELD:
        raise OutputBusyError(f"another tiltbench run is writing {target} (pid {os.getpid()}); "
                              "wait for it to end or choose another output")
    while True:
        try:
            fd = os.open(lock_path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
        except OSError as exc:
            _reraise(exc, target)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            try:
                pid = _holder_pid(fd)
            finally:
                os.close(fd)
            raise OutputBusyError(f"another tiltbench run is writing {target} (pid {pid}); "
                                  "nothing was written by this run: run it again when that "
                                  "one has ended, or choose another output") from None
        try:  # the holder before us may have removed the file: lock the one on disk
            same = os.path.samestat(os.fstat(fd), os.stat(lock_path))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    _HELD[key] = fd
    try:
        with contextlib.suppress(OSError):  # the pid is for the message only (full disk)
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield lock_path
    finally:
        del _HELD[key]
        with contextlib.suppress(OSError):
            os.unlink(lock_path)
        os.close(fd)


@contextlib.contextmanager
def holding(target: str | os.PathLike) -> Iterator[Path]:
    """The output lock of ``target`` for the block: taken here (:func:`output_lock`) unless
    this process already holds it (a command that claimed its outputs at start-up), in which
    case the block runs under that lock and leaves it held."""
    if holds_lock(target):
        yield _lock_path(target)
        return
    with output_lock(target) as lock_path:
        yield lock_path


@contextlib.contextmanager
def inputs_protected(paths: Iterable[str | os.PathLike]) -> Iterator[list[str]]:
    """Within the block, :func:`write_bytes` and :func:`atomic_dir` refuse to replace any
    of ``paths`` (existing regular files; others are ignored) — a command's inputs.

    A file is matched by its identity (``st_dev``, ``st_ino``), so the same name, another
    spelling (``./a``, ``../x/a``), a symbolic link or a hard link to an input are all
    refused. Yields the names protected."""
    added = []
    for p in paths:
        with contextlib.suppress(OSError, ValueError, TypeError):
            st = os.stat(p)
            if stat.S_ISREG(st.st_mode):
                added.append((os.fspath(p), st.st_dev, st.st_ino))
    _INPUTS.extend(added)
    try:
        yield [a[0] for a in added]
    finally:
        for a in added:
            _INPUTS.remove(a)


def input_behind(path: str | os.PathLike) -> str | None:
    """The protected input (:func:`inputs_protected`) that ``path`` is, or None."""
    if not _INPUTS:
        return None
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    for name, dev, ino in _INPUTS:
        if (st.st_dev, st.st_ino) == (dev, ino):
            return name
    return None


def _input_inside(folder: Path) -> str | None:
    """The first protected input whose real path lies inside ``folder``, or None."""
    top = os.path.realpath(folder)
    for name, _, _ in _INPUTS:
        if os.path.realpath(name).startswith(top + os.sep):
            return name
    return None


def refuse_input(path: str | os.PathLike, shown: str | os.PathLike | None = None) -> None:
    """Raise :class:`InputAsOutputError` if ``path`` is a protected input (any spelling,
    symbolic or hard link); the message names ``shown`` (default ``path``)."""
    name = input_behind(path)
    if name is None:
        return
    if os.path.islink(path) or os.path.islink(name):
        how = " through a symbolic link"
    elif os.path.realpath(name) == os.path.realpath(path):
        how = ""
    else:
        how = " (a hard link to it)"
    raise InputAsOutputError(
        f"{shown if shown is not None else path}: is the input {name}{how}; an output never "
        "replaces an input of the same run, not even with --force: write to another name")


def _exchange(a: Path, b: Path) -> bool:
    """Swap ``a`` and ``b`` atomically; False where the system or filesystem cannot."""
    try:
        fn = ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):
        return False
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    fn.restype = ctypes.c_int
    if fn(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def _carry_over(old: Path, new: Path, exclusive: set[str], rel: str = "") -> None:
    """Hard-link (else copy) into ``new`` every entry of ``old`` that ``new`` does not have,
    except the ``exclusive`` ones (relative paths, folders or files): those belong to the set,
    so an old one the new set does not write goes with the old set."""
    for entry in os.scandir(old):
        if _ANY_TMP.match(entry.name):  # a killed writer's leftover: dropped with the old set
            continue
        r = f"{rel}{entry.name}"
        dst = new / entry.name
        if entry.is_dir(follow_symlinks=False):
            if r in exclusive and dst.exists():
                continue
            if not dst.exists():
                dst.mkdir()
                shutil.copymode(entry.path, dst)
            elif not dst.is_dir() or dst.is_symlink():
                continue
            _carry_over(Path(entry.path), dst, exclusive, r + "/")
        elif r in exclusive:
            continue
        elif not os.path.lexists(dst):
            if entry.is_symlink():
                os.symlink(os.readlink(entry.path), dst)
                continue
            try:
                os.link(entry.path, dst, follow_symlinks=False)
            except OSError:
                shutil.copy2(entry.path, dst, follow_symlinks=False)


def _commit(tmp: Path, real: Path) -> None:
    """Put the finished ``tmp`` at ``real`` (replacing an old directory as a whole).

    ``tmp`` is 0700 (``mkdtemp``) and gets the target's mode only after the rename: a run
    killed before it leaves a temporary set (an answer key) that other users cannot read,
    and the new target at worst 0700 (closed, not exposed) until the next run."""
    parent = real.parent
    if not real.exists():
        os.rename(tmp, real)
        os.chmod(real, 0o777 & ~_umask())
        _fsync_dir(parent)
        return
    mode = stat.S_IMODE(os.stat(real).st_mode)
    if _exchange(tmp, real):  # tmp now holds the old set
        os.chmod(real, mode)
        with contextlib.suppress(OSError):
            os.chmod(tmp, 0o700)  # the old set, on its way out: private meanwhile
        _fsync_dir(parent)
        shutil.rmtree(tmp, ignore_errors=True)
        return
    # os.urandom, as secrets.token_hex does, without importing secrets (hmac, hashlib and
    # OpenSSL: ≈ 7 ms of every command that writes a file)
    backup = parent / f"{_tmp_prefix(real.name)}{os.urandom(4).hex()}{BACKUP_SUFFIX}"
    os.rename(real, backup)
    try:
        os.rename(tmp, real)
    except BaseException:
        os.rename(backup, real)  # restore the old set
        raise
    os.chmod(real, mode)
    _fsync_dir(parent)
    shutil.rmtree(backup, ignore_errors=True)


def _holds_cwd(path: Path) -> bool:
    try:
        cwd = Path(os.getcwd())
    except OSError:
        return False
    return cwd == path or path in cwd.parents


def _commit_in_place(tmp: Path, real: Path, exclusive: set[str]) -> None:
    """Move the new entries into ``real`` one file at a time (each rename atomic, the set
    not): for a target that cannot be swapped (a mount point, the working directory)."""
    for rel in sorted(exclusive):
        old, new = real / rel, tmp / rel
        if not os.path.lexists(new) and os.path.lexists(old) and not old.is_dir():
            _remove(old)  # an exclusive file the new set does not write
        elif new.is_dir() and old.is_dir() and not old.is_symlink():
            for entry in os.listdir(old):
                if not os.path.lexists(new / entry):
                    _remove(old / entry)
    for here, _dirs, files in os.walk(tmp):
        rel = Path(here).relative_to(tmp)
        (real / rel).mkdir(exist_ok=True)
        for f in files:
            os.replace(Path(here) / f, real / rel / f)
        _fsync_dir(real / rel)
    shutil.rmtree(tmp, ignore_errors=True)


@contextlib.contextmanager
def atomic_dir(target: str | os.PathLike, force: bool = False, owned: Iterable[str] = (),
               exclusive: Iterable[str] = ()) -> Iterator[Path]:
    """Write a set of files as a whole: yields an empty temporary directory beside ``target``.

    Write everything into the yielded directory; on normal exit it is flushed and replaces
    ``target`` in one step (see the module docstring); on any error (or interrupt) it is
    removed and ``target`` is untouched. The target's lock is held throughout
    (:class:`OutputBusyError` if another run writes it).

    Parameters
    ----------
    target : the output directory (created if missing; its parents too).
    force : replace the ``owned`` entries if they exist; else :class:`FileExistsError`
        (checked under the lock, before anything is written).
    owned : relative paths the set writes (the overwrite check).
    exclusive : relative folders replaced whole (nothing of the old one is carried over) and
        relative files that belong to the set: an old one the new set does not write is
        removed, so the target never holds a mix of old and new (``tiltbench import`` over
        an earlier import: a new ``acel.mat`` never sits beside an old ``ensayo.mat``).
    """
    shown = Path(target)
    real = Path(os.path.realpath(shown))
    owned, exclusive = list(owned), list(exclusive)  # each read more than once
    if real.exists() and not real.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, "exists and is not a directory", str(shown))
    try:
        real.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        _reraise(exc, shown)
    # A target that cannot be renamed (a mount point) or that holds the working directory
    # (the shell would be left in the removed old one) gets its new files one by one, from a
    # temporary directory inside it: each file atomic, the set not.
    in_place = real.is_dir() and (os.path.ismount(real) or _holds_cwd(real))
    tmp_parent = real if in_place else real.parent
    with holding(shown):
        clean_stale(real, locked=True)
        if in_place:
            clean_stale(real / real.name, locked=True)
        for n in owned:  # before anything is written, whatever ``force`` says
            refuse_input(real / n, shown / n)
        for n in exclusive:  # replaced whole: an input anywhere inside would go with it
            inside = _input_inside(real / n)
            if inside is not None:
                raise InputAsOutputError(f"{shown / n}: holds the input {inside}, and this "
                                         "run replaces that folder whole, even with --force: "
                                         "write to another folder or move the input out")
        if not force and real.is_dir():
            clash = [n for n in owned if os.path.lexists(real / n)]
            if clash:
                raise FileExistsError(f"{shown}: {', '.join(clash[:4])}"
                                      f"{' …' if len(clash) > 4 else ''} already exist(s)")
        try:
            tmp = Path(tempfile.mkdtemp(dir=tmp_parent, prefix=_tmp_prefix(real.name),
                                        suffix=TMP_SUFFIX))
        except OSError as exc:
            _reraise(exc, shown)
        try:
            yield tmp
            if in_place:
                _fsync_tree(tmp)
                _commit_in_place(tmp, real, set(exclusive))
            else:
                if real.is_dir():
                    _carry_over(real, tmp, set(exclusive))
                _fsync_tree(tmp)
                _commit(tmp, real)
        except OSError as exc:
            shutil.rmtree(tmp, ignore_errors=True)
            _reraise(exc, shown, tmp)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise


__all__ = ["InputAsOutputError", "OutputBusyError", "atomic_dir", "clean_stale", "holding",
           "holds_lock", "input_behind", "inputs_protected", "output_lock", "refuse_input",
           "write_bytes", "write_text"]
