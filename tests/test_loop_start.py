"""A pure reorientation: joints that end where they start turn the spacecraft by a loop.

The quintic path of such a request does not move, so the attitude map is singular there; the
planner starts from a closed loop chosen with the quadratic model of the turn
(:mod:`freefloat.solvers.loop_start`), as ``freefloat correct`` does. Truths: the plan's joint
paths evaluated at both ends (the same joints), and an RK5 replay of the base attitude along
them (:func:`freefloat.robust.replay_attitude`, not the planner's Magnus scheme), which must
land on the goal attitude; the planar simple-motion bound (an empty interval for joints that
do not travel) is not held against it.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import freefloat as ff
from freefloat.physics.attitude import quat_exp, quat_from_zyx, quat_multiply
from freefloat.problem.build import problem_from_scenario
from freefloat.robot.model import robots_dir
from freefloat.robust import replay_attitude
from freefloat.solvers.loop_start import loop_origin, stays_put

SCENARIOS = robots_dir() / "scenarios"


def _in_place(name: str, turn: np.ndarray) -> ff.Scenario:
    """The shipped scenario with its goal joints its start joints, turned by ``turn`` (rad)."""
    scenario = ff.Scenario.from_toml(SCENARIOS / f"{name}.toml")
    goal = quat_multiply(scenario.start_attitude, quat_exp(np.asarray(turn, dtype=float)))
    return dataclasses.replace(
        scenario, goal_joints=dict(scenario.start_joints), goal_attitude=goal, extra=None
    )


@pytest.mark.parametrize(
    ("name", "turn"),
    [
        ("worked_example", [0.0, 0.0, np.radians(2.0)]),
        ("ur5_servicer", np.radians([1.0, -1.0, 1.5])),
    ],
)
def test_a_pure_reorientation_plans_a_loop_that_lands_on_the_goal(name, turn):
    scenario = _in_place(name, turn)
    plan = ff.plan(scenario)
    robot = scenario.robot
    ends = np.array([plan.samples.q[0], plan.samples.q[-1]])
    np.testing.assert_allclose(ends[0], scenario.start, atol=1e-12)
    np.testing.assert_allclose(ends[1], scenario.start, atol=1e-12)
    assert np.ptp(plan.samples.q, axis=0).max() > np.radians(1.0)  # it does move: a loop
    replayed = replay_attitude(plan, robot)
    assert replayed.error_rad <= 1e-9 + replayed.estimate_rad


def test_the_loop_is_the_start_only_where_the_quintic_path_stays_put():
    moving = problem_from_scenario(ff.Scenario.from_toml(SCENARIOS / "ur5_servicer.toml"))
    assert not stays_put(moving) and loop_origin(moving, ff.default_constraints()) is None
    still = _in_place("ur5_servicer", [0.0, 0.0, 0.0])
    problem = problem_from_scenario(still, extra=[2] * still.robot.n)
    assert stays_put(problem)
    assert loop_origin(problem, ff.default_constraints()) is None  # already at its goal
    turned = problem.with_goal(quat_multiply(problem.start_quaternion, quat_from_zyx(0.02)))
    loop = loop_origin(turned, ff.default_constraints())
    assert loop is not None and np.any(loop)
    # the quadratic model's turn: within a fifth of the 0.02 rad asked (it is a model)
    reached = np.linalg.norm(turned.residual(np.zeros(turned.n_free)) - turned.residual(loop))
    assert abs(reached - 0.02) < 0.2 * 0.02


def test_reach_of_a_pure_reorientation_starts_from_loops_and_its_goals_plan():
    """reach printed 0 in every direction for joints that end where they start (the quintic
    path stays put: singular). It now heads out from a loop on each axis; the goals it prints
    (at the inner turn and within it) plan. Truth: each plan's RK5 replay lands on its goal."""
    scenario = _in_place("ur5_servicer", [0.0, 0.0, 0.0])
    scenario = dataclasses.replace(
        scenario, safety=dataclasses.replace(scenario.safety, check=False)
    )
    axes = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
    report = ff.reachable(scenario, directions=axes, jobs=1)
    assert report.loops
    for d in report.directions:
        assert d.outer == 0.0 and d.inner > np.radians(1.0), d
        for fraction in (1.0, 0.5):
            turn = fraction * d.inner
            goal = quat_multiply(report.drift_quaternion, quat_exp(turn * d.axis))
            plan = ff.plan(dataclasses.replace(scenario, goal_attitude=goal))
            replayed = replay_attitude(plan, scenario.robot)
            assert replayed.error_rad <= 1e-9 + replayed.estimate_rad


def test_reach_of_a_planar_pure_reorientation_says_the_bounds_are_of_simple_motions():
    from freefloat.viz.reach_text import reach_lines

    report = ff.reachable(_in_place("worked_example", [0.0, 0.0, 0.0]))
    assert report.loops and report.planar
    assert [d.outer for d in report.directions] == [0.0, 0.0]
    assert reach_lines(report)[-1] == (
        "verdict: the goal joints are the start joints: every motion is a loop, which no "
        "simple-motion bound covers; plan starts each such goal from a loop (docs/reach.md)"
    )


@pytest.mark.parametrize("turn_deg", [[0.0, 0.0, 1.0], [1.0, -1.0, 1.5], [0.5, 0.0, 0.0]])
def test_the_loop_swings_the_spacecraft_about_as_far_as_it_turns_it(turn_deg):
    """A loop picked for its turn alone swung the UR5 servicer 5 to 7.5 times further on the
    way than it turned it at the end (6.1 deg for 0.92 deg), out of any narrow pointing cone;
    the loop that turns the most for its first-order swing swings at most twice its turn.
    Truth: SciPy's DOP853 on Pinocchio's centroidal map, both the swing and the end turn."""
    from test_base_swing import _scipy_attitude, scipy_largest

    still = _in_place("ur5_servicer", [0.0, 0.0, 0.0])
    problem = problem_from_scenario(still, extra=[2] * still.robot.n)
    turned = problem.with_goal(
        quat_multiply(problem.start_quaternion, quat_exp(np.radians(turn_deg)))
    )
    loop = loop_origin(turned, ff.default_constraints())
    assert loop is not None
    path = turned.polynomials(loop)

    def angle(y: np.ndarray) -> np.ndarray:
        return 2.0 * np.arctan2(np.linalg.norm(y[:3], axis=0), np.abs(y[3]))

    swing, _ = scipy_largest(path, still.robot, angle)
    end = float(angle(_scipy_attitude(path, still.robot).sol(path.duration)))
    assert end > np.radians(0.2)  # it does turn the spacecraft
    assert swing <= 2.0 * end, (np.degrees(swing), np.degrees(end))
