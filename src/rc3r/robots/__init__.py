"""Robots: the contract (:mod:`~rc3r.robots.base`) and the registry of implementations.

:data:`ROBOTS` maps a name to its class, imported on first use. A robot class
provides, besides the :class:`~rc3r.robots.base.Robot` contract, the classmethods
``nominal()`` (its default parameter set), ``from_urdf(path)``, ``default_box()``
and ``default_trajectory()``. To add a robot: implement the contract in
``rc3r/robots/<name>/`` and add one line here.
"""
from __future__ import annotations

import importlib

from ..errors import ConfigError
from .base import Robot

__all__ = ["Robot", "ROBOTS", "DEFAULT_ROBOT", "robot_class", "load_robot"]

#: name -> "module:Class" (imported lazily).
ROBOTS = {
    "rr3": "rc3r.robots.rr3.robot:RR3",
}

#: The robot the command line uses when none is named: the paper's arm.
DEFAULT_ROBOT = "rr3"


def robot_class(name: str = DEFAULT_ROBOT) -> type[Robot]:
    """The class registered as ``name``."""
    try:
        module, cls = ROBOTS[name].split(":")
    except KeyError:
        raise ConfigError(f"unknown robot {name!r} (known: {', '.join(ROBOTS)})") from None
    return getattr(importlib.import_module(module), cls)


def load_robot(name: str = DEFAULT_ROBOT, urdf=None) -> Robot:
    """The nominal robot ``name``, or the robot of that kind read from ``urdf``."""
    cls = robot_class(name)
    return cls.nominal() if urdf is None else cls.from_urdf(urdf)
