"""The continuation strategy (issue 11): reach, constraints along the dense path, determinism."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

import freefloat as ff
from freefloat.physics import attitude as att
from freefloat.problem.build import problem_from_scenario
from freefloat.problem.constraints import default_constraints
from freefloat.solvers.continuation import INTERMEDIATE_TOLERANCE, track
from freefloat.solvers.tracked import BranchPoint
from test_solver import _independent_final_attitude

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "robots" / "scenarios"


@pytest.fixture(scope="module")
def panda() -> ff.Scenario:
    return ff.Scenario.from_toml(SCENARIOS / "panda_servicer.toml")


@pytest.fixture(scope="module")
def panda_problem(panda: ff.Scenario) -> ff.Problem:
    """Panda servicer with two free coefficients per joint (the continuation default)."""
    return problem_from_scenario(panda, extra=[2] * panda.robot.n)


def _turned(problem: ff.Problem, rotvec: np.ndarray) -> ff.Problem:
    """The problem with its goal at the quintic path's attitude turned by ``rotvec`` (rad)."""
    reached = problem.achieved(np.zeros(problem.n_free))
    return problem.with_goal(att.quat_multiply(reached, att.quat_exp(np.asarray(rotvec))))


def _independent_residual(problem: ff.Problem, beta: np.ndarray) -> float:
    """Geodesic error (rad) at T of SciPy's adaptive DOP853 on the quaternion ODE in seconds
    (not the planner's Magnus scheme)."""
    return att.geodesic_angle(_independent_final_attitude(problem, beta), problem.goal_quaternion)


def test_with_goal_is_a_copy(panda_problem: ff.Problem) -> None:
    goal = panda_problem.goal_quaternion.copy()
    other = _turned(panda_problem, [0.0, 0.0, 0.1])
    assert np.array_equal(panda_problem.goal_quaternion, goal)
    assert other.family is panda_problem.family
    assert att.geodesic_angle(other.goal_quaternion, goal) > 0.01


def test_regression_panda_goal_yaw_plus_5_deg(panda: ff.Scenario) -> None:
    """The issue's case: the multistart search refused it after ~55 s; continuation plans it."""
    yaw, pitch, roll = ff.zyx_from_quat(panda.goal_attitude)
    goal = ff.quat_from_zyx(yaw + math.radians(5.0), pitch, roll)
    plan = ff.plan(dataclasses.replace(panda, goal_attitude=goal))
    assert plan.solver.strategy == "continuation"
    assert plan.base.attitude_error_rad < 1e-9
    assert ff.geodesic_angle(np.array(plan.base.achieved_quaternion_xyzw), goal) < 1e-9


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_ten_degrees_about_each_axis_within_the_limits_along_the_dense_path(
    panda_problem: ff.Problem, axis: int
) -> None:
    rotvec = np.zeros(3)
    rotvec[axis] = math.radians(10.0)
    problem = _turned(panda_problem, rotvec)
    solution = ff.solve(problem, ff.SolveOptions(strategy=ff.Strategy.CONTINUATION))
    assert solution.strategy == ff.Strategy.CONTINUATION
    assert _independent_residual(problem, solution.beta) < 1e-9
    path = problem.polynomials(solution.beta)
    for constraint in default_constraints():
        excess = constraint.excess(problem.robot, path)
        assert excess.value <= constraint.tolerance, (constraint.name, excess)


def test_points_on_the_way_are_solved_to_their_tolerance_by_an_independent_integrator(
    panda_problem: ff.Problem,
) -> None:
    """The targets on the way are solved on half the integration steps (their tolerance allows
    it): SciPy's DOP853 finds each traced path within that tolerance of its target (plus a
    micro-radian), and the goal's within 1e-9 rad."""
    problem = _turned(panda_problem, [0.0, 0.0, math.radians(10.0)])
    trace: list[BranchPoint] = []
    result = track(problem, default_constraints(), ff.SolveOptions(), trace=trace)
    assert result.reached and len(trace) >= 4  # the start, two points on the way, the goal
    start = problem.achieved(np.zeros(problem.n_free))
    for point in trace[1:-1]:
        target = att.quat_multiply(start, att.quat_exp(point.turn * result.axis))
        found = _independent_final_attitude(problem, point.beta)
        assert att.geodesic_angle(found, target) < INTERMEDIATE_TOLERANCE + 1e-6
    assert _independent_residual(problem, trace[-1].beta) < 1e-9


def test_a_limit_met_on_the_way_is_kept_along_the_dense_path(panda_problem: ff.Problem) -> None:
    """3 deg about y drives panda_joint4 onto its limit: the path must touch, never cross."""
    problem = _turned(panda_problem, [0.0, math.radians(3.0), 0.0])
    solution = ff.solve(problem)
    limits = default_constraints()[0]
    excess = limits.excess(problem.robot, problem.polynomials(solution.beta))
    assert -1e-6 < excess.value <= limits.tolerance  # active, and not beyond
    # The unconstrained minimum-norm Newton continuation would cross it: the limit is real.
    unconstrained = ff.solve(problem, constraints=[])
    crossed = limits.excess(problem.robot, problem.polynomials(unconstrained.beta))
    assert crossed.value > 1e-4


def test_two_runs_give_byte_identical_plans(panda: ff.Scenario) -> None:
    yaw, pitch, roll = ff.zyx_from_quat(panda.goal_attitude)
    scenario = dataclasses.replace(
        panda, goal_attitude=ff.quat_from_zyx(yaw + math.radians(2.0), pitch, roll)
    )

    def untimed() -> str:
        data = json.loads(ff.plan(scenario).to_json())
        for timing in ("wall_time_s", "solve_time_s", "sample_time_s", "verify_time_s"):
            data["solver"].pop(timing)
        return json.dumps(data, sort_keys=True)

    assert untimed() == untimed()


