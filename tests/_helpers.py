"""Assertions shared by the test modules (tests/ is on sys.path under pytest's default import mode)."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

#: Relative tolerance of the model identities: float64 rounding of O(100) products of
#: magnitudes <= O(1e3) gives ~1e-13 relative; 1e-9 leaves four orders of margin and still
#: fails any wrong term (the smallest coefficient, |theta_10| = 0.2, times O(1) trig).
TOL = 1e-9


def assert_close(x, ref, tol=TOL):
    """max|x - ref| <= tol * max(1, max|ref|) (the verify-model relative error)."""
    x, ref = np.asarray(x, float), np.asarray(ref, float)
    assert x.shape == ref.shape
    err = np.max(np.abs(x - ref))
    scale = max(1.0, float(np.max(np.abs(ref))))
    assert err <= tol * scale, f"max abs err {err:.3e} > {tol:.0e} * {scale:.3g}"


def named_arm(name: str):
    """A named configuration of the 3R as ``SimpleNamespace(params, model)``.

    * ``table1`` -- the committed ``urdf/rr3.urdf`` (the paper's Table 1: every length 1 m,
      g0 = 9.81), loaded and checked by :func:`rc3r.robots.rr3.urdf.load_arm`;
    * ``unequal`` -- lengths 0.8 / 1.3 / 0.6 m, g0 = 9.80665 m/s^2, off-diagonal inertia and
      off-axis centres of mass: with l2 = 1 a term that drops or squares l2 is invisible, and
      with Table 1's g0 a wrong gravity constant is.
    """
    from types import SimpleNamespace

    from rc3r.robots.rr3.params import ArmParams, LinkParams, physical_issues
    from rc3r.robots.rr3.urdf import REPO_URDF, load_arm, model_from_params

    if name == "table1":
        return load_arm(REPO_URDF)
    if name != "unequal":
        raise KeyError(name)
    links = (
        LinkParams(0.8, 7.0, (0.02, -0.3, 0.05), (0.35, 0.12, 0.30, 0.01, -0.02, 0.015)),
        LinkParams(1.3, 4.5, (-0.6, 0.04, 0.07), (0.30, 0.42, 0.40, 0.02, 0.01, -0.03)),
        LinkParams(0.6, 2.2, (-0.25, -0.03, 0.02), (0.05, 0.09, 0.08, -0.004, 0.006, 0.003)),
    )
    p = ArmParams(links, g0=9.80665, name="unequal")
    assert physical_issues(p) == [], physical_issues(p)
    return SimpleNamespace(params=p, model=model_from_params(p))


#: Names of :func:`named_arm`, the parametrization of the model and regressor identity tests.
NAMED_ARMS = ("table1", "unequal")


# Fixtures over the named configurations, for the identity tests: a test module that imports them
# (``from _helpers import arm, th, pdata``) runs each test on every arm of NAMED_ARMS; they override
# conftest's session-scoped Table 1 fixtures of the same names in that module only.
@pytest.fixture(scope="module", params=NAMED_ARMS)
def arm(request):
    return named_arm(request.param)


@pytest.fixture(scope="module")
def th(arm):
    from rc3r.robots.rr3.params import theta

    return theta(arm.params)


@pytest.fixture(scope="module")
def pdata(arm):
    return arm.model.createData()


def shared_panda_log() -> Path | None:
    """The real Franka Panda log (GPL-3, never in this repository), or None: ``$RC3R_SHARED_DATA``, else a
    ``shared/data`` folder beside the repository, its parent or its grandparent, holding
    ``panda_gaz/exciting_traj_1.npz``. Tests that need it skip with a reason without it."""
    repo = Path(__file__).resolve().parents[1]
    roots = [Path(os.environ["RC3R_SHARED_DATA"])] if os.environ.get("RC3R_SHARED_DATA") else []
    roots += [up / "shared" / "data" for up in repo.parents[:3]]
    for root in roots:
        if (root / "panda_gaz" / "exciting_traj_1.npz").is_file():
            return root / "panda_gaz" / "exciting_traj_1.npz"
    return None
