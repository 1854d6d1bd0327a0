"""Shared fixtures: a seeded RNG and the Table 1 arm loaded from the committed URDF."""
from __future__ import annotations

import os

import numpy as np
import pytest

os.environ.setdefault("MPLBACKEND", "Agg")
# The suite compiles what it runs, so that "auto" picks the same engine whatever ran before; the cold
# start (a short run on the python engine while numba's cache is cold) is tested in subprocesses
# that unset this (tests/test_cold_start.py).
os.environ["RC3R_COLD_START"] = "compile"


def _plan_every_law_and_effect():
    """The suite runs every law on many plants: one compiled instance of all registered laws and effects per
    kernel supply (rc3r.simulate._fast.plan), not one per law and effect set as a single run takes
    (tests/test_engine_instances.py tests that choice, with the plan lifted)."""
    from rc3r.plants import EFFECTS
    from rc3r.simulate import _fast
    from rc3r.simulate.engines import _dispatch, _effects

    _fast.plan([c.code for c in _dispatch.compiled_laws()], [c.code for c in _effects.compiled_effects(EFFECTS)])


_plan_every_law_and_effect()

#: One seed for the whole suite; change it to re-roll every random test.
SEED = 20241122


@pytest.fixture
def rng():
    """A fresh, seeded numpy Generator per test (reproducible, order-independent)."""
    return np.random.default_rng(SEED)


@pytest.fixture(scope="session")
def arm():
    """The committed ``urdf/rr3.urdf`` loaded and checked (params + Pinocchio model)."""
    from rc3r.robots.rr3.urdf import REPO_URDF, load_arm

    return load_arm(REPO_URDF)


@pytest.fixture(scope="session")
def table1():
    from rc3r.robots.rr3.params import table1

    return table1()


@pytest.fixture(scope="session")
def th(arm):
    """theta (15,) of the committed URDF (Table 1)."""
    from rc3r.robots.rr3.params import theta

    return theta(arm.params)


@pytest.fixture(scope="session")
def pdata(arm):
    """A Pinocchio Data for the committed URDF's model."""
    return arm.model.createData()


@pytest.fixture(scope="session")
def ur5():
    """The UR5 of example-robot-data as a PinocchioRobot (36 base parameters)."""
    from rc3r.robots.pinocchio import PinocchioRobot

    return PinocchioRobot.named("ur5")


@pytest.fixture(scope="session")
def panda():
    """The Panda arm of example-robot-data, fingers locked (43 base parameters)."""
    from rc3r.robots.pinocchio import PinocchioRobot

    return PinocchioRobot.named("panda")
