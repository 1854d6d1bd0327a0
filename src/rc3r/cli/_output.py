"""Output directories written as a whole: checked before any work, filled in a temporary
directory, swapped in at the end, locked against a second writer.

``with output_dir(path) as tmp: ...`` checks ``path`` before the caller simulates anything
(not a file, a symlink, a device or a filesystem root; its parent creatable and writable, which
is tried by creating and removing a file there, so a read-only or unnameable place is found
before any work), takes the lock ``.<name>.lock`` beside it (a second run into the same
directory is refused while the first one's process lives), and yields a fresh temporary
directory beside it. On success the temporary directory replaces ``path`` (the old one is moved
aside by one rename and deleted after the new one is in place by another), so a reader sees the
old directory or the new one, never a mix of two runs. Entries of the old directory that rc3r
does not write (:data:`OWN_ENTRIES`: a user's notes beside a result) are carried into the new
one first, as hard links (the same files), and so survive ``--force``. On any error or interrupt
the temporary directory is removed and ``path`` is untouched; an error of the file system
(read-only, full, a name too long) is one line, exit 2. Directories and files get the user's
umask.

The lock file appears atomically with its owner's PID in it (written into a temporary file,
then ``link``-ed into place), so it is never empty; a stale lock (its process gone) is broken by
renaming exactly that file aside, so two processes breaking it at once cannot remove each
other's fresh lock.

A writer killed by ``kill -9`` (or the OOM killer) leaves its lock and its temporary directory
``.<name>.tmp-XXXXXXXX`` beside ``path``. The next writer takes the stale lock over and, holding it,
removes every such temporary directory of ``path`` (:func:`_remove_dead_tmp`): only a writer that
holds the lock ever creates one, so while the lock is ours none of them has a live owner. Only
names of exactly that form are touched (``tempfile.mkdtemp``'s 8 characters; a directory
``.<name>.tmp-x.tmp-XXXXXXXX`` of another output ``<name>.tmp-x`` is not), and only directories.
"""
from __future__ import annotations

import errno
import fnmatch
import os
import re
import secrets
import shutil
import stat
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

from ..errors import ConfigError
from ..io import apply_umask

__all__ = ["output_dir", "check_output_path", "locked", "OWN_ENTRIES", "OUTPUT_MARKERS"]


#: Files that mark a directory as rc3r's own output (it may then be replaced as a whole).
OUTPUT_MARKERS = ("metrics.json", "summary.json", "sweep.json", "stability.json", "campaign.json", "runs.csv",
                  "identified.json", "export.json")

#: Entries (glob patterns) ``rc3r run`` and ``rc3r paper`` write in their directory: replaced by a
#: rerun (an older run's ``animation.gif`` does not survive beside a new run without one). Any
#: other entry of the old directory is kept.
OWN_ENTRIES = ("metrics.json", "timeseries.csv", "run.png", "estimate.png", "animation.gif", "animation.mp4",
               "summary.json", "summary.md", "errors-*.png", "compare-*.png", "boundary-layer-*.png",
               "continuous", "sampled")

#: An empty lock file younger than this [s] is held, not stale: a writer without hard links
#: (some network or FAT file systems) creates it and then writes its PID.
EMPTY_LOCK_GRACE_S = 10.0


def _oserror(path, exc: OSError, doing: str) -> ConfigError:
    return ConfigError(f"--out {path}: {doing}: {exc.strerror or exc}")


def check_output_path(path) -> Path:
    """Refuse an output directory that cannot be (re)written as a whole; return it absolute.

    Refused: an empty path, a filesystem root, the current directory or one that contains it,
    a symbolic link, a file or device, an existing non-empty directory that is not an earlier
    rc3r output (none of :data:`OUTPUT_MARKERS`: replacing it would delete files rc3r did not
    write, a source tree, a git repository), a name the system cannot hold, and a parent in
    which a file cannot be created (read-only, ``/proc``, a regular file on the way).
    """
    p = Path(path)
    if str(path).strip() in ("", "."):
        raise ConfigError("--out is empty or '.'; give a directory for the results")
    absolute = Path(os.path.abspath(p))
    if absolute.parent == absolute:
        raise ConfigError(f"--out {path} is a filesystem root; give a directory for the results")
    cwd = Path(os.path.abspath(os.getcwd()))
    if cwd == absolute or absolute in cwd.parents:
        raise ConfigError(f"--out {path} is the current directory or contains it; give a directory for the results")
    try:
        st = os.lstat(p)
    except FileNotFoundError:
        st = None
    except OSError as exc:  # a name too long, a file used as a directory, a loop of links
        raise _oserror(path, exc, "cannot use it") from None
    if st is not None and stat.S_ISLNK(st.st_mode):
        raise ConfigError(f"--out {path} is a symbolic link; give the directory itself")
    if st is not None:
        if not stat.S_ISDIR(st.st_mode):
            kind = "a file" if stat.S_ISREG(st.st_mode) else "not a directory (a device or special file)"
            raise ConfigError(f"--out {path} is {kind}; give a directory for the results")
        try:
            names = {e.name for e in os.scandir(p)}
        except OSError as exc:
            raise _oserror(path, exc, "cannot read it") from None
        if ".git" in names or (names and not names & set(OUTPUT_MARKERS)):
            raise ConfigError(f"--out {path} is a non-empty directory that rc3r did not write (no "
                              f"{', '.join(OUTPUT_MARKERS[:2])} ...); refusing to replace it: give another directory")
        if not os.access(p, os.W_OK | os.X_OK):  # it is moved aside as a whole: needs write permission
            raise ConfigError(f"--out {path} is not writable")
    parent = absolute.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _oserror(path, exc, f"cannot create {parent}") from None
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ConfigError(f"--out {path}: directory {parent} is not writable")
    _probe(parent, absolute.name, path)
    return absolute


