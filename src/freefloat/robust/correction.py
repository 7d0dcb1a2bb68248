"""A correcting motion: back to the same joints, turning the spacecraft to its goal.

After a plan has run, the spacecraft is measured at an attitude off its goal (its mass
properties were not what the model said). A second motion from the plan's goal joints back to
the same joints (paper's example 5.2) turns it, because a closed loop in joint space turns the
base by the momentum map's curvature over the area it encloses. Its first-order turn is zero
(the joints return), so the correction starts from a closed loop chosen with the quadratic
model of the turn (:mod:`freefloat.solvers.loop_start`). From there the planner's continuation
reaches the goal attitude within the plan's limits and clearance, and the result is sampled
and verified like any plan. Where that search stops, it starts again from the other loop (of
the least joint motion), then from both with :data:`FREEDOM` + 1 free coefficients per joint.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._blas import one_blas_thread
from ..errors import GoalAttitudeError, InfeasibleError, InputError, SolverError
from ..physics.attitude import geodesic_angle, relative_quat, relative_rotvec
from ..pipeline import plan_from_solution
from ..plans.format import Plan
from ..problem.build import build_problem
from ..problem.constraints import Constraint
from ..problem.endpoints import at_attitude
from ..problem.residual import Problem
from ..robot.model import Robot
from ..solvers.dispatch import solve
from ..solvers.loop_start import loop_start, same_start
from ..solvers.options import Solution, SolveOptions
from ..solvers.restore import first_broken
from ..verify.checks import plan_constraints

__all__ = ["FREEDOM", "correcting_plan"]

#: Free coefficients per joint of the correcting motion.
FREEDOM = 2


def correcting_plan(
    plan: Plan,
    robot: Robot,
    measured_quaternion: np.ndarray,
    options: SolveOptions | None = None,
) -> Plan:
    """The verified motion from the plan's goal joints back to them, to the goal attitude.

    It turns the spacecraft from ``measured_quaternion`` (``[x, y, z, w]``) to the plan's goal
    attitude, and takes the plan's duration, samples and constraints (joint limits, clearance
    when the plan was kept clear).

    Raises:
        InputError: the robot has one joint (no loop turns its spacecraft).
        InfeasibleError: a planar robot measured off its axis (only the yaw can be corrected).
        GoalAttitudeError: the measured or the goal attitude breaks a constraint of the
            attitude (a pointing cone, the swing bound).
        SolverError: one motion cannot turn the spacecraft that far (the message gives the
            angle asked and how far the search got).
    """
    with one_blas_thread():  # as plan's search: the same on every machine (freefloat._blas)
        return _correcting(plan, robot, measured_quaternion, options)


def _correcting(
    plan: Plan,
    robot: Robot,
    measured_quaternion: np.ndarray,
    options: SolveOptions | None,
) -> Plan:
    """:func:`correcting_plan`, on whatever BLAS threads the caller set."""
    if robot.n == 1:
        raise InputError(
            "a robot with one joint cannot correct its attitude: every path from its joints "
            "back to them turns the spacecraft alike, that is not at all"
        )
    options = options or SolveOptions()
    goal_joints = np.asarray(plan.request.goal_joints, dtype=float)
    goal = np.asarray(plan.base.target_quaternion_xyzw, dtype=float)
    measured = np.asarray(measured_quaternion, dtype=float)
    measured = measured / np.linalg.norm(measured)
    angle = geodesic_angle(measured, goal)
    problem = _correction_problem(robot, goal_joints, measured, goal, plan.duration, FREEDOM)
    constraints = _restarted(plan, robot, measured)  # (a planar robot off its axis: said first)
    first: _Failed | None = None
    also: list[str] = []
    for extra in (FREEDOM, FREEDOM + 1):  # as plan's search: more freedom where less stops
        if extra != FREEDOM:
            problem = _correction_problem(robot, goal_joints, measured, goal, plan.duration, extra)
        # the loop turns the base frame at the end: the turn wanted, in that frame (planar: yaw)
        turn = relative_rotvec(measured, goal)
        if problem.planar:
            turn = -problem.residual(np.zeros(problem.n_free))
        starts: list[np.ndarray | None] = []
        for swing in (True, False):  # each loop plans some corrections the other cannot
            start = loop_start(problem, constraints, turn, swing) if angle > 0.0 else None
            if any(same_start(start, known) for known in starts):
                continue
            starts.append(start)
            try:
                solution = _within(problem, options, constraints, start)
            except SolverError as exc:
                if first is None:
                    first = _Failed(problem, exc, start)
                else:
                    loop = "swing" if swing else "joint motion"
                    also.append(f"freedom +{extra}, the loop of the least {loop}: {exc.headline}")
                continue
            return plan_from_solution(
                problem.with_steps(solution.steps),
                solution,
                samples=len(plan.samples.t),
                tolerance=options.tolerance,
                constraints=constraints,
                safety=plan.safety,
            )
    assert first is not None  # every attempt raised
    raise _refusal(first.problem, first.error, first.start, angle, constraints, also)


@dataclass(frozen=True)
class _Failed:
    """A correcting search that failed: its problem, its error and where it started."""

    problem: Problem
    error: SolverError
    start: np.ndarray | None


def _correction_problem(
    robot: Robot,
    joints: np.ndarray,
    measured: np.ndarray,
    goal: np.ndarray,
    duration: float,
    extra: int,
) -> Problem:
    """The problem from ``joints`` back to them, ``measured`` to ``goal`` (``[x, y, z, w]``).

    ``duration`` in s; ``extra`` free coefficients per joint.

    Raises:
        InfeasibleError: a planar robot measured off its axis (only the yaw can be corrected).
    """
    try:
        return build_problem(
            robot,
            joints,
            joints,
            measured,
            goal,
            duration,
            extra=[extra] * robot.n,
            check_bounds=False,
        )
    except InfeasibleError as exc:
        if not exc.off_axis:
            raise
        raise InfeasibleError(
            exc.requested_deg,
            exc.bounds_deg,
            f"this robot is planar: a motion turns its base only about its z axis, and the "
            f"measured attitude is {exc.requested_deg:.6g} deg from the plan's goal about "
            "other axes; only the yaw can be corrected (give the measured yaw with the goal's "
            "pitch and roll)",
            off_axis=True,
        ) from None


def _within(
    problem: Problem, options: SolveOptions, constraints: list[Constraint], start: np.ndarray | None
) -> Solution:
    """The solver's solution from ``start``, checked against the constraints on its own grid.

    The solver may return a root that its certification's polishing moved past a constraint
    (:func:`~freefloat.solvers.dispatch.solve`, for a planner that brings it back inside
    later); a correction has no such stage, so that root is a failed search here.

    Raises:
        SolverError: no root, or the root breaks a constraint (named).
    """
    solution = solve(problem, options, constraints, start)
    broken = first_broken(problem.with_steps(solution.steps), constraints, solution.beta)
    if broken is not None:  # the search's last path within the constraints: its start
        began = np.zeros(problem.n_free) if start is None else start
        raise SolverError(
            "no path within the constraints reaches the goal attitude",
            float(np.linalg.norm(problem.residual(began))),
            [*solution.tried, f"the root polished on a finer grid breaks {broken}"],
            blocked_by=(broken.name,),
        )
    return solution


def _refusal(
    problem: Problem,
    exc: SolverError,
    start: np.ndarray | None,
    angle: float,
    constraints: list[Constraint],
    also: Sequence[str] = (),
) -> SolverError:
    """The correction's refusal in its own words, from the search's error from ``start``.

    ``angle``: the turn asked (rad); ``also``: the further attempts that failed, for the list
    of what was tried.
    """
    said = "continued from where the search with less freedom stopped"  # the solver's words
    tried = [t.replace(said, "started from the quadratic-model loop") for t in exc.tried]
    tried += list(also)
    goal = problem.goal_quaternion
    began = problem.achieved(np.zeros(problem.n_free) if start is None else start)
    away = geodesic_angle(began, goal)  # what the search's own figures count from
    where = (
        ""
        if abs(away - angle) < 1e-9
        else f"its search began on a loop ending {math.degrees(away):.4g} deg from the goal: "
    )
    best, per_axis = exc.best_residual, exc.per_axis
    if start is not None:  # the loop keeps the constraints: the search's own figure
        missed = problem.residual(start)
        if float(np.linalg.norm(missed)) < best:
            best, per_axis = float(np.linalg.norm(missed)), tuple(missed)
    return SolverError(
        f"one correcting motion cannot turn the spacecraft back by {math.degrees(angle):.4g}"
        f" deg within the plan's constraints ({where}{exc.headline}){_near_edge(constraints)}",
        best,
        tried,
        per_axis=per_axis,
        stopped_by=exc.stopped_by,
        reached_fraction=exc.reached_fraction,
        blocked_by=exc.blocked_by,
    )


def _restarted(plan: Plan, robot: Robot, measured: np.ndarray) -> list[Constraint]:
    """The plan's constraints for a motion from the ``measured`` attitude (``[x, y, z, w]``).

    What the plan fixed in space stays where it was (a pointing cone's direction,
    :meth:`~freefloat.problem.constraints.Constraint.restarted`).

    Raises:
        GoalAttitudeError: the measured or the goal attitude breaks a constraint of the
            attitude (every correcting motion starts or ends there).
    """
    start = np.asarray(plan.base.start_quaternion_xyzw, dtype=float)
    goal = np.asarray(plan.base.target_quaternion_xyzw, dtype=float)
    turn = relative_quat(start / np.linalg.norm(start), measured)
    constraints = [c.restarted(turn) for c in plan_constraints(plan, robot)]
    for where, relative in (
        ("measured", _IDENTITY),
        ("plan's goal", relative_quat(measured, goal / np.linalg.norm(goal))),
    ):
        for constraint, excess, holds in at_attitude(constraints, relative):
            if not holds:
                raise GoalAttitudeError(constraint.name, excess.value, excess.detail, where)
    return constraints


#: The attitude of the start relative to itself (``[x, y, z, w]``).
_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])
#: How near (rad) an attitude bound's edge a measured attitude is said to lie when the
#: correction fails: the loop that starts it has little room there (the search found none
#: from 0.01 deg inside a 13.8 deg cone, and planned from 0.05 deg inside).
EDGE_NOTE = 1e-3


def _near_edge(constraints: list[Constraint]) -> str:
    """A note for a failed correction's message, ``""`` unless it is needed.

    ``"; the measured attitude lies ... inside ..."`` when that attitude is within
    :data:`EDGE_NOTE` (rad) of an attitude bound's edge.
    """
    for constraint in constraints:
        excess = constraint.at_attitude(_IDENTITY)
        if excess is not None and -excess.value < EDGE_NOTE:
            return (
                f"; the measured attitude lies only {math.degrees(-excess.value):.2g} deg inside "
                f"the {constraint.name} bound, where a correcting loop has little room"
            )
    return ""
