"""A run configuration describes the arm (urdf, lock) and the plant's effects ([plant]), so campaigns
(which pass configurations to every job) get them too: friction ranges are drawn with each plant's
own seed."""
from __future__ import annotations

import numpy as np
import pytest

import rc3r
from rc3r.errors import ConfigError
from rc3r.robots.pinocchio import example_robot_data_dir

Z1 = str(example_robot_data_dir() / "z1_description/urdf/z1.urdf")


def test_config_names_the_arm_and_its_plant():
    cfg = {"urdf": Z1, "lock": {"jointGripper": 0.0}, "tolerance": 0.05,
           "plant": {"friction": "urdf", "torque_limit": "urdf", "noise": "1e-4:0", "delay": 1},
           "simulation": {"rate": 1000.0, "duration": 0.05}}
    spec = rc3r.build_run(controller="fbl", config=cfg)
    assert spec.true_rigid.n == 6 and spec.controller_model.locked == {"jointGripper": 0.0}
    assert [e.name for e in spec.true_plant.effects] == ["friction", "saturation", "limits"]
    assert spec.loop.delay == 1 and spec.loop.noise_q.tolist() == [1e-4] * 6 and spec.tolerance == 0.05
    res, m = rc3r.execute(spec)
    assert m["tolerance"] == 0.05 and m["loop"]["delay"] == 1


def test_friction_ranges_follow_the_plant_seed():
    """random:<seed> plants draw their friction from the same seed: equal seeds, equal plants."""
    cfg = {"plant": {"friction": {"viscous": {"lo": 0.5, "hi": 1.5}}}}
    a, b, c = (rc3r.build_run(controller="fbl", perturbed=True, plant=f"random:{k}", config=cfg)
               for k in (3, 3, 4))
    fa, fb, fc = (s.true_plant.effect("friction").viscous for s in (a, b, c))
    np.testing.assert_array_equal(fa, fb)
    assert not np.array_equal(fa, fc) and np.all((fa >= 0.5) & (fa <= 1.5))


def test_bad_lock_table():
    with pytest.raises(ConfigError, match="lock must be a table"):
        rc3r.build_run(controller="fbl", config={"urdf": Z1, "lock": {"jointGripper": "zero"}})
