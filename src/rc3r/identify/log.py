r"""Logs of a moving arm: loading and validation of CSV and NPZ files.

A log is what an experiment records at (about) a fixed rate: time stamps ``t`` [s],
joint positions ``q`` [rad or m], optionally velocities ``qd`` and the joint torques
``tau`` [N m or N] the drives applied. Accelerations are never logged (they are
differentiated, :mod:`rc3r.identify.filtering`).

Formats
    * **CSV** with a header line naming the columns ``t, q1..qn, tau1..taun`` and
      optionally ``qd1..qdn`` (any order of the columns, spaces around names
      allowed, nothing else); one row per sample.
    * **NPZ** (``numpy.savez``) with arrays ``t`` (N,), ``q`` (N, n), ``tau``
      (N, n) and optionally ``qd`` (N, n).

Validation (:func:`load_log`): every refusal is one :class:`~rc3r.errors.ConfigError`
line naming the file and what is wrong -- missing or unreadable file, unknown or
duplicate columns, a number of joints other than the robot's, a row with the wrong
number of fields, a field that is not a number, NaN or infinite values (with the
row and column), time stamps that do not strictly increase, fewer than
:data:`MIN_SAMPLES` samples; a corrupt NPZ (a bad zip, a bad CRC, a truncated array) or one whose
arrays would take more than :data:`MAX_NPZ_BYTES` once unpacked; a CSV with a header and no rows.

Hostile numbers are refused here too, so that what follows (resampling on a uniform grid at the
median step, least squares on squares of the torques) can neither overflow nor allocate without
bound:

* a value of ``q``, ``qd``, ``tau`` or ``t`` beyond :data:`rc3r.io.MAX_MAGNITUDE` (1e12) in
  magnitude: squares of 1e300 overflow double precision;
* a time span (last stamp minus first) over :data:`MAX_SPAN_S` (1e6 s, 11.6 days);
* a gap between two samples over :data:`MAX_GAP_STEPS` (100) times the median step: a spline
  through a hole of a hundred samples invents the motion, and a gap of 1e6 s in a 1 kHz log would
  make a grid of 1e9 points (7.4 GiB);
* a span over :data:`MAX_GRID_RATIO` (4) times what the samples cover at the median step (the
  uniform grid would have more than 4 N points: most of the log is gaps).
"""
from __future__ import annotations

import csv
import hashlib
import re
import stat
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..io import MAX_MAGNITUDE

__all__ = ["Log", "load_log", "save_log", "MIN_SAMPLES", "MAX_SPAN_S", "MAX_GAP_STEPS", "MAX_GRID_RATIO",
           "MAX_NPZ_BYTES"]

#: Fewest samples a log may have (a fit needs many more than it has unknowns, too).
MIN_SAMPLES = 100

#: Longest time span of a log [s] (11.6 days; a 1 kHz log of it would be 1e9 samples).
MAX_SPAN_S = 1e6

#: Longest gap between two samples, in median time steps (the log is resampled on a uniform grid at
#: the median step, by splines: a longer hole would be invented motion).
MAX_GAP_STEPS = 100.0

#: Largest ratio of the uniform grid's points (span / median step + 1) to the samples.
MAX_GRID_RATIO = 4.0

#: Largest total size of an NPZ log's arrays once unpacked [bytes] (a zip bomb is refused unread).
MAX_NPZ_BYTES = 2 ** 31

_COLUMN = re.compile(r"^(t|q|qd|tau)(\d*)$")