def _probe(parent: Path, name: str, path) -> None:
    """Create and remove a file named like the longest rc3r creates beside ``name`` (the lock's
    temporary file): a read-only file system, ``/proc`` or a name over the system's limit is found
    now, before any work, even as root (for whom permission bits do not stop writes)."""
    try:
        fd, probe = tempfile.mkstemp(prefix=f".{name}.lock.", dir=parent)
    except OSError as exc:
        raise _oserror(path, exc, f"cannot write in {parent}") from None
    os.close(fd)
    os.unlink(probe)


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _read_lock(lock: Path):
    """``(pid or 0, stat)`` of the lock file, or ``(0, None)`` if it is gone."""
    try:
        with open(lock, "rb") as f:
            st = os.fstat(f.fileno())
            text = f.read(64).decode(errors="replace").strip()
    except FileNotFoundError:
        return 0, None
    except OSError as exc:
        raise ConfigError(f"cannot read the lock {lock}: {exc.strerror or exc}; remove it if no rc3r runs") from None
    return (int(text) if text.isdigit() else 0), st


def _break_stale(lock: Path, st) -> None:
    """Remove the stale lock ``st`` (that very file): rename it aside, and if what was renamed is
    another file (a fresh lock that replaced it meanwhile), put that one back."""
    grave = lock.parent / f"{lock.name}.{secrets.token_hex(4)}"
    try:
        os.rename(lock, grave)
    except FileNotFoundError:  # another process broke it first
        return
    moved = os.lstat(grave)
    if (moved.st_ino, moved.st_dev) != (st.st_ino, st.st_dev):
        try:
            os.link(grave, lock)
        except FileExistsError:
            pass
    os.unlink(grave)


def _place(lock: Path) -> int | None:
    """Create ``lock`` holding this process's PID; its inode, or None if it exists already."""
    pid = str(os.getpid()).encode()
    try:
        fd, tmp = tempfile.mkstemp(prefix=f"{lock.name}.", dir=lock.parent)
    except OSError as exc:
        raise ConfigError(f"cannot create lock {lock}: {exc.strerror or exc}") from None
    try:
        os.write(fd, pid)
        os.fchmod(fd, 0o644)
        os.close(fd)
        try:
            os.link(tmp, lock)  # appears with the PID in it: never empty
            return os.lstat(tmp).st_ino
        except FileExistsError:
            return None
        except OSError as exc:
            if exc.errno not in (errno.EPERM, errno.EOPNOTSUPP, errno.ENOTSUP, errno.EMLINK):
                raise ConfigError(f"cannot create lock {lock}: {exc.strerror or exc}") from None
        try:  # no hard links here: exclusive create, then the PID (an empty lock is held, EMPTY_LOCK_GRACE_S)
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            return None
        except OSError as exc:
            raise ConfigError(f"cannot create lock {lock}: {exc.strerror or exc}") from None
        os.write(fd, pid)
        ino = os.fstat(fd).st_ino
        os.close(fd)
        return ino
    finally:
        os.unlink(tmp)


def _acquire(lock: Path) -> int:
    """Take ``lock``; return its inode. Refused while a live process holds it (its PID inside) or while
    it is empty and younger than :data:`EMPTY_LOCK_GRACE_S`; a stale one is broken and retaken."""
    target = lock.parent / lock.name[1:-5]
    for _ in range(3):
        ino = _place(lock)
        if ino is not None:
            return ino
        pid, st = _read_lock(lock)
        if st is None:  # released meanwhile
            continue
        if pid and _pid_alive(pid):
            raise ConfigError(f"another rc3r process (pid {pid}) is writing to {target}; wait for it or remove {lock}")
        if not pid and time.time() - st.st_mtime < EMPTY_LOCK_GRACE_S:
            raise ConfigError(f"another rc3r process is taking the lock {lock} of {target} (empty, "
                              f"{time.time() - st.st_mtime:.1f} s old); wait for it or remove {lock}")
        _break_stale(lock, st)  # stale: its process is gone
    raise ConfigError(f"cannot take the lock {lock}")


