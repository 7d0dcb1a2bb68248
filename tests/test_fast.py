"""The fast paths agree with independent references."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import freefloat as ff
from freefloat.physics import attitude as att
from freefloat.physics.planar_map import identify

import reference as ref
import urdfs
from conftest import ROOT


def test_planar_map_equals_the_closed_form(planar_robot):
    pm = identify(planar_robot, np.array([0.0, 0.0, 1.0]))
    assert pm is not None and pm.error < 1e-12
    q = np.random.default_rng(3).uniform(-6, 6, (200, 2))
    np.testing.assert_allclose(pm.gains(q), [ref.gains(*x) for x in q], atol=1e-13)
    gains, dgains = pm.gains_and_derivatives(q[:5])
    np.testing.assert_allclose(gains, pm.gains(q[:5]), atol=1e-15)
    eps = 1e-6
    fd = np.stack([ref.central_jacobian(pm.gains, x, eps) for x in q[:5]])
    np.testing.assert_allclose(dgains, fd, atol=1e-8)


def test_planar_map_is_refused_for_prismatic_joints(tmp_path):
    path = tmp_path / "p.urdf"
    path.write_text(urdfs.slider_arm())
    assert identify(ff.load_robot(path), np.array([0.0, 0.0, 1.0])) is None


def test_fast_planar_path_equals_the_pinocchio_path(worked_scenario):
    s = worked_scenario
    problem = ff.build_problem(
        s.robot, s.start, s.goal, s.start_attitude, s.goal_attitude, 10.0, extra={"q1": 1, "q2": 1}
    )
    assert problem.planar_map is not None
    slow = dataclasses.replace(problem, planar_map=None)
    beta = np.array([12.0, -30.0])
    assert problem.residual(beta) == pytest.approx(slow.residual(beta), abs=1e-13)
    np.testing.assert_allclose(problem.jacobian(beta), slow.jacobian(beta), rtol=1e-10)


@pytest.mark.parametrize("name", ["panda_servicer", "ur5_servicer"])
def test_magnus_integration_agrees_with_a_tight_adaptive_reference(name):
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / f"{name}.toml")
    problem = ff.build_problem(
        scenario.robot,
        scenario.start,
        scenario.goal,
        scenario.start_attitude,
        scenario.goal_attitude,
        20.0,
    )
    beta = np.array([0.02, -0.03, 0.015])  # rad RMS deviations (the old basis took 2, -3, 1.5)
    mmap = ff.MomentumMap(scenario.robot)

    def rhs(t, y):
        path = problem.family.at_times(beta, np.array([t]), 20.0)
        omega = mmap.f1(path.q[0]) @ path.qd[0]
        return 0.5 * att.quat_multiply(y, np.concatenate([omega, [0.0]]))

    sol = solve_ivp(
        rhs, (0.0, 20.0), problem.start_quaternion, method="DOP853", rtol=1e-13, atol=1e-14
    )
    reference = sol.y[:, -1] / np.linalg.norm(sol.y[:, -1])
    assert att.geodesic_angle(problem.achieved(beta), reference) < 1e-10


def test_replaced_problems_share_no_cached_values(worked_scenario):
    s = worked_scenario
    problem = ff.build_problem(
        s.robot, s.start, s.goal, s.start_attitude, s.goal_attitude, 10.0, extra={"q2": 1}
    )
    beta = np.array([-40.0])
    problem.residual(beta)
    other = dataclasses.replace(problem, yaw_change=problem.yaw_change + 0.5)
    assert other.residual(beta) == pytest.approx(problem.residual(beta) - 0.5, abs=1e-14)
