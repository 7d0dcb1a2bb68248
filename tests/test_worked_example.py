"""The worked example of docs/method.md section 8, against the closed form of section 7."""

from __future__ import annotations

import math

import numpy as np
import pytest

import freefloat as ff

import reference as ref
from conftest import ROOT, deg, worked_problem


def test_virtual_manipulator_lengths():
    # docs/method.md: a = 0.43 m, b = 0.89 m, c = 0.97 m; workspace 2.29 m, inner ring 1.44 m.
    assert ref.A == pytest.approx(0.43, abs=5e-3)
    assert ref.B == pytest.approx(0.89, abs=5e-3)
    assert ref.C == pytest.approx(0.97, abs=5e-3)
    assert ref.A + ref.B + ref.C == pytest.approx(2.29, abs=5e-3)
    assert ref.B + ref.C - ref.A == pytest.approx(1.44, abs=5e-3)


def test_end_effector_at_start_and_goal(worked_plan):
    start = worked_plan.samples.end_effector_position[0]
    goal = worked_plan.samples.end_effector_position[-1]
    assert start[:2] == pytest.approx(ref.end_effector(deg(-50), deg(80), deg(30)), abs=1e-12)
    assert goal[:2] == pytest.approx(ref.end_effector(0.0, deg(-60), deg(90)), abs=1e-12)
    assert start[:2] == pytest.approx([1.53, 0.96], abs=5e-3)
    assert goal[:2] == pytest.approx([1.71, -0.29], abs=5e-3)


def test_bounds_match_method(worked_plan):
    lo, hi = worked_plan.feasibility.yaw_change_bounds_deg
    assert lo == pytest.approx(1.4, abs=0.1)
    assert hi == pytest.approx(72.2, abs=0.1)
    assert worked_plan.feasibility.requested_yaw_change_deg == pytest.approx(50.0, abs=1e-12)


def test_bounds_gains_are_extremes_of_the_closed_form(planar_robot):
    bounds = ff.planar_bounds(ff.MomentumMap(planar_robot))
    grid = np.linspace(-math.pi, math.pi, 241)
    values = np.array([ref.gains(a, b) for a in grid for b in grid])
    # The refined extremes are at least as extreme as a dense grid, and not beyond it by more
    # than the grid's resolution can hide.
    assert np.all(bounds.g_min <= values.min(axis=0) + 1e-12)
    assert np.all(bounds.g_max >= values.max(axis=0) - 1e-12)
    assert bounds.g_min == pytest.approx(values.min(axis=0), abs=1e-5)
    assert bounds.g_max == pytest.approx(values.max(axis=0), abs=1e-5)


#: phi_0 = C0 s^3 (1 - s)^3 with C0 = sqrt(13 * 12! / 6!^2) = sqrt(12012); the paper's
#: s^6 - (a3 s^3 + a4 s^4 + a5 s^5) is -s^3 (1 - s)^3, so b26 T^6 = -C0 beta.
C0 = math.sqrt(12012.0)


def _b26(beta: float, duration: float = 10.0) -> float:
    """The paper's t^6 coefficient (rad/s^6) of a path whose free parameter is ``beta`` (rad)."""
    return -C0 * beta / duration**6


def test_minimum_norm_root_b26(worked_plan):
    (beta,) = worked_plan.free_parameters["q2"]
    assert worked_plan.free_parameters["q1"] == []
    b26 = worked_plan.path().monomials()[1, 6]  # the plan's path in the old units
    assert b26 == pytest.approx(_b26(beta), rel=1e-9)
    assert b26 == pytest.approx(-0.552e-4, rel=0.01)
    # Independent truth: the closed-form yaw integral with docs/method.md's printed coefficients.
    c1, c2 = ref.worked_example_coefficients(b26)
    assert ref.yaw_change(c1, c2, 10.0) == pytest.approx(math.radians(50.0), abs=1e-9)


def test_all_roots_listed_and_minimum_norm_is_shortest(worked_plan):
    solutions = worked_plan.solver.solutions
    b26s = [_b26(s.free_parameters["q2"][0]) for s in solutions]
    # docs/method.md: five roots between -5e-4 and 5e-4.
    assert len([b for b in b26s if abs(b) < 5e-4]) == 5
    assert abs(b26s[0]) == min(abs(b) for b in b26s)
    lengths = [s.path_length for s in solutions]
    assert lengths[0] == min(lengths)
    for b in b26s:
        c1, c2 = ref.worked_example_coefficients(b)
        assert ref.yaw_change(c1, c2, 10.0) == pytest.approx(math.radians(50.0), abs=1e-8)


