"""Where a scenario's motion can leave the spacecraft: drift attitude and reachable set.

:func:`reachable` answers, before any goal attitude is guessed:

- the *drift attitude*: where the plain quintic path (every joint monotone, no free
  coefficient) leaves the spacecraft;
- an *outer bound for simple motions* (:mod:`freefloat.problem.simple_bound`): no motion whose
  joints travel at most ``k`` times their start-goal span ends farther than ``B`` from the
  start attitude, and so, per direction from the drift attitude, no farther than a turn it
  gives;
- an *inner estimate*: per direction, the largest turn from the drift attitude that
  continuation reached with a solved path, heading for that outer limit, with the same
  freedom and constraints the planner tries first (:func:`freefloat.solvers.reach.reach_set`);
  its end is solved as the planner solves it, and the goals before it take the planner's
  steps along the same branch (as a rule, not a proof: docs/reach.md).

For a planar robot the reachable yaw changes are the planar bounds (docs/method.md section 6).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ._blas import one_blas_thread
from .parallel import check_jobs, default_jobs, where_run
from .physics.attitude import (
    quat_exp,
    quat_multiply,
    relative_quat,
    relative_rotvec,
    zyx_from_quat,
)
from .physics.momentum import MomentumMap
from .problem.build import problem_from_scenario
from .problem.constraints import Clearance, scenario_constraints
from .problem.endpoints import check_endpoints, goal_turn_limit
from .problem.residual import Problem
from .problem.scenario import Scenario, scenario_of
from .problem.simple_bound import SimpleMotionBound, inertia_ratio, simple_motion_bound, turn_limit
from .progress import LOGGER
from .robot.light_base import warn_light_base, warn_unphysical
from .solvers.branch_stop import singular
from .solvers.loop_start import stays_put
from .solvers.options import SolveOptions
from .solvers.reach import (
    DEFAULT_MAX_ANGLE,
    DirectionReach,
    ReachEstimate,
    default_directions,
    reach_set,
)
from .solvers.search import freedom_candidates

__all__ = [
    "DEFAULT_BUDGET",
    "SMALL_REACH_DEG",
    "DirectionLimits",
    "ReachReport",
    "inner_family",
    "reachable",
]

#: Residual evaluations per continuation pass of a direction of the inner estimate (a count;
#: ``--budget``; :func:`~freefloat.solvers.reach.reach_set`).
DEFAULT_BUDGET = 30
#: Below this largest outer turn (deg) the report says the reach is small.
SMALL_REACH_DEG = 5.0
#: ``stopped_by`` of a direction whose inner turn was not estimated (budget 0).
NOT_ESTIMATED = "not estimated (budget 0)"
#: The inner estimate is reported rounded down to this (deg), so a printed goal lies inside.
REPORT_STEP_DEG = 0.01


@dataclass(frozen=True)
class DirectionLimits:
    """Reach about one axis from the drift attitude.

    Attributes:
        axis: unit axis, base frame at the drift attitude.
        outer: largest turn a simple motion can give about it (rad).
        inner: largest turn reached by a solved path, rounded down to
            :data:`REPORT_STEP_DEG` (rad).
        stopped_by: why the inner estimate stopped short of ``outer`` ("" if it did not).
        breaks: a velocity or effort limit the path at ``inner`` breaks at this duration.
        goal_quaternion: the attitude at ``inner``, ``[x, y, z, w]`` (world).
        goal_zyx_deg: the same as yaw, pitch, roll (deg), for a scenario's ``base_zyx_deg``.
    """

    axis: np.ndarray
    outer: float
    inner: float
    stopped_by: str
    breaks: str
    goal_quaternion: np.ndarray
    goal_zyx_deg: np.ndarray


@dataclass(frozen=True)
class ReachReport:
    """Drift attitude, outer bound and inner estimate of a scenario's reachable attitudes.

    Attributes:
        robot: the robot's name.
        planar: whether the robot is planar (then ``directions`` are +- its axis).
        start_quaternion: the start attitude ``[x, y, z, w]``.
        drift_quaternion: where the plain quintic path leaves the spacecraft.
        drift_zyx_deg: the same as yaw, pitch, roll (deg).
        bound: the simple-motion bound (turn from the start attitude; spatial robots).
        inertia_ratio: spacecraft over arm rotational inertia about the system CM at the start.
        directions: per direction, the outer and inner reach.
        freedom: free coefficients per joint of the inner estimate's path family.
        evaluations: residual evaluations spent on the inner estimate (those of worker
            processes included: the same count whatever the jobs).
        budget: the evaluation budget per continuation pass of a direction.
        goal_joints: the goal joint values every direction is reached with (rad, or m for
            prismatic joints), in joint order.
        end_effector_goal: the scenario's goal is an end-effector goal, solved into
            ``goal_joints`` at its stated attitude: a goal of this report is one with these
            joints (solved anew at another attitude, the joints may move far, and with them
            the drift attitude and the reach).
        loops: the goal joints are the start joints: every motion is a closed loop, which
            no simple-motion bound covers (``outer`` 0); the inner estimate heads for
            :data:`~freefloat.solvers.reach.DEFAULT_MAX_ANGLE` from a loop on each axis.
        goal_judged: the constraints that judge a goal attitude (``[constraints.base_swing]``,
            say): the outer turns and where the inner estimate heads stop where a goal would
            break one.
        drift_breaks: ``"name (detail)"`` of such a constraint the drift attitude itself
            breaks ("" if none): no goal about it plans.
    """

    robot: str
    planar: bool
    start_quaternion: np.ndarray
    drift_quaternion: np.ndarray
    drift_zyx_deg: np.ndarray
    bound: SimpleMotionBound | None
    inertia_ratio: float
    directions: tuple[DirectionLimits, ...]
    freedom: tuple[int, ...]
    evaluations: int
    budget: int
    goal_joints: np.ndarray
    end_effector_goal: bool
    loops: bool = False
    goal_judged: tuple[str, ...] = ()
    drift_breaks: str = ""

    @property
    def largest_outer(self) -> float:
        """Largest outer turn over the directions (rad)."""
        return max((d.outer for d in self.directions), default=0.0)

    def estimate(self) -> ReachEstimate:
        """The inner estimate as a :class:`ReachEstimate` (for its figure)."""
        return ReachEstimate(
            self.drift_quaternion,
            tuple(
                DirectionReach(d.axis, d.inner, d.outer, d.stopped_by, 0, None, d.breaks)
                for d in self.directions
            ),
            self.freedom,
        )


def _limits(
    drift: np.ndarray, axis: np.ndarray, outer: float, reached: DirectionReach | None
) -> DirectionLimits:
    step = math.radians(REPORT_STEP_DEG)
    inner = outer if reached is None else math.floor(reached.reached / step + 1e-9) * step
    goal = quat_multiply(drift, quat_exp(inner * axis))
    return DirectionLimits(
        axis=axis,
        outer=outer,
        inner=inner,
        stopped_by="" if reached is None else reached.stopped_by,
        breaks="" if reached is None else reached.breaks,
        goal_quaternion=goal,
        goal_zyx_deg=np.degrees(zyx_from_quat(goal)),
    )


def reachable(
    scenario: Scenario | str | os.PathLike,
    travel_factor: float = 1.0,
    budget: int = DEFAULT_BUDGET,
    directions: np.ndarray | None = None,
    progress: Callable[[int, int, DirectionReach], None] | None = None,
    jobs: int | None = None,
) -> ReachReport:
    """Drift attitude, outer bound and inner estimate of the scenario's reachable attitudes.

    The scenario's goal attitude is ignored (its joints are used; an end-effector goal is solved
    into joints at the stated attitude, :attr:`ReachReport.goal_joints`, and a goal of the
    report is one with those joints). Nothing is written except an inline servicer's URDF into
    its cache.

    Args:
        scenario: the request (or the path of its TOML file).
        travel_factor: ``k >= 1`` of the outer bound (1: every joint monotone).
        budget: residual evaluations per continuation pass of a direction of the inner
            estimate (a count: a direction makes one pass, and more where it confirms its turn
            or imposes a deferred constraint such as clearance); 0: the
            drift attitude and the outer bound only (every ``inner`` is 0).
        directions: rotation axes (rows, base frame); default the six axes and eight diagonals.
        progress: called after each direction of the inner estimate (with several jobs, in
            the order the directions finish).
        jobs: worker processes for the inner estimate's directions (1: in this process);
            default the usable cores, at most one per direction. The report is the same, bit
            for bit, whatever the jobs (:func:`freefloat.parallel.run_tasks`).

    Raises:
        InputLimitError: ``jobs`` is not a whole number from 1 to
            :data:`~freefloat.parallel.MAX_JOBS`.
        JointLimitError: the start or goal joints outside their limits.
        CollisionError: the start or goal closer than the clearance margin, as ``plan``
            refuses it (a spatial robot's only with a budget: the inner estimate's claim).
        EndpointError: the start or goal breaks a constraint of the pose alone (an
            end-effector cone), under the same condition.
    """
    check_jobs(jobs, "jobs")
    scenario = scenario_of(scenario)
    end_effector_goal = bool(scenario.goal_poses)
    scenario = scenario.resolved()
    scenario.write_robot()
    warn_light_base(scenario.robot)
    warn_unphysical(scenario.robot)
    probe = problem_from_scenario(scenario, check_bounds=False)
    mmap = MomentumMap(scenario.robot)
    ratio = inertia_ratio(mmap, probe.family.start)
    if probe.planar:
        check_endpoints(scenario, scenario_constraints(scenario), end_effector_goal)  # as plan
        return _planar_report(scenario, probe, ratio, end_effector_goal)
    problem = inner_family(scenario)
    start = problem.start_quaternion
    drift = problem.achieved(np.zeros(problem.n_free))
    bound = simple_motion_bound(mmap, problem.family.start, problem.family.goal, travel_factor)
    moved = relative_quat(start, drift)
    axes = default_directions() if directions is None else np.atleast_2d(directions)
    axes = axes / np.linalg.norm(axes, axis=1, keepdims=True)
    constraints = scenario_constraints(scenario)
    outer = np.array(
        [
            goal_turn_limit(constraints, moved, axis, turn_limit(moved, axis, bound.bound))
            for axis in axes
        ]
    )
    loops = scenario.robot.n > 1 and stays_put(problem)  # every motion a closed loop
    before = problem.evaluations
    if budget > 0:  # as plan refuses them: no goal of this scenario plans
        check_endpoints(scenario, constraints, end_effector_goal)
    if scenario.robot.n == 1:  # every path reaches the drift attitude (method.md section 6)
        freedom = tuple(d - 5 for d in problem.family.degrees)
        found = tuple(
            replace(_limits(drift, axis, 0.0, None), stopped_by=ONE_JOINT) for axis in axes
        )
    else:  # joints that end where they start move in loops: no simple-motion bound holds
        heading = (
            np.array([goal_turn_limit(constraints, moved, a, DEFAULT_MAX_ANGLE) for a in axes])
            if loops
            else outer
        )
        estimate = _inner(scenario, problem, drift, axes, heading, budget, progress, jobs)
        freedom = estimate.freedom
        found = tuple(
            _limits(drift, axis, float(limit), reached)
            for axis, limit, reached in zip(axes, outer, estimate.directions, strict=True)
        )
    judged = [
        (c, e, e.value <= 0.0) for c in constraints if (e := c.at_attitude(moved)) is not None
    ]
    return ReachReport(
        robot=scenario.robot.name,
        planar=False,
        start_quaternion=start,
        drift_quaternion=drift,
        drift_zyx_deg=np.degrees(zyx_from_quat(drift)),
        bound=bound,
        inertia_ratio=ratio,
        directions=found,
        freedom=freedom,
        evaluations=problem.evaluations - before,
        budget=budget,
        goal_joints=problem.family.goal.copy(),
        end_effector_goal=end_effector_goal,
        loops=loops,
        goal_judged=tuple(c.name for c, _, _ in judged),
        drift_breaks=next((f"{c.name} ({e.detail})" for c, e, ok in judged if not ok), ""),
    )


def inner_family(scenario: Scenario) -> Problem:
    """The spatial problem of the inner estimate, its freedom as the planner would start.

    The scenario's ``[path] extra``, or else the planner's first freedom level whose map is
    not singular at the plain quintic path. Continuation cannot start from a path where the
    residual's Jacobian loses rank (its tangent is then meaningless): the planner goes on to
    its next level there, and so does the estimate (the last level when every one is).
    """
    if scenario.extra is not None:
        return problem_from_scenario(scenario, extra=scenario.extra, check_bounds=False)
    levels = freedom_candidates(scenario.robot.n, 3, continuation=True)
    for extra in levels:
        problem = problem_from_scenario(scenario, extra=extra, check_bounds=False)
        _, jacobian = problem.residual_and_jacobian(np.zeros(problem.n_free))
        if not singular(jacobian):
            break
    return problem


def _inner(
    scenario: Scenario,
    problem: Problem,
    drift: np.ndarray,
    axes: np.ndarray,
    outer: np.ndarray,
    budget: int,
    progress: Callable[[int, int, DirectionReach], None] | None,
    jobs: int | None,
) -> ReachEstimate:
    """The inner estimate towards the outer turns ``outer`` (rad) about ``axes``."""
    if budget <= 0:  # the drift attitude and the outer bound only
        skipped = DirectionReach(np.zeros(3), 0.0, 0.0, NOT_ESTIMATED, 0)
        freedom = tuple(d - 5 for d in problem.family.degrees)
        return ReachEstimate(drift, (skipped,) * len(axes), freedom)
    constraints = scenario_constraints(scenario)
    workers = default_jobs(len(axes)) if jobs is None else jobs
    LOGGER.info("reach: %d directions %s", len(axes), where_run(workers, len(axes)))
    with one_blas_thread():  # many tiny products: see freefloat._blas
        return reach_set(
            problem,
            axes,
            outer,
            constraints,
            SolveOptions(max_evaluations=budget),
            progress,
            deferred=[c for c in constraints if isinstance(c, Clearance)],
            step=math.radians(REPORT_STEP_DEG),
            jobs=workers,
        )


#: Why a one-joint planar robot's reach is nil.
ONE_JOINT = "one joint: every path turns the spacecraft alike"


def _planar_report(
    scenario: Scenario, problem: Problem, ratio: float, end_effector_goal: bool
) -> ReachReport:
    """The planar bounds as a reach report: +- the planar axis from the drift attitude."""
    interval = problem.bounds_interval
    if interval is None:
        raise ValueError("a planar problem without planar bounds")
    start = problem.start_quaternion
    drift = problem.achieved(np.zeros(problem.n_free))
    change = float(relative_rotvec(start, drift) @ problem.axis)
    lo, hi = interval
    axis = np.asarray(problem.axis, dtype=float)
    directions: tuple[DirectionLimits, ...] = (
        _limits(drift, axis, max(hi - change, 0.0), None),
        _limits(drift, -axis, max(change - lo, 0.0), None),
    )
    if scenario.robot.n == 1:  # the bounds are the one change every path makes
        directions = tuple(replace(d, stopped_by=ONE_JOINT) for d in directions)
    return ReachReport(
        robot=scenario.robot.name,
        planar=True,
        start_quaternion=start,
        drift_quaternion=drift,
        drift_zyx_deg=np.degrees(zyx_from_quat(drift)),
        bound=None,
        inertia_ratio=ratio,
        directions=directions,
        freedom=tuple(d - 5 for d in problem.family.degrees),
        evaluations=0,
        budget=0,
        goal_joints=problem.family.goal.copy(),
        end_effector_goal=end_effector_goal,
        loops=scenario.robot.n > 1 and stays_put(problem),
    )
