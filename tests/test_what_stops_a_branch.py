"""A stopped branch names the constraint that stops it, not one far away along a long tangent.

A 100 kg base with a three-joint arm (limits +-3 rad, 2 rad/s) asked to turn 30 deg in 4 s:
the velocity limit binds long before any position limit. The truth is the stopped path
itself, sampled densely: its joint rates by finite differences of its joint values (not the
constraints' own formulas) reach 2 rad/s, while every joint keeps more than 0.3 rad from its
position limits.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import freefloat as ff
from freefloat.physics import attitude as att
from freefloat.problem.constraints import default_constraints
from freefloat.solvers import branch_stop, continuation
from freefloat.solvers.continuation import track
from freefloat.solvers.in_the_way import WITHOUT
from freefloat.solvers.options import SolveOptions

import urdfs

START, GOAL, DURATION = [0.2, -0.3, 0.4], [0.9, 0.3, -0.2], 4.0
#: The URDF's limits (urdfs.joint): position +-3 rad, velocity 2 rad/s.
POSITION, VELOCITY = 3.0, 2.0


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> ff.Robot:
    path = tmp_path_factory.mktemp("slow") / "arm.urdf"
    path.write_text(urdfs.spatial_arm(base_mass=100.0))
    return ff.load_robot(path)


@pytest.fixture(scope="module")
def problem(robot: ff.Robot) -> ff.Problem:
    return ff.build_problem(robot, START, GOAL, att.IDENTITY, att.IDENTITY, DURATION, extra=[2] * 3)


def _turned(problem: ff.Problem, axis: list[float], degrees: float) -> ff.Problem:
    drift = problem.achieved(np.zeros(problem.n_free))
    turn = att.quat_exp(math.radians(degrees) * np.array(axis, dtype=float))
    return problem.with_goal(att.quat_multiply(drift, turn))


def _scenario_and_drift(robot: ff.Robot, duration: float) -> tuple[ff.Scenario, np.ndarray]:
    """The scenario from START to GOAL in ``duration`` (s), and its plain quintic's attitude."""
    names = [j.name for j in robot.joints]
    start, goal = dict(zip(names, START, strict=True)), dict(zip(names, GOAL, strict=True))
    scenario = ff.Scenario(robot, duration, start, goal)
    quintic = ff.problem_from_scenario(scenario)
    return scenario, quintic.achieved(np.zeros(quintic.n_free))


def _room_and_peak_rate(problem: ff.Problem, beta: np.ndarray) -> tuple[float, float]:
    """Smallest distance to a position limit (rad) and largest |rate| (rad/s), sampled."""
    t = np.linspace(0.0, DURATION, 4001)
    q = problem.polynomials(beta).evaluate(t).q
    rates = np.gradient(q, t, axis=0)  # finite differences of the joint values
    return POSITION - float(np.abs(q).max()), float(np.abs(rates).max())