def test_coefficients_equal_the_printed_polynomials(worked_plan):
    c1, c2 = ref.worked_example_coefficients(_b26(worked_plan.free_parameters["q2"][0]))
    coeffs = worked_plan.path().monomials()
    np.testing.assert_allclose(coeffs[0][: len(c1)][::-1], c1, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(coeffs[1][::-1], c2, rtol=1e-10, atol=1e-14)


def test_achieved_yaw_within_1e9(worked_plan):
    assert worked_plan.base.attitude_error_rad < 1e-9
    # Independent: adaptive quadrature of the closed form along the planned polynomials.
    monomials = worked_plan.path().monomials()
    c1, c2 = monomials[0][::-1], monomials[1][::-1]
    yaw = math.radians(-50.0) + ref.yaw_change(c1, c2, 10.0)
    assert abs(yaw) < 1e-9
    assert worked_plan.base.achieved_zyx_deg[0] == pytest.approx(0.0, abs=1e-7)


def test_joint_boundary_conditions_exact(worked_plan):
    start, goal = (deg(80), deg(30)), (deg(-60), deg(90))
    ends = worked_plan.path().evaluate(np.array([0.0, 10.0]))
    assert ends.q[0] == pytest.approx(start, abs=1e-15)
    assert ends.q[1] == pytest.approx(goal, abs=1e-14)
    assert np.abs(ends.qd).max() < 1e-15 and np.abs(ends.qdd).max() < 1e-15
    q = np.array(worked_plan.samples.q)
    assert q[0] == pytest.approx(start, abs=1e-15)
    assert q[-1] == pytest.approx(goal, abs=1e-12)


def test_arm_turns_clockwise_base_counterclockwise(worked_plan):
    yaw = np.array(worked_plan.samples.base_zyx_deg)[:, 0]
    q1 = np.array(worked_plan.samples.q)[:, 0]
    assert q1[-1] < q1[0]
    assert yaw[-1] > yaw[0]


@pytest.mark.parametrize("duration", [2.5, 40.0])
def test_duration_does_not_change_the_path(worked_scenario, worked_plan, duration):
    scenario = ff.Scenario(**{**worked_scenario.__dict__, "duration": duration})
    other = ff.plan(scenario)
    (b_ref,), (b_new,) = worked_plan.free_parameters["q2"], other.free_parameters["q2"]
    # Same path: the free parameter does not depend on T, the attitude reached is the same.
    assert b_new == pytest.approx(b_ref, rel=1e-9)
    assert other.base.achieved_quaternion_xyzw == pytest.approx(
        worked_plan.base.achieved_quaternion_xyzw, abs=1e-12
    )
    np.testing.assert_allclose(
        np.array(other.samples.q), np.array(worked_plan.samples.q), atol=1e-12
    )
    # Rates scale as 1/T, accelerations as 1/T^2.
    np.testing.assert_allclose(
        np.array(other.samples.qd) * duration, np.array(worked_plan.samples.qd) * 10.0, atol=1e-12
    )
    np.testing.assert_allclose(
        np.array(other.samples.qdd) * duration**2,
        np.array(worked_plan.samples.qdd) * 100.0,
        atol=1e-12,
    )


@pytest.mark.parametrize("b26", [-5.5e-5, 2.4e-4, -4.4e-4])
def test_attitude_integral_accurate_to_1e10(worked_scenario, b26):
    problem = worked_problem(worked_scenario, {"q2": 1})
    c1, c2 = ref.worked_example_coefficients(b26)
    assert problem.yaw_change_of(np.array([-b26 * 10.0**6 / C0])) == pytest.approx(
        ref.yaw_change(c1, c2, 10.0), abs=1e-10
    )


def test_planar_robot_described_in_another_plane_gives_the_same_plan(tmp_path, worked_plan):
    """Joint axes along base y: the reference system rotated by Rx(-90 deg), same plan."""
    text = (
        (ROOT / "robots" / "planar_2dof.urdf")
        .read_text()
        .replace('<axis xyz="0 0 1"/>', '<axis xyz="0 1 0"/>')
    )
    urdf = tmp_path / "planar_y.urdf"
    urdf.write_text(text)
    robot = ff.load_robot(urdf)
    np.testing.assert_allclose(ff.planar_axis(robot), [0.0, 1.0, 0.0])
    scenario = ff.Scenario(
        robot=robot,
        duration=10.0,
        start_joints={"q1": deg(80), "q2": deg(30)},
        goal_joints={"q1": deg(-60), "q2": deg(90)},
        start_attitude=ff.quat_from_zyx(0.0, deg(-50), 0.0),  # -50 deg about base y
        goal_attitude=ff.quat_from_zyx(0.0),
        extra={"q2": 1},
    )
    other = ff.plan(scenario)
    assert other.feasibility.planar
    assert other.free_parameters["q2"][0] == pytest.approx(
        worked_plan.free_parameters["q2"][0], rel=1e-9
    )
    assert other.feasibility.yaw_change_bounds_deg == pytest.approx(
        worked_plan.feasibility.yaw_change_bounds_deg, abs=1e-6
    )
    ee, ee_ref = (
        np.array(other.samples.end_effector_position),
        np.array(worked_plan.samples.end_effector_position),
    )
    np.testing.assert_allclose(ee[:, 0], ee_ref[:, 0], atol=1e-9)
    np.testing.assert_allclose(ee[:, 2], -ee_ref[:, 1], atol=1e-9)  # Rx(-90): y -> -z


def test_spatial_integrator_agrees_with_the_planar_integral(worked_scenario, worked_plan):
    import dataclasses

    problem = worked_problem(worked_scenario, {"q2": 1})
    beta = np.array(worked_plan.free_parameters["q2"])
    spatial = dataclasses.replace(problem, planar=False)
    assert ff.geodesic_angle(spatial.achieved(beta), problem.achieved(beta)) < 1e-12
    assert ff.geodesic_angle(spatial.achieved(beta), problem.goal_quaternion) < 1e-9
