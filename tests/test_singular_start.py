"""A path family whose map is singular at the plain quintic path (a two-joint arm with
parallel axes, two free coefficients per joint): the refusal names the singular map, not the
joint limit its meaningless tangent would break, and the reach estimate starts from the
planner's next freedom level, where every goal it reports plans."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import freefloat as ff
from freefloat.physics import attitude as att
from freefloat.solvers.continuation import track
from freefloat.solvers.options import SolveOptions

import urdfs

START, GOAL = [0.2, -0.3], [1.1, 0.4]


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> ff.Robot:
    path = tmp_path_factory.mktemp("parallel") / "arm.urdf"
    path.write_text(urdfs.spatial_arm(kinds=("revolute", "revolute"), axes=((0, 1, 0),) * 2))
    return ff.load_robot(path)


def _problem(robot: ff.Robot, extra: int) -> ff.Problem:
    return ff.build_problem(robot, START, GOAL, att.IDENTITY, att.IDENTITY, 8.0, extra=[extra] * 2)


def _finite_difference_jacobian(problem: ff.Problem, step: float = 1e-6) -> np.ndarray:
    """Central differences of the residual (rad per unit of beta) at beta = 0."""
    columns = []
    for k in range(problem.n_free):
        e = np.zeros(problem.n_free)
        e[k] = step
        columns.append((problem.residual(e) - problem.residual(-e)) / (2 * step))
    return np.array(columns).T


def test_the_first_level_is_singular_by_finite_differences_the_next_is_not(robot) -> None:
    """The ratio of singular values of the residual's Jacobian by central differences (not
    the planner's derivative): below 1e-7 at +2 per joint, above 1e-4 at +3."""
    ratios = []
    for extra in (2, 3):
        sigma = np.linalg.svd(_finite_difference_jacobian(_problem(robot, extra)), compute_uv=False)
        ratios.append(sigma[-1] / sigma[0])
    assert ratios[0] < 1e-7 < 1e-4 < ratios[1]


def test_a_branch_that_cannot_start_names_the_singular_map(robot) -> None:
    """Its least-squares tangent is of order 1e8 and would break the joint limits at once;
    the reason given is the singular map."""
    problem = _problem(robot, 2)
    weak = np.linalg.svd(_finite_difference_jacobian(problem))[0][:, -1]
    drift = problem.achieved(np.zeros(problem.n_free))
    target = problem.with_goal(att.quat_multiply(drift, att.quat_exp(math.radians(1.0) * weak)))
    result = track(target, ff.default_constraints(), SolveOptions(max_evaluations=30))
    assert result.fraction == 0.0
    assert result.stopped_by == "a singular map (dh/dbeta loses rank)"
    assert result.blocked_by == ""  # no constraint named from that tangent's step


def test_the_reach_estimate_starts_where_the_map_is_regular_and_its_goals_plan(robot) -> None:
    """No [path] extra: the estimate uses +3 per joint (the planner's next level); a goal at
    each of two directions' inner turns, as printed (4 decimals of a degree), plans."""
    scenario = ff.Scenario(
        robot,
        8.0,
        dict(zip(robot.joint_names, START, strict=True)),
        dict(zip(robot.joint_names, GOAL, strict=True)),
        start_attitude=att.IDENTITY,
        goal_attitude=att.IDENTITY,
    )
    report = ff.reachable(scenario, jobs=1)
    assert report.freedom == (3, 3)
    reached = sorted(report.directions, key=lambda d: d.inner, reverse=True)[:2]
    assert reached[1].inner > 0.0
    for direction in reached:
        goal = ff.quat_from_zyx(*np.radians(np.round(direction.goal_zyx_deg, 4)))
        plan = ff.plan(dataclasses.replace(scenario, goal_attitude=goal))
        assert plan.verification.passed


