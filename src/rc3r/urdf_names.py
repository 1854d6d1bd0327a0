"""URDF files by name: example-robot-data's directory, portable ``erd:`` names, and the options that lock joints.

``erd:REL`` names the file REL under the ``robots/`` directory of the installed example-robot-data
(:data:`ERD_PREFIX`): a name that does not change when the virtual environment is recreated or on
another machine, accepted wherever a URDF path is (``--urdf``, a config's ``urdf``) and written by
``rc3r design`` (docs/control.md, "Files a config names"). Nothing here imports Pinocchio.
"""
from __future__ import annotations

import sys
from pathlib import Path

from .errors import UrdfError

__all__ = ["example_robot_data_dir", "ERD_PREFIX", "resolve_erd", "erd_name", "lock_option", "mimic_advice"]


def example_robot_data_dir() -> Path:
    """The ``robots/`` directory of the installed example-robot-data (6.x: files only, no loader).

    Looked for as ``[cmeel.prefix/]share/example-robot-data/robots`` under the
    distribution's install location, ``sys.prefix`` and every ``sys.path`` entry.
    """
    import site

    bases = []
    try:
        from importlib.metadata import distribution

        bases.append(Path(distribution("example-robot-data").locate_file("")))
    except Exception:  # not installed as a distribution: fall back to the prefixes
        pass
    bases += [Path(sys.prefix), *map(Path, site.getsitepackages()), *map(Path, filter(None, sys.path))]
    for base in bases:
        for sub in ("cmeel.prefix/share/example-robot-data/robots", "share/example-robot-data/robots"):
            if (base / sub).is_dir():
                return base / sub
    raise UrdfError("example-robot-data is not installed (no share/example-robot-data/robots under "
                    f"{sys.prefix} or site-packages): pip install example-robot-data")


#: A URDF of example-robot-data named portably: ``erd:<its path under the robots/ directory>``, e.g.
#: ``erd:ur_description/urdf/ur3_robot.urdf``. Accepted wherever a URDF path is (``--urdf``, a config's
#: ``urdf``), and written by ``rc3r design`` into ``design.toml`` in place of the absolute path inside
#: the virtual environment, so that a design survives a new venv or another machine (docs/design.md).
ERD_PREFIX = "erd:"


def resolve_erd(path):
    """The file a URDF name means: ``erd:REL`` is ``example_robot_data_dir() / REL``; any other
    name (a path) is returned unchanged.

    Parameters
    ----------
    path : str or path-like
        ``erd:REL`` or a path.

    Returns
    -------
    pathlib.Path or the argument
        The file of example-robot-data, or ``path`` itself.

    Raises
    ------
    UrdfError
        ``erd:`` with no path after it, or example-robot-data not installed.
    """
    text = str(path) if isinstance(path, (str, Path)) else None
    if text is None or not text.startswith(ERD_PREFIX):
        return path
    rel = text[len(ERD_PREFIX):].strip("/")
    if not rel:
        raise UrdfError(f"URDF {text!r}: give the path under example-robot-data's robots/ directory after "
                        f"'{ERD_PREFIX}' (e.g. {ERD_PREFIX}ur_description/urdf/ur5_robot.urdf)")
    return example_robot_data_dir() / rel


def erd_name(path) -> str | None:
    """The portable name of a URDF path, the inverse of :func:`resolve_erd`.

    Parameters
    ----------
    path : str or path-like
        A file.

    Returns
    -------
    str or None
        ``erd:REL`` if ``path`` is a file of the installed example-robot-data (REL under its robots/
        directory, with ``/``), else None (also when example-robot-data is not installed).
    """
    try:
        root = example_robot_data_dir().resolve()
        rel = Path(path).resolve().relative_to(root)
    except (UrdfError, ValueError, OSError, TypeError):
        return None
    return ERD_PREFIX + rel.as_posix()


def lock_option(joints) -> str:
    """The command-line options that lock ``joints`` at 0.

    Parameters
    ----------
    joints : iterable of str
        Joint names.

    Returns
    -------
    str
        ``--lock a=0 --lock b=0``.
    """
    return " ".join(f"--lock {j}=0" for j in joints)


def mimic_advice(where, free) -> str:
    """The one-line refusal of unlocked ``<mimic>`` joints.

    Parameters
    ----------
    where : str or path-like
        The URDF (the message's first words).
    free : list of (str, str)
        The unlocked mimic joints and the joint each mimics.

    Returns
    -------
    str
        What each mimics and the command-line options that lock them (``--lock J=0`` of every rc3r
        command that reads a URDF; in Python the ``lock={joint: value}`` argument).
    """
    what = ", joint ".join(f"'{j}' mimics '{leader}'" for j, leader in free)
    return f"{where}: joint {what}: lock {'it' if len(free) == 1 else 'them'} with {lock_option(j for j, _ in free)}"
