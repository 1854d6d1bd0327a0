"""Deprecated: the former name of :mod:`rc3r.runspec` (a run as data: :class:`~rc3r.runspec.RunSpec`,
:func:`~rc3r.runspec.build_run`, :func:`~rc3r.runspec.execute`), kept so that ``import rc3r.study`` and
``from rc3r.study import build_run`` keep working; importing it warns (:class:`DeprecationWarning`).
"""
from __future__ import annotations

import warnings

from . import runspec as _runspec
from .runspec import *  # noqa: F401,F403
from .runspec import __all__  # noqa: F401

warnings.warn("rc3r.study is deprecated: import rc3r.runspec (the same names)", DeprecationWarning, stacklevel=2)


def __getattr__(name: str):
    """Every other name of :mod:`rc3r.runspec` (its private helpers too), read from there."""
    return getattr(_runspec, name)