def test_a_refusal_never_claims_more_of_the_way_than_its_path_covers(robot) -> None:
    """The branch's fraction comes from targets solved on a coarser grid; the refusal's is
    the path's own on the problem's grid. A path that has not moved (beta = 0, the quintic)
    towards a goal 20 deg off covers none of the way, whatever the branch claimed (by hand:
    the goal is the quintic attitude turned 20 deg); the quintic's own attitude covers all."""
    from freefloat.solvers.continuation import held_fraction
    from freefloat.solvers.tracked import ContinuationResult

    problem = _problem(robot, 3)
    quintic = problem.achieved(np.zeros(problem.n_free))
    angle = math.radians(20.0)
    goal = att.quat_multiply(quintic, att.quat_exp(np.array([0.0, 0.0, angle])))
    stopped = ContinuationResult(
        np.zeros(problem.n_free), 0.9, angle, np.eye(3)[2], np.zeros(3), 5, 9, "x"
    )
    assert held_fraction(problem.with_goal(goal), stopped) == pytest.approx(0.0, abs=1e-12)
    assert held_fraction(problem.with_goal(quintic), stopped) == 0.9


def test_a_constraint_ahead_on_a_nearly_singular_map_says_so() -> None:
    """By hand, the singular values of a diagonal map: a weakest gain below 1e-3 of the
    strongest is named before the constraint, as the cause (the step ahead is then long);
    above, nothing; a singular map is named instead of the constraint."""
    from freefloat.solvers.branch_stop import why_stopped as _why
    from freefloat.solvers.restore import Broken

    ahead = Broken("joint_position_limits", "joint 'j1' at t = 2 s")
    near = _why(ahead, np.c_[np.diag([2.0, 1.0, 8e-4]), np.zeros(3)])
    assert near == (
        "a nearly singular map (its weakest gain 0.0004 of its strongest), so a step on is "
        "long: joint_position_limits ahead: joint 'j1' at t = 2 s"
    )
    regular = np.c_[np.diag([2.0, 1.0, 4e-3]), np.zeros(3)]
    assert _why(ahead, regular) == "joint_position_limits ahead: joint 'j1' at t = 2 s"
    assert _why(ahead, np.c_[np.diag([2.0, 1.0, 1e-12]), np.zeros(3)]) == (
        "a singular map (dh/dbeta loses rank)"
    )
    # Every gain tiny though of one size (an outside trial: 2.6e-6 to 8.5e-7 rad per unit,
    # a step asking the elbow for 16311 deg): the weak map is named first.
    weak = np.c_[np.diag([3e-6, 2e-6, 1e-6]), np.zeros(3)]
    assert _why(ahead, weak) == (
        "a weak map (its largest gain 3e-06 rad per unit of the free coefficients), so a "
        "step on is long: joint_position_limits ahead: joint 'j1' at t = 2 s"
    )
    assert _why(ahead, 10.0 * weak) == "joint_position_limits ahead: joint 'j1' at t = 2 s"


def test_a_path_that_does_not_move_takes_no_step_from_its_singular_map(robot) -> None:
    """Start and goal joints alike: every free coefficient's first-order effect on the
    attitude vanishes (the finite-difference Jacobian is zero to rounding), so continuation
    stops at once, naming the singular map. (It used to step along a least-squares tangent of
    order 1e9 and, on some CPUs, leave quadprog looping on the rows of that path.)"""
    problem = ff.build_problem(robot, START, START, att.IDENTITY, att.IDENTITY, 8.0, extra=[2, 2])
    assert np.abs(_finite_difference_jacobian(problem)).max() < 1e-9
    target = problem.with_goal(att.quat_exp(math.radians(1.0) * np.array([0.0, 0.0, 1.0])))
    before = problem.evaluations
    result = track(target, ff.default_constraints(), SolveOptions(max_evaluations=30))
    assert (result.steps, result.fraction) == (0, 0.0)
    assert result.stopped_by == "a singular map (dh/dbeta loses rank)"
    assert problem.evaluations - before <= 2