@dataclass(frozen=True, eq=False)
class Log:
    """A validated log.

    Attributes
    ----------
    t : ndarray (N,)
        Strictly increasing time stamps [s].
    q, tau : ndarray (N, n)
        Positions and torques.
    qd : ndarray (N, n) or None
        Logged velocities, if any.
    source : str
        The file it was read from (or ``"<memory>"``).
    sha256 : str
        Digest of the file's bytes (empty for a log built in memory).
    """

    t: np.ndarray
    q: np.ndarray
    tau: np.ndarray
    qd: np.ndarray | None = None
    source: str = "<memory>"
    sha256: str = ""

    @property
    def n(self) -> int:
        """Number of joints."""
        return int(self.q.shape[1])

    @property
    def samples(self) -> int:
        """Number of samples N."""
        return int(self.t.size)

    def describe(self) -> dict:
        """JSON-ready summary: source, digest, samples, duration, time-step statistics [s]."""
        dt = np.diff(self.t)
        return {"source": self.source, "sha256": self.sha256, "samples": self.samples, "n": self.n,
                "duration_s": float(self.t[-1] - self.t[0]), "velocities": "logged" if self.qd is not None
                else "differentiated", "dt_min_s": float(dt.min()), "dt_median_s": float(np.median(dt)),
                "dt_max_s": float(dt.max())}

    def slice(self, mask) -> "Log":
        """The samples where ``mask`` (N,) is true, as a log of the same source."""
        return Log(self.t[mask], self.q[mask], self.tau[mask], None if self.qd is None else self.qd[mask],
                   self.source, self.sha256)


def _check(path: str, t, q, qd, tau, n: int | None) -> Log:
    """Shapes, finiteness, time order and length of the arrays of a log; a :class:`Log`."""
    if t.ndim != 1:
        raise ConfigError(f"log {path}: t must be one column, got shape {t.shape}")
    for name, x in (("q", q), ("tau", tau), ("qd", qd)):
        if x is None:
            continue
        if x.ndim != 2 or x.shape[0] != t.size:
            raise ConfigError(f"log {path}: {name} must have shape ({t.size}, n) like t, got {x.shape}")
    if tau.shape[1] != q.shape[1] or (qd is not None and qd.shape[1] != q.shape[1]):
        raise ConfigError(f"log {path}: {q.shape[1]} position columns but {tau.shape[1]} torque"
                          + ("" if qd is None else f" and {qd.shape[1]} velocity") + " columns")
    if n is not None and q.shape[1] != n:
        raise ConfigError(f"log {path} has {q.shape[1]} joints (q1..q{q.shape[1]}), the robot has {n}")
    for name, x in (("t", t[:, None]), ("q", q), ("qd", qd), ("tau", tau)):
        if x is None:
            continue
        bad = np.argwhere(~np.isfinite(x))
        if bad.size:
            row, col = bad[0]
            what = "t" if name == "t" else f"{name}{col + 1}"
            raise ConfigError(f"log {path}: {what} is {x[row, col]} at sample {row + 1} (NaN or infinite; "
                              f"{len(bad)} such values)")
    for name, x in (("t", t[:, None]), ("q", q), ("qd", qd), ("tau", tau)):
        if x is None:
            continue
        big = np.argwhere(np.abs(x) > MAX_MAGNITUDE)
        if big.size:
            row, col = big[0]
            what = "t" if name == "t" else f"{name}{col + 1}"
            raise ConfigError(f"log {path}: {what} is {x[row, col]:g} at sample {row + 1}, beyond "
                              f"{MAX_MAGNITUDE:g} in magnitude (SI units; {len(big)} such values)")
    if t.size < MIN_SAMPLES:
        raise ConfigError(f"log {path} has {t.size} samples, at least {MIN_SAMPLES} are needed")
    dt = np.diff(t)
    if np.any(dt <= 0):
        k = int(np.argmax(dt <= 0))
        raise ConfigError(f"log {path}: time does not increase at sample {k + 2} (t = {t[k + 1]!r} after "
                          f"{t[k]!r})")
    span = float(t[-1] - t[0])
    if span > MAX_SPAN_S:
        raise ConfigError(f"log {path} spans {span:.4g} s (from t = {t[0]:.6g} to {t[-1]:.6g} s), more than "
                          f"{MAX_SPAN_S:g} s")
    step = float(np.median(dt))
    k = int(np.argmax(dt))
    if dt[k] > MAX_GAP_STEPS * step:
        raise ConfigError(f"log {path}: a gap of {dt[k]:.4g} s between samples {k + 1} and {k + 2} (t = {t[k]:.6g} "
                          f"to {t[k + 1]:.6g} s) is {dt[k] / step:.3g} median steps ({step:.3g} s); at most "
                          f"{MAX_GAP_STEPS:g} are bridged: split the log")
    if span / step + 1 > MAX_GRID_RATIO * t.size:
        raise ConfigError(f"log {path}: {t.size} samples over {span:.4g} s at a median step of {step:.3g} s: "
                          f"gaps fill most of it (a uniform grid at that step has {span / step + 1:.3g} points, "
                          f"more than {MAX_GRID_RATIO:g} x the samples)")
    return Log(t, q, tau, qd, path)


