"""Provenance of an output: what produced it, so a result can be traced and reproduced.

:func:`provenance` returns a JSON-ready dict that every output file of the command
line carries (``metrics.json``, ``summary.json``, ``sweep.json``, ``bounds --json``):
the rc3r version, the git commit when rc3r runs from a source checkout (with a
``dirty`` flag), the command line, the Python version and platform, and the versions
of numpy, scipy, numba and pinocchio. The resolved configuration and the seed are
added by the caller, which knows them.
"""
from __future__ import annotations

import datetime as _dt
import platform
import subprocess
import sys
from functools import lru_cache
from pathlib import Path

__all__ = ["provenance", "git_commit"]

_REPO = Path(__file__).resolve().parents[2]


@lru_cache(maxsize=1)
def git_commit() -> dict | None:
    """``{"commit": sha, "dirty": bool}`` of the source checkout rc3r runs from, else None."""
    if not (_REPO / ".git").exists():
        return None
    try:
        sha = subprocess.run(["git", "-C", str(_REPO), "rev-parse", "HEAD"], capture_output=True, text=True,
                             timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(_REPO), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10, check=True).stdout.strip() != ""
    except (OSError, subprocess.SubprocessError):
        return None
    return {"commit": sha, "dirty": dirty}


@lru_cache(maxsize=1)
def _versions() -> dict:
    import numba
    import numpy
    import pinocchio
    import scipy

    from . import __version__

    return {"rc3r": __version__, "python": platform.python_version(), "numpy": numpy.__version__,
            "scipy": scipy.__version__, "numba": numba.__version__, "pinocchio": pinocchio.__version__}


def provenance(argv=None, **extra) -> dict:
    """What produced an output: versions, git commit, command line, time; plus ``extra`` entries.

    Parameters
    ----------
    argv : list of str, optional
        The command line (default ``sys.argv``).
    **extra
        Added as they are (e.g. ``config=...``, ``seed=...``).
    """
    out = {
        "versions": _versions(),
        "git": git_commit(),
        "command": list(sys.argv if argv is None else argv),
        "platform": platform.platform(),
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
    }
    out.update(extra)
    return out
