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

__all__ = ["Robot", "ROBOTS", "DEFAULT_ROBOT", "robot_class", "load_robot", "load_urdf_robot"]

#: name -> "module:Class" (imported lazily).
ROBOTS = {
    "rr3": "rc3r.robots.rr3.robot:RR3",
    "ur5": "rc3r.robots.pinocchio:PinocchioRobot",
    "panda": "rc3r.robots.pinocchio:PinocchioRobot",
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
    """The nominal robot ``name``, or the robot of that kind read from ``urdf``.

    A class that serves several names (:class:`~rc3r.robots.pinocchio.PinocchioRobot`) gets
    the name: ``cls.nominal(name)``.
    """
    cls = robot_class(name)
    if urdf is not None:
        return cls.from_urdf(urdf)
    return cls.nominal(name) if cls.name != name else cls.nominal()


def load_urdf_robot(path, lock: dict | None = None) -> Robot:
    """Any serial URDF arm, as a :class:`~rc3r.robots.pinocchio.PinocchioRobot` (joints of ``lock``,
    ``{name: value}``, fixed at their value)."""
    return robot_class("ur5").from_urdf(path, lock=lock or None)