def _read_bytes(path: Path) -> bytes:
    try:
        st = path.stat()
        if stat.S_ISDIR(st.st_mode):
            raise ConfigError(f"log path is a directory: {path}")
        if not stat.S_ISREG(st.st_mode):
            raise ConfigError(f"log {path} is not a regular file")
        return path.read_bytes()
    except FileNotFoundError:
        raise ConfigError(f"log not found: {path}") from None
    except OSError as exc:
        raise ConfigError(f"log {path}: {exc.strerror or exc}") from None


def _columns(path: str, header: list[str]) -> dict:
    """``{"t": i, "q": [i1..in], "qd": [...] or None, "tau": [...]}`` from the header names."""
    found: dict = {"t": [], "q": {}, "qd": {}, "tau": {}}
    for i, raw in enumerate(header):
        name = raw.strip()
        m = _COLUMN.match(name)
        if not m or (m.group(1) == "t") != (m.group(2) == "") or m.group(2).startswith("0"):
            raise ConfigError(f"log {path}: unknown column {name!r} (expected t, q1..qn, tau1..taun, "
                              "optionally qd1..qdn)")
        kind, k = m.group(1), m.group(2)
        if kind == "t":
            found["t"].append(i)
            continue
        if int(k) in found[kind]:
            raise ConfigError(f"log {path}: column {name!r} appears twice")
        found[kind][int(k)] = i
    if len(found["t"]) != 1:
        raise ConfigError(f"log {path}: needs exactly one column t, found {len(found['t'])}")
    out = {"t": found["t"][0]}
    for kind in ("q", "qd", "tau"):
        ks = sorted(found[kind])
        if kind == "qd" and not ks:
            out[kind] = None
            continue
        if not ks or ks != list(range(1, len(ks) + 1)):
            raise ConfigError(f"log {path}: {kind} columns must be {kind}1..{kind}n, found "
                              f"{', '.join(f'{kind}{k}' for k in ks) or 'none'}")
        out[kind] = [found[kind][k] for k in ks]
    return out


def _load_csv(path: Path, data: bytes, n: int | None) -> Log:
    try:
        text = data.decode()
    except UnicodeDecodeError as exc:
        raise ConfigError(f"log {path}: not a text file: {exc}") from None
    lines = text.splitlines()
    if not lines or not lines[0].strip():
        raise ConfigError(f"log {path} is empty (expected a header t, q1..qn, tau1..taun)")
    header = next(csv.reader([lines[0]]))
    cols = _columns(str(path), header)
    width = len(header)
    if not any(line.strip() for line in lines[1:]):  # numpy would warn "input contained no data"
        raise ConfigError(f"log {path} has a header and no rows (0 samples, at least {MIN_SAMPLES} are needed)")
    try:
        table = np.loadtxt(lines[1:], delimiter=",", ndmin=2, dtype=float)
    except ValueError:
        table = None
    if table is None or (table.size and table.shape[1] != width):
        for k, row in enumerate(csv.reader(lines[1:])):
            if len(row) != width:
                raise ConfigError(f"log {path}: row {k + 2} has {len(row)} fields, the header has {width}")
            for name, field in zip(header, row):
                try:
                    float(field)
                except ValueError:
                    raise ConfigError(f"log {path}: row {k + 2}, column {name.strip()}: {field!r} is not a "
                                      "number") from None
        raise ConfigError(f"log {path}: cannot read the rows as numbers")  # pragma: no cover - found above
    if table.size == 0:
        table = np.zeros((0, width))
    def pick(idx):
        return None if idx is None else np.ascontiguousarray(table[:, idx])

    return _check(str(path), table[:, cols["t"]].copy(), pick(cols["q"]), pick(cols["qd"]), pick(cols["tau"]), n)


