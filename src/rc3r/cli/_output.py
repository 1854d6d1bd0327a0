"""Output directories written as a whole: checked before any work, filled in a temporary
directory, swapped in at the end, locked against a second writer.

``with output_dir(path) as tmp: ...`` checks ``path`` before the caller simulates anything
(not a file, a symlink, a device or a filesystem root; its parent creatable and writable),
takes the lock ``.<name>.lock`` beside it (a second run into the same directory is refused
while the first one's process lives), and yields a fresh temporary directory beside it.
On success the temporary directory replaces ``path`` (the old one is moved aside by one
rename and deleted after the new one is in place by another), so a reader sees the old
directory or the new one, never a mix of two runs. On any error or interrupt the
temporary directory is removed and ``path`` is untouched. Directories and files get the
user's umask.
"""
from __future__ import annotations

import errno
import os
import shutil
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path

from ..errors import ConfigError
from ..io import apply_umask

__all__ = ["output_dir", "check_output_path", "locked"]


#: Files that mark a directory as rc3r's own output (it may then be replaced as a whole).
OUTPUT_MARKERS = ("metrics.json", "summary.json", "sweep.json", "stability.json", "campaign.json", "runs.csv")


def check_output_path(path) -> Path:
    """Refuse an output directory that cannot be (re)written as a whole; return it absolute.

    Refused: an empty path, a filesystem root, the current directory or one that contains it,
    a symbolic link, a file or device, and an existing non-empty directory that is not an
    earlier rc3r output (none of :data:`OUTPUT_MARKERS`): replacing it would delete files
    rc3r did not write (a source tree, a git repository).
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
    if p.is_symlink():
        raise ConfigError(f"--out {path} is a symbolic link; give the directory itself")
    if p.exists():
        mode = p.stat().st_mode
        if not stat.S_ISDIR(mode):
            kind = "a file" if stat.S_ISREG(mode) else "not a directory (a device or special file)"
            raise ConfigError(f"--out {path} is {kind}; give a directory for the results")
        try:
            names = {e.name for e in os.scandir(p)}
        except OSError as exc:
            raise ConfigError(f"--out {path}: cannot read it: {exc.strerror or exc}") from None
        if ".git" in names or (names and not names & set(OUTPUT_MARKERS)):
            raise ConfigError(f"--out {path} is a non-empty directory that rc3r did not write (no "
                              f"{', '.join(OUTPUT_MARKERS[:2])} ...); refusing to replace it: give another directory")
    parent = absolute.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"--out {path}: cannot create {parent}: {exc.strerror or exc}") from None
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ConfigError(f"--out {path}: directory {parent} is not writable")
    return absolute


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _acquire(lock: Path) -> None:
    for _ in range(2):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            try:
                pid = int(lock.read_text().strip() or 0)
            except (OSError, ValueError):
                pid = 0
            if pid and _pid_alive(pid):
                raise ConfigError(f"another rc3r process (pid {pid}) is writing to {lock.parent / lock.name[1:-5]}; "
                                  f"wait for it or remove {lock}") from None
            lock.unlink(missing_ok=True)  # stale: its process is gone
            continue
        except OSError as exc:
            raise ConfigError(f"cannot create lock {lock}: {exc.strerror or exc}") from None
        with os.fdopen(fd, "w") as f:
            f.write(str(os.getpid()))
        return
    raise ConfigError(f"cannot take the lock {lock}")


@contextmanager
def locked(final: Path):
    """Hold ``.<name>.lock`` beside the directory ``final`` (refused while another live rc3r holds it)."""
    lock = final.parent / f".{final.name}.lock"
    _acquire(lock)
    try:
        yield
    finally:
        lock.unlink(missing_ok=True)


@contextmanager
def output_dir(path):
    """Yield a temporary directory that replaces ``path`` as a whole on success (module docstring)."""
    final = check_output_path(path)
    with locked(final):
        tmp = None
        try:
            try:
                tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.tmp-", dir=final.parent))
            except OSError as exc:
                raise ConfigError(f"--out {path}: cannot write in {final.parent}: {exc.strerror or exc}") from None
            yield tmp
            apply_umask(tmp, directory=True)
            old = None
            if final.exists():
                old = Path(tempfile.mkdtemp(prefix=f".{final.name}.old-", dir=final.parent))
                os.replace(final, old / "previous")
            try:
                os.replace(tmp, final)
            except OSError as exc:
                if old is not None:  # put the previous results back
                    os.replace(old / "previous", final)
                if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EACCES, errno.EROFS):
                    raise ConfigError(f"--out {path}: {exc.strerror}") from None
                raise
            tmp = None
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)
        finally:
            if tmp is not None:
                shutil.rmtree(tmp, ignore_errors=True)