@contextmanager
def locked(final: Path):
    """Hold ``.<name>.lock`` beside the directory ``final`` (refused while another live rc3r holds it)."""
    lock = final.parent / f".{final.name}.lock"
    ino = _acquire(lock)
    try:
        yield
    finally:
        try:
            if os.lstat(lock).st_ino == ino:  # ours: never remove another process's lock
                os.unlink(lock)
        except FileNotFoundError:
            pass


def _own(name: str, own) -> bool:
    return any(fnmatch.fnmatchcase(name, pattern) for pattern in own)


def _link(src, dst) -> None:
    try:
        os.link(src, dst)
    except OSError:  # a file system without hard links
        shutil.copy2(src, dst)


def _carry(final: Path, tmp: Path, own) -> None:
    """Hard-link the entries of ``final`` that rc3r does not write (and the new run did not) into ``tmp``."""
    for entry in os.scandir(final):
        dst = tmp / entry.name
        if _own(entry.name, own) or os.path.lexists(dst):
            continue
        if entry.is_symlink():
            os.symlink(os.readlink(entry.path), dst)
        elif entry.is_dir():
            shutil.copytree(entry.path, dst, symlinks=True, copy_function=_link)
        else:
            _link(entry.path, dst)


def _swap(tmp: Path, final: Path, own) -> None:
    """Put ``tmp`` in place of ``final`` (module docstring); on failure ``final`` is as it was."""
    apply_umask(tmp, directory=True)
    old = None
    if os.path.lexists(final):
        _carry(final, tmp, own)
        old = Path(tempfile.mkdtemp(prefix=f".{final.name}.old-", dir=final.parent))
        try:
            os.replace(final, old / "previous")
        except OSError:
            old.rmdir()
            raise
    try:
        os.replace(tmp, final)
    except OSError as exc:
        if old is not None:  # put the previous results back
            try:
                os.replace(old / "previous", final)
                old.rmdir()
            except OSError:
                raise ConfigError(f"--out {final}: cannot put the results in place ({exc.strerror or exc}) nor the "
                                  f"earlier ones back: they are in {old / 'previous'}") from None
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


#: What ``tempfile.mkdtemp`` appends to a prefix: 8 characters of this alphabet.
_MKDTEMP_SUFFIX = "[a-z0-9_]{8}"


def _remove_dead_tmp(final: Path) -> list[Path]:
    """Remove the temporary directories ``.<name>.tmp-XXXXXXXX`` of ``final`` that killed writers left.

    Call only while holding ``final``'s lock (:func:`locked`): a temporary directory is made only under
    the lock, so every one found then belongs to a writer that is gone. Returns the removed paths.
    """
    pattern = re.compile(re.escape(f".{final.name}.tmp-") + _MKDTEMP_SUFFIX + r"\Z")
    removed = []
    try:
        entries = list(os.scandir(final.parent))
    except OSError:
        return removed
    for entry in entries:
        if pattern.match(entry.name) and entry.is_dir(follow_symlinks=False):
            shutil.rmtree(entry.path, ignore_errors=True)
            removed.append(Path(entry.path))
    return removed


@contextmanager
def output_dir(path, own=OWN_ENTRIES):
    """Yield a temporary directory that replaces ``path`` as a whole on success (module docstring).

    ``own``: glob patterns of the entries the caller writes; other entries of an earlier ``path``
    are kept. An ``OSError`` while the caller writes into the temporary directory or while it is
    swapped in (a full or read-only file system) becomes a one-line :class:`ConfigError`; the
    earlier ``path`` is left as it was.
    """
    final = check_output_path(path)
    with locked(final):
        _remove_dead_tmp(final)  # a killed writer's leftovers: the lock is ours, so their owners are gone
        tmp = None
        try:
            tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.tmp-", dir=final.parent))
            yield tmp
            _swap(tmp, final, own)
            tmp = None
        except OSError as exc:
            if exc.errno is None:
                raise
            where = f" ({exc.filename})" if exc.filename else ""
            kept = "the earlier results in it are kept" if os.path.lexists(final) else "nothing was written"
            raise ConfigError(f"--out {path}: cannot write the results: {exc.strerror or exc}{where}; {kept}") from None
        finally:
            if tmp is not None:
                shutil.rmtree(tmp, ignore_errors=True)