def _load_npz(path: Path, n: int | None) -> Log:
    try:
        with zipfile.ZipFile(path) as zf:
            unpacked = sum(info.file_size for info in zf.infolist())
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as exc:
        raise ConfigError(f"log {path}: not a readable NPZ file: {exc}") from None
    if unpacked > MAX_NPZ_BYTES:
        raise ConfigError(f"log {path}: its arrays would take {unpacked / 2 ** 30:.3g} GiB unpacked, more than "
                          f"{MAX_NPZ_BYTES / 2 ** 30:g} GiB")
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: np.asarray(z[k]) for k in z.files}
    except (ValueError, OSError, EOFError, KeyError, zipfile.BadZipFile, zlib.error, MemoryError) as exc:
        # a bad CRC or a truncated member (BadZipFile, zlib.error), a corrupt .npy header (ValueError)
        raise ConfigError(f"log {path}: not a readable NPZ file: {type(exc).__name__}: {exc}") from None
    unknown = sorted(set(arrays) - {"t", "q", "qd", "tau"})
    missing = [k for k in ("t", "q", "tau") if k not in arrays]
    if unknown or missing:
        raise ConfigError(f"log {path}: NPZ needs arrays t, q, tau (qd optional); "
                          + (f"missing {', '.join(missing)}" if missing else f"unknown {', '.join(unknown)}"))
    try:
        t, q, tau = (np.asarray(arrays[k], dtype=float) for k in ("t", "q", "tau"))
        qd = None if "qd" not in arrays else np.asarray(arrays["qd"], dtype=float)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"log {path}: arrays must be numbers: {exc}") from None
    return _check(str(path), t, q, qd, tau, n)


def load_log(path, n: int | None = None) -> Log:
    """Read and validate a CSV or NPZ log (module docstring: formats and refusals).

    Parameters
    ----------
    path : str or Path
        ``.npz`` is read as NPZ, anything else as CSV.
    n : int, optional
        The robot's number of joints; a log with another number is refused.

    Returns
    -------
    Log
        With ``source`` and ``sha256`` of the file.
    """
    path = Path(path)
    data = _read_bytes(path)
    log = _load_npz(path, n) if path.suffix.lower() == ".npz" else _load_csv(path, data, n)
    return Log(log.t, log.q, log.tau, log.qd, str(path), hashlib.sha256(data).hexdigest())


def save_log(log: Log, path) -> Path:
    """Write ``log`` as CSV (header ``t, q1..qn[, qd1..qdn], tau1..taun``, 17 significant digits) or NPZ.

    Written atomically (:mod:`rc3r.io`); the format follows the suffix as in :func:`load_log`.
    """
    from ..io import atomic_path, atomic_write_text

    path = Path(path)
    if path.suffix.lower() == ".npz":
        with atomic_path(path) as tmp:
            arrays = {"t": log.t, "q": log.q, "tau": log.tau, **({} if log.qd is None else {"qd": log.qd})}
            with open(tmp, "wb") as f:
                np.savez(f, **arrays)
        return path
    n = log.n
    names = ["t", *(f"q{i}" for i in range(1, n + 1)), *([] if log.qd is None else [f"qd{i}" for i in range(1, n + 1)]),
             *(f"tau{i}" for i in range(1, n + 1))]
    table = np.column_stack([log.t, log.q, *([] if log.qd is None else [log.qd]), log.tau])
    rows = "\n".join(",".join(f"{x:.17g}" for x in row) for row in table)
    return atomic_write_text(path, ",".join(names) + "\n" + rows + "\n")
