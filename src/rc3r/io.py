"""Atomic file output: results already written are never half-overwritten.

Every file rc3r writes goes to a temporary file in the same directory first and
is then renamed over the target (``os.replace`` is atomic on POSIX), so an
interrupted run leaves either the old file or the new one, never a torn one.
"""
from __future__ import annotations

import json
import os
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .errors import ConfigError

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # Python 3.10: the same parser, as the package tomli
    import tomli as tomllib

__all__ = ["atomic_path", "atomic_write_text", "atomic_write_json", "atomic_savefig", "read_toml", "tomllib", "apply_umask", "floats"]


def floats(x):
    """JSON-ready floats of an array (nested lists keep its shape), or None for None."""
    return None if x is None else np.asarray(x, dtype=float).tolist()


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def apply_umask(path: str | Path, directory: bool = False) -> None:
    """Give ``path`` the mode a plain ``open``/``mkdir`` would: 0666 (0777 for a directory) & ~umask.

    ``tempfile`` creates files 0600 and directories 0700; a result renamed into place must not
    keep those (a regenerated ``urdf/rr3.urdf`` would lose its 0644).
    """
    os.chmod(path, (0o777 if directory else 0o666) & ~_umask())


@contextmanager
def atomic_path(path: str | Path, suffix: str = ""):
    """Yield a temporary path beside ``path``; rename it onto ``path`` on success."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix or path.suffix, dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        apply_umask(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically; return the path."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def atomic_write_json(path: str | Path, obj) -> Path:
    """Write ``obj`` as indented JSON to ``path`` atomically."""
    return atomic_write_text(path, json.dumps(obj, indent=2, allow_nan=True) + "\n")


def atomic_savefig(fig, path: str | Path, **kwargs) -> Path:
    """``fig.savefig`` to ``path`` atomically (PNG by default)."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=kwargs.pop("format", "png"), **kwargs)
    return Path(path)


#: Largest TOML file read (config, parameter and box files are a few kB).
MAX_TEXT_BYTES = 1 << 20


def read_toml(path: str | Path, what: str) -> dict:
    """Parse the TOML file ``path``; one-line :class:`ConfigError` naming ``what`` otherwise.

    ``what`` names the file in messages (``"parameter file"``, ``"config file"`` ...).
    """
    path = Path(path)
    try:
        st = path.stat()
        if stat.S_ISDIR(st.st_mode):
            raise IsADirectoryError
        if not stat.S_ISREG(st.st_mode):  # /dev/zero, a FIFO ...: would be read forever
            raise ConfigError(f"{what} {path} is not a regular file")
        if st.st_size > MAX_TEXT_BYTES:
            raise ConfigError(f"{what} {path} is {st.st_size} bytes (at most {MAX_TEXT_BYTES}): not a config")
        with open(path, "rb") as f:
            text = f.read(MAX_TEXT_BYTES + 1).decode()
    except FileNotFoundError:
        raise ConfigError(f"{what} not found: {path}") from None
    except IsADirectoryError:
        raise ConfigError(f"{what} path is a directory: {path}") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: not a text file: {exc}") from None
    except OSError as exc:  # unreadable, name too long, a loop of links ...
        raise ConfigError(f"{what} {path}: {exc.strerror or exc}") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: malformed TOML: {exc}") from None
