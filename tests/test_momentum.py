"""The momentum map against the closed form, finite differences and conservation laws."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff

import reference as ref
import urdfs


def test_map_equals_closed_form(planar_robot):
    mmap = ff.MomentumMap(planar_robot)
    rng = np.random.default_rng(1)
    for q in rng.uniform(-4.0, 4.0, size=(50, 2)):
        f1 = mmap.f1(q)
        assert f1[:2] == pytest.approx(np.zeros((2, 2)), abs=1e-14)
        assert f1[2] == pytest.approx(ref.gains(*q), abs=1e-10)


def test_base_linear_velocity_keeps_cm_fixed(planar_robot):
    """Rows 0:3 of the map move the base so that the CM velocity is zero (finite differences)."""
    mmap = ff.MomentumMap(planar_robot)
    model, data = planar_robot.model, planar_robot.model.createData()
    rng = np.random.default_rng(2)
    for _ in range(10):
        joints, rates = rng.uniform(-3, 3, 2), rng.uniform(-1, 1, 2)
        quat = ff.quat_from_zyx(*rng.uniform(-1, 1, 3))
        q = mmap.configuration(joints, quat)
        v = mmap.velocity(joints, rates)
        dt = 1e-6
        c_plus = pin.centerOfMass(model, data, pin.integrate(model, q, v * dt))
        c_minus = pin.centerOfMass(model, data, pin.integrate(model, q, -v * dt))
        assert np.linalg.norm((c_plus - c_minus) / (2 * dt)) < 1e-8
        assert np.linalg.norm(mmap.momentum(q, v)) < 1e-10


def test_cm_at_origin_and_end_effector_closed_form(planar_robot):
    mmap = ff.MomentumMap(planar_robot)
    model, data = planar_robot.model, planar_robot.model.createData()
    rng = np.random.default_rng(3)
    for yaw, q1, q2 in rng.uniform(-3, 3, size=(20, 3)):
        quat = ff.quat_from_zyx(yaw)
        q = mmap.configuration(np.array([q1, q2]), quat)
        assert np.linalg.norm(pin.centerOfMass(model, data, q)) < 1e-14
        ee = mmap.end_effector_pose(np.array([q1, q2]), quat).translation
        assert ee[:2] == pytest.approx(ref.end_effector(yaw, q1, q2), abs=1e-12)
        assert ee[2] == pytest.approx(0.0, abs=1e-14)


def test_momentum_stays_zero_along_the_plan(worked_plan, planar_robot):
    mmap = ff.MomentumMap(planar_robot)
    s = worked_plan.samples
    worst = 0.0
    for q, qd, quat in zip(s.q, s.qd, s.base_quaternion_xyzw, strict=True):
        config = mmap.configuration(np.array(q), np.array(quat))
        worst = max(worst, np.linalg.norm(mmap.momentum(config, mmap.velocity(q, np.array(qd)))))
    assert worst < 1e-9


def test_sampled_base_motion_is_consistent_with_the_map(worked_plan, planar_robot):
    """The sampled base position's time derivative equals the mapped base velocity."""
    mmap = ff.MomentumMap(planar_robot)
    s = worked_plan.samples
    t = np.array(s.t)
    pos = np.array(s.base_position)
    k = 100
    fd = (pos[k + 1] - pos[k - 1]) / (t[k + 1] - t[k - 1])
    twist = mmap.base_twist_map(np.array(s.q[k])) @ np.array(s.qd[k])
    rot = ff.physics.attitude.quat_to_matrix(np.array(s.base_quaternion_xyzw[k]))
    assert fd == pytest.approx(rot @ twist[:3], abs=1e-4)


def test_spatial_robot_map_is_not_planar(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(urdfs.spatial_arm())
    robot = ff.load_robot(path)
    assert not ff.is_planar(robot)
    f1 = ff.MomentumMap(robot).f1(np.array([0.3, -0.4, 0.5]))
    assert np.abs(f1[:2]).max() > 1e-3


def test_prismatic_planar_robot_is_planar(tmp_path):
    path = tmp_path / "p.urdf"
    path.write_text(urdfs.slider_arm())
    robot = ff.load_robot(path)
    assert [j.kind for j in robot.joints] == ["prismatic", "revolute"]
    assert ff.is_planar(robot)
    assert math.isclose(robot.total_mass, 57.0)


def test_planar_bounds_contain_every_monotone_motion(tmp_path):
    """Three-joint planar arm with offsets: yaw changes of monotone paths lie in the interval."""
    body = urdfs.BASE.format(mass=80.0, i=12.0)
    parent = "base"
    for i in range(1, 4):
        body += urdfs.joint(f"j{i}", parent, f"l{i}", "continuous", (0, 0, 1), (0.6, 0.1, 0))
        body += urdfs.link(f"l{i}", mass=9.0 - 2 * i, com=(0.3, 0.04 * i, 0.0))
        parent = f"l{i}"
    path = tmp_path / "planar3.urdf"
    path.write_text(urdfs.robot(body))
    robot = ff.load_robot(path)
    assert ff.is_planar(robot)
    mmap = ff.MomentumMap(robot)
    bounds = ff.planar_bounds(mmap)
    rng = np.random.default_rng(7)
    for _ in range(5):
        start, goal = rng.uniform(-3, 3, 3), rng.uniform(-3, 3, 3)
        lo, hi = bounds.interval(goal - start)
        problem = ff.build_problem(
            robot,
            start,
            goal,
            ff.quat_from_zyx(0.0),
            ff.quat_from_zyx(0.0),
            1.0,
            extra=[1, 0, 0],
            check_bounds=False,
        )
        assert lo < problem.yaw_change_of(np.zeros(1)) < hi


def test_batched_rates_and_their_derivative_against_the_full_solve_and_differences(tmp_path):
    """The batch's 3 x 3 shortcut (the base block is triangular) against the full 6 x 6 solve
    of ``A_g v = 0`` done by LAPACK, and ``d omega / d q`` against central differences."""
    path = tmp_path / "arm.urdf"
    path.write_text(urdfs.spatial_arm())
    mmap = ff.MomentumMap(ff.load_robot(path))
    rng = np.random.default_rng(3)
    joints, rates = rng.uniform(-1.5, 1.5, (5, 3)), rng.normal(size=(5, 3))
    batch = mmap.base_rates(joints, rates, derivatives=True)
    q = mmap.configurations(joints)
    for k in range(5):
        ag = pin.computeCentroidalMap(mmap.model, mmap.model.createData(), q[k])
        full = -np.linalg.solve(ag[:, :6], ag[:, 6:])
        np.testing.assert_allclose(batch.f1[k], full[3:], rtol=0, atol=1e-13)
        np.testing.assert_allclose(batch.omega[k], full[3:] @ rates[k], rtol=0, atol=1e-13)
    eps = 1e-6
    for i in range(3):
        step = np.zeros(3)
        step[i] = eps
        ahead = mmap.base_rates(joints + step, rates).omega
        behind = mmap.base_rates(joints - step, rates).omega
        fd = (ahead - behind) / (2 * eps)
        assert np.abs(batch.domega_dq[:, :, i] - fd).max() <= 1e-7 * np.abs(fd).max()