def test_failure_reports_reach_and_a_goal_at_95_percent_of_it_plans(
    panda_problem: ff.Problem,
) -> None:
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    angle = math.radians(60.0)
    budget = ff.SolveOptions(max_evaluations=400)
    with pytest.raises(ff.SolverError) as info:
        ff.solve(_turned(panda_problem, angle * axis), budget)
    err = info.value
    assert 0.0 < err.reached_fraction < 1.0
    assert err.stopped_by
    reach_deg = math.degrees(err.reached_fraction * angle)
    assert str(err).startswith(f"reachable up to {reach_deg:.3g} deg of the 60 deg asked")
    inside = _turned(panda_problem, 0.95 * err.reached_fraction * angle * axis)
    solution = ff.solve(inside)
    assert _independent_residual(inside, solution.beta) < 1e-9


def test_more_freedom_continues_from_where_less_stopped() -> None:
    """The new free coefficients start at zero, so the carried path is exactly the old one."""
    start, goal = np.array([0.1, -0.4, 0.9]), np.array([1.2, 0.3, -0.5])
    small = ff.PathFamily.with_extra(start, goal, [2, 2, 2])
    large = ff.PathFamily.with_extra(start, goal, [3, 3, 3])
    beta = np.array([0.3, -0.2, 0.5, 0.1, -0.7, 0.25])
    carried = large.embed(small, beta)
    assert carried is not None and len(carried) == 9
    s = np.linspace(0.0, 1.0, 57)
    np.testing.assert_allclose(large.evaluate(carried, s).q, small.evaluate(beta, s).q, atol=1e-14)
    assert small.embed(large, carried) is None  # fewer coefficients cannot hold it
    other = ff.PathFamily.with_extra(start, goal + 0.1, [3, 3, 3])
    assert other.embed(small, beta) is None  # another motion


def test_a_stopped_search_is_continued_with_more_freedom(panda: ff.Scenario) -> None:
    import io

    from freefloat.progress import configure

    far = ff.quat_from_zyx(math.radians(75.0), 0.0, 0.0)  # yaw 60 deg plans since round 14
    log = io.StringIO()
    configure(1, stream=log)  # -v: a line per freedom level
    try:
        with pytest.raises(ff.SolverError) as info:
            ff.plan(dataclasses.replace(panda, goal_attitude=far))
    finally:
        configure(0)
    assert "(level 1 of 2)" in log.getvalue() and "(level 2 of 2)" in log.getvalue()
    assert "solve: level 2 stopped: reachable up to" in log.getvalue()
    err = info.value
    assert "(continued): stopped" in str(err)
    assert err.stopped_by
    # One figure throughout: the reach from the quintic attitude plus what the path the
    # search stopped on misses (its residual, recomputed here) make up the turn asked.
    assert isinstance(err, ff.UnreachableGoalError)
    assert err.reached + err.best_residual == pytest.approx(err.asked, abs=2e-3)
    assert err.reached_fraction == pytest.approx(err.reached / err.asked, rel=1e-12)
    assert f"reachable up to {math.degrees(err.reached):.3g} deg of the" in str(err)
    assert f"misses the goal by {err.best_residual:.3g} rad" in str(err)


@pytest.mark.parametrize(
    ("fraction", "printed"),
    [(0.5, "0.5"), (0.1234, "0.123"), (0.9996, "0.9996"), (0.99999999, "0.99999999"), (1.0, "1")],
)
def test_a_stop_short_of_the_goal_never_prints_as_the_whole_way(fraction, printed):
    from freefloat.solvers.tracked import ContinuationResult

    def result(f):
        return ContinuationResult(np.zeros(1), f, 0.1, np.array([0.0, 0.0, 1.0]), np.zeros(3), 1, 1)

    assert result(fraction).fraction_text == printed
    just_short = np.nextafter(1.0, 0.0)
    assert float(result(just_short).fraction_text) == just_short


def test_a_start_no_path_can_bring_within_a_constraint_stops_at_once_saying_so(tmp_path):
    """A cone about the direction opposite to the end effector's axis at the start holds no
    path of the family: every path shares the start. Continuation stops there, naming the
    constraint, without a step."""
    import pinocchio as pin

    from freefloat.problem.constraints.end_effector_cone import EndEffectorCone
    from freefloat.solvers.continuation import NO_START, track
    from freefloat.solvers.options import SolveOptions

    import urdfs

    path = tmp_path / "arm.urdf"
    path.write_text(urdfs.spatial_arm())
    robot = ff.load_robot(path)
    start, goal = np.array([0.2, -0.3, 0.4]), np.array([0.9, 0.5, -0.2])
    problem = ff.build_problem(robot, start, goal, att.IDENTITY, att.IDENTITY, 8.0)
    data = robot.model.createData()  # the start's end-effector axis, by Pinocchio alone
    pin.framesForwardKinematics(robot.model, data, robot.configuration(start))
    tip = data.oMf[robot.model.getFrameId(robot.end_effector)].rotation[:, 0]
    away = -(data.oMi[1].rotation.T @ tip)  # in the base frame: 180 deg from the axis
    cone = EndEffectorCone([1.0, 0.0, 0.0], away, math.radians(10.0))
    result = track(problem, [cone], SolveOptions())
    assert result.stopped_by == NO_START and result.blocked_by == "end_effector_cone"
    assert result.steps == 0 and result.fraction == 0.0
