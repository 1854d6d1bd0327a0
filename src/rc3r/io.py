"""Atomic file output, TOML reading, and the edges where files enter rc3r.

Every file rc3r writes goes to a temporary file in the same directory first and
is then renamed over the target (``os.replace`` is atomic on POSIX), so an
interrupted run leaves either the old file or the new one, never a torn one. Only a
regular file (or nothing) is ever replaced: a directory, a device, a FIFO or a
symbolic link at the target is refused (:func:`file_target_problem`). JSON is
written strict (non-finite floats as ``null``). :func:`native_stderr` keeps what C++
libraries (urdfdom, under Pinocchio) print on file descriptor 2 out of the user's
terminal, so a refusal stays one line; :data:`MAX_MAGNITUDE` bounds the numbers read
from URDF, parameter and box files.
"""
from __future__ import annotations

import json
import math
import os
import stat
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .errors import ConfigError

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # Python 3.10: the same parser, as the package tomli
    import tomli as tomllib

__all__ = ["atomic_path", "atomic_write_text", "atomic_write_json", "atomic_savefig", "read_toml", "tomllib",
           "apply_umask", "floats", "strict_json", "file_target_problem", "native_stderr", "NativeStderr",
           "MAX_MAGNITUDE", "MAGNITUDE_NOTE", "too_large", "number_problem", "require_file", "PATH_KEYS",
           "read_config", "resolve_config_paths", "portable_config"]

#: Largest magnitude of a number read from a URDF (origins, axes, masses, inertias), a parameter
#: file or a box file, in SI units. Beyond it products and squares of the dynamics (up to the 4th
#: power of a length times a mass, ~1e60) would approach double-precision overflow (1.8e308) in
#: the bounds and the closed forms; no robot comes near it (a 1e12 kg mass, a 1e12 m link).
MAX_MAGNITUDE = 1e12

#: How messages state the bound on numbers read from files.
MAGNITUDE_NOTE = f" (finite, magnitude <= {MAX_MAGNITUDE:g})"


def too_large(x) -> bool:
    """Whether the number ``x`` is not finite or beyond :data:`MAX_MAGNITUDE` in magnitude."""
    return not abs(float(x)) <= MAX_MAGNITUDE


def number_problem(text: str, count: int | None = None, bounded: bool = True) -> str | None:
    """Why the attribute ``text`` is not ``count`` (any number if None) whitespace-separated numbers,
    finite and within :data:`MAX_MAGNITUDE` when ``bounded``; None if it is.

    >>> number_problem("0 1e300 0", 3)
    'beyond 1e+12 in magnitude'
    """
    try:
        values = [float(x) for x in text.split()]
    except ValueError:
        return "not a finite number"
    if count is not None and len(values) != count:
        return f"not {count} numbers"
    if bounded and any(not math.isfinite(x) for x in values):
        return "not a finite number"
    if bounded and any(too_large(x) for x in values):
        return f"beyond {MAX_MAGNITUDE:g} in magnitude"
    return None


def require_file(path: str | Path, what: str, error=ConfigError) -> Path:
    """``path`` as a Path if it names a regular file; else raise ``error`` (one line): ``what`` not
    found, not a file (a directory, a device), or not usable (a name too long, a file on the way)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise error(f"{what} not found: {path}") from None
    except OSError as exc:
        raise error(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{what} path is not a file: {path}")
    return Path(path)


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


def file_target_problem(path: str | Path) -> str | None:
    """Why a file cannot be (re)written at ``path`` by :func:`atomic_path`, or None if it can.

    Refused: an empty path, a directory (``/`` included), a symbolic link, a device, FIFO or
    socket (renaming a regular file over ``/dev/null`` as root would destroy the device), and a
    path the system cannot name (too long, a file used as a directory ...).
    """
    if str(path).strip() in ("", "."):
        return "is empty; give a file name"
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return None
    except OSError as exc:  # ENAMETOOLONG, ENOTDIR, ELOOP, EACCES
        return f"cannot be used: {exc.strerror or exc}"
    if stat.S_ISLNK(st.st_mode):
        return "is a symbolic link; refusing to replace it (give the file it points to, or another name)"
    if stat.S_ISDIR(st.st_mode):
        return "is a directory; give a file name"
    if not stat.S_ISREG(st.st_mode):
        return "is not a regular file (a device, FIFO or socket); refusing to replace it"
    return None


@contextmanager
def atomic_path(path: str | Path, suffix: str = ""):
    """Yield a temporary path beside ``path``; rename it onto ``path`` on success.

    Raises
    ------
    ConfigError
        ``path`` is not a regular file or a new name (:func:`file_target_problem`), or its
        directory cannot be created or written (name too long, read-only, not a directory).
    """
    problem = file_target_problem(path)
    if problem:
        raise ConfigError(f"output {path} {problem}")
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix or path.suffix, dir=path.parent)
    except OSError as exc:
        raise ConfigError(f"cannot write {path}: {exc.strerror or exc}") from None
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


def strict_json(obj):
    """``obj`` with every non-finite float (NaN, +-inf) replaced by None: JSON without ``NaN`` or
    ``Infinity``, which are not JSON and which strict parsers (``jq``, browsers) refuse."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: strict_json(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [strict_json(v) for v in obj]
    return obj


def atomic_write_json(path: str | Path, obj) -> Path:
    """Write ``obj`` as indented strict JSON to ``path`` atomically (non-finite floats as ``null``)."""
    return atomic_write_text(path, json.dumps(strict_json(obj), indent=2, allow_nan=False) + "\n")


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