@pytest.mark.parametrize("axis", [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
def test_the_velocity_limit_that_binds_is_named_not_a_distant_position_limit(problem, axis) -> None:
    found = track(_turned(problem, axis, 30.0), default_constraints(), SolveOptions())
    assert 0.0 < found.fraction < 1.0
    assert found.stopped_by.startswith("joint_velocity_limits ahead: joint 'j")
    room, peak = _room_and_peak_rate(problem, found.beta)
    assert room > 0.3
    assert peak == pytest.approx(VELOCITY, abs=1e-3)


def test_a_constraint_in_the_way_but_not_ahead_is_found_by_leaving_it_out(
    problem, monkeypatch
) -> None:
    """Where no constraint is broken along the tangent (here: made so), the failed step is
    corrected without each constraint in turn; the one named is the one without which the
    branch goes further, on a path that breaks it."""
    target = _turned(problem, [1.0, 0.0, 0.0], 30.0)
    for module in (continuation, branch_stop):
        monkeypatch.setattr(module, "ahead", lambda *args: None)
    found = track(target, default_constraints(), SolveOptions())
    assert found.stopped_by.startswith("joint_velocity_limits ahead: joint 'j")
    assert found.stopped_by.endswith(f"({WITHOUT})")
    assert found.blocked_by == "joint_velocity_limits"
    monkeypatch.undo()
    others = [c for c in default_constraints() if c.name != "joint_velocity_limits"]
    freer = track(target, others, SolveOptions())
    assert freer.fraction > found.fraction
    assert _room_and_peak_rate(problem, freer.beta)[1] > VELOCITY + 1e-3


def test_without_any_constraint_in_the_way_the_family_is_blamed(problem, monkeypatch) -> None:
    """No constraint ahead and none whose absence lets the step converge: the freedom."""
    for module in (continuation, branch_stop):
        monkeypatch.setattr(module, "ahead", lambda *args: None)
    monkeypatch.setattr(branch_stop, "in_the_way", lambda *args: None)
    found = track(_turned(problem, [1.0, 0.0, 0.0], 30.0), default_constraints(), SolveOptions())
    assert found.stopped_by.startswith("freedom exhausted")


def test_a_velocity_refusal_says_how_far_the_search_within_the_limits_got(robot) -> None:
    """10 deg about x in 4 s needs more than 2 rad/s: the refusal names the joint's rate and
    the longer duration, and how far the search within every limit got; a goal that far (and
    one nearer) about the same axis plans at 4 s, its rates within the limit by finite
    differences of its joint values on a dense grid."""
    scenario, drift = _scenario_and_drift(robot, DURATION)
    turn = att.quat_exp(math.radians(10.0) * np.array([1.0, 0.0, 0.0]))
    with pytest.raises(ff.VelocityLimitError) as info:
        ff.plan(dataclasses.replace(scenario, goal_attitude=att.quat_multiply(drift, turn)))
    error = info.value
    assert 0.0 < error.reached < error.asked == pytest.approx(math.radians(10.0), rel=1e-6)
    phrase = ff.UnreachableAttitudeError.turn_phrase(error.reached, error.asked)
    assert str(error).endswith(f"; at this duration and within every limit, {phrase}")
    axis = np.array(error.__cause__.axis)
    t = np.linspace(0.0, DURATION, 20001)
    for share in (1.0, 0.6):
        goal = att.quat_multiply(drift, att.quat_exp(share * error.reached * axis))
        plan = ff.plan(dataclasses.replace(scenario, goal_attitude=goal), samples=41)
        assert plan.verification.passed
        rates = np.gradient(plan.joint_positions(t), t, axis=0)  # finite differences
        assert np.abs(rates).max() <= VELOCITY + 1e-6


def test_a_goal_refused_before_any_step_is_an_unreachable_attitude(robot) -> None:
    """A branch that takes no step (every corrector fails; made so here) is refused as the
    out-of-reach goal its message describes: an ``UnreachableAttitudeError`` (so also an
    ``UnreachableGoalError``), reached 0 of the turn asked, that turn measured apart."""
    scenario, drift = _scenario_and_drift(robot, 20.0)
    turn = att.quat_exp(math.radians(2.0) * np.array([0.0, 0.0, 1.0]))
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(continuation, "corrected_step", _failing_step)
        with pytest.raises(ff.UnreachableAttitudeError) as info:
            ff.plan(dataclasses.replace(scenario, goal_attitude=att.quat_multiply(drift, turn)))
    error = info.value
    assert isinstance(error, ff.UnreachableGoalError)
    assert error.reached == 0.0 and error.last_beta is None
    assert error.asked == pytest.approx(math.radians(2.0), rel=1e-9)
    assert str(error).startswith("reachable up to 0 deg of the 2 deg asked")


def _failing_step(problem, target, constraints, predicted, tol, at):
    """A ``corrected_step`` whose corrector never converges."""
    from freefloat.solvers.corrector import Step

    r, jac = target.residual_and_jacobian(predicted)
    return Step(None, r, jac, 8, 8, at.instants, at.dips)


def test_a_search_that_spends_its_budget_without_a_path_stays_a_plain_solver_error(
    problem,
) -> None:
    """Only a strategy that says how far it got is refused as out of reach: the multistart
    search stopped by its evaluation budget (one evaluation) is a ``SolverError`` that
    claims no turn reached."""
    from freefloat.solvers.dispatch import solve

    target = _turned(problem, [1.0, 0.0, 0.0], 60.0)
    with pytest.raises(ff.SolverError) as info:
        solve(target, SolveOptions(strategy="multistart", max_evaluations=1), default_constraints())
    assert not isinstance(info.value, ff.UnreachableAttitudeError)
    assert "reachable up to" not in str(info.value)


def test_a_duration_below_every_paths_floor_is_named_in_the_refusal(tmp_path) -> None:
    """A 100 t base, 0.2 s, a goal 10 deg off the drift attitude: out of reach with or without
    the velocity limits, and 0.2 s is shorter than any path between these joints can keep
    2 rad/s (the largest span over the limit, closed form: 0.35 s). The refusal says so, so
    the user lengthens the duration before doubting the attitude."""
    path = tmp_path / "heavy.urdf"
    path.write_text(urdfs.spatial_arm(base_mass=1e5))
    heavy = ff.load_robot(path)
    scenario, drift = _scenario_and_drift(heavy, 0.2)
    turn = att.quat_exp(math.radians(10.0) * np.array([1.0, 0.0, 0.0]))
    floor = max(abs(g - s) for s, g in zip(START, GOAL, strict=True)) / VELOCITY
    assert floor == pytest.approx(0.35)
    with pytest.raises(ff.SolverError) as info:
        ff.plan(dataclasses.replace(scenario, goal_attitude=att.quat_multiply(drift, turn)))
    assert str(info.value).endswith(
        f"no path keeps every velocity limit in under {floor:.4g} s (each joint's travel at its "
        "limit), longer than the 0.2 s asked: lengthen the duration first"
    )