class NativeStderr:
    """What native code wrote on file descriptor 2 inside :func:`native_stderr`.

    Attributes
    ----------
    text : str
        Everything written (at most 64 kB kept), available after the block.
    """

    text: str = ""

    @property
    def first_line(self) -> str:
        """The first non-blank line, without urdfdom's ``Error:`` prefix, cut after its first sentence
        (urdfdom's first line goes on with advice; no final full stop) and at 200 characters; ``""``
        if nothing was written."""
        line = next((ln for ln in self.text.splitlines() if ln.strip()), "")
        line = " ".join(line.split())
        for prefix in ("Error:", "error:", "Warning:"):
            if line.startswith(prefix):
                line = line[len(prefix):].strip()
        line = line.partition(". ")[0].rstrip(".")
        return line if len(line) <= 200 else line[:197] + "..."

    def folded(self, message: str, detail: str = "") -> str:
        """``message: <first line> (detail)``, or ``message: detail`` when nothing was caught."""
        if not self.first_line:
            return f"{message}: {detail}" if detail else message
        return f"{message}: {self.first_line}" + (f" ({detail})" if detail else "")


@contextmanager
def native_stderr():
    """Catch what C/C++ code (urdfdom's ``Error: ...`` lines) writes on file descriptor 2 while the
    block runs; yield a :class:`NativeStderr` whose ``text`` holds it afterwards.

    File descriptor 2 is pointed at an anonymous temporary file with ``dup2`` and restored on
    exit, whatever happens in the block (Python's ``sys.stderr`` is flushed first so nothing of it
    is caught by mistake). The redirection is process-wide: a thread writing to fd 2 meanwhile is
    caught too (rc3r parses URDFs in the main thread). Without a file descriptor 2 (closed) or a
    place for the temporary file, the block runs as it is.
    """
    cap = NativeStderr()
    try:
        sys.stderr.flush()
    except (AttributeError, OSError, ValueError):
        pass
    sink = saved = None
    try:
        sink = tempfile.TemporaryFile()
        saved = os.dup(2)
    except OSError:
        if sink is not None:
            sink.close()
        sink = None
    if sink is None:
        yield cap
        return
    try:
        os.dup2(sink.fileno(), 2)
        try:
            yield cap
        finally:
            os.dup2(saved, 2)
            sink.seek(0)
            cap.text = sink.read(1 << 16).decode(errors="replace")
    finally:
        os.close(saved)
        sink.close()


#: The keys of a run configuration that name files, as ``(table, key)`` (``""``: the top level); the
#: plant's ``spec`` only when it names a URDF (ends in ``.urdf``).
PATH_KEYS = (("", "urdf"), ("", "box"), ("", "bounds"), ("plant", "urdf"), ("plant", "box"), ("plant", "spec"))


def _path_entries(cfg: dict):
    """``(table dict, key, value)`` of every file the configuration ``cfg`` names (:data:`PATH_KEYS`)."""
    for table, key in PATH_KEYS:
        where = cfg if table == "" else cfg.get(table)
        value = where.get(key) if isinstance(where, dict) else None
        if isinstance(value, str) and value and (key != "spec" or value.endswith(".urdf")):
            yield where, key, value


def resolve_config_paths(cfg: dict, base) -> dict:
    """The files a run configuration names, read relative to the configuration file.

    Parameters
    ----------
    cfg : dict
        A run configuration (the TOML's tables).
    base : path-like
        The directory of the configuration file.

    Returns
    -------
    dict
        A copy of ``cfg`` whose relative file names (:data:`PATH_KEYS`) are ``base / name``, unless
        only ``name`` exists from the working directory (configurations written before names were
        relative to their file). Absolute names and ``erd:`` names
        (:data:`rc3r.urdf_names.ERD_PREFIX`, resolved where the URDF is read) are kept.
    """
    import copy

    from .urdf_names import ERD_PREFIX

    out = copy.deepcopy(cfg)
    for where, key, value in _path_entries(out):
        if value.startswith(ERD_PREFIX) or Path(value).is_absolute():
            continue
        beside = Path(os.path.abspath(Path(base) / value))  # "../arm.urdf" without the ".."
        if beside.exists() or not Path(value).exists():
            where[key] = str(beside)
    return out


def portable_config(cfg: dict, base) -> dict:
    """The files a run configuration names, written portably for a configuration file in ``base``.

    Parameters
    ----------
    cfg : dict
        A run configuration whose file names are absolute or relative to the working directory.
    base : path-like
        The directory the configuration file is written to.

    Returns
    -------
    dict
        A copy of ``cfg`` naming a URDF of example-robot-data ``erd:REL``
        (:func:`rc3r.urdf_names.erd_name`) and any other file relative to ``base``
        (``os.path.relpath``); :func:`resolve_config_paths` reads them back.
    """
    import copy

    from .urdf_names import ERD_PREFIX, erd_name

    out = copy.deepcopy(cfg)
    base = Path(base).resolve()
    for where, key, value in _path_entries(out):
        if value.startswith(ERD_PREFIX):
            continue
        name = erd_name(value) if key in ("urdf", "spec") else None
        where[key] = name or Path(os.path.relpath(Path(value).resolve(), base)).as_posix()
    return out


def read_config(path) -> dict:
    """Read a run configuration TOML (``--config``).

    Parameters
    ----------
    path : path-like
        The TOML file.

    Returns
    -------
    dict
        Its tables, file names resolved relative to the file (:func:`resolve_config_paths`).

    Raises
    ------
    rc3r.errors.ConfigError
        A missing, unreadable or malformed file (:func:`read_toml`).
    """
    return resolve_config_paths(read_toml(path, "config file"), Path(path).parent)
