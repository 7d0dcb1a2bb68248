"""Reachable attitude set of a spatial problem, estimated from inside by continuation.

From the attitude the quintic path reaches (from a loop on the axis when it stays put,
:func:`.loop_start.loop_on_axis`), continuation (:func:`.continuation.track`) heads towards
a far goal in each of a set of directions and stops where it cannot go on (a joint's limit,
a singular map, the freedom of the path family). The attitudes up to that angle were reached
by solved paths within the constraints, so these segments are an *inner* estimate of the
reachable set with the given freedom. (The planner heading for a nearer goal takes the same
steps but its own last one, which can fail where the traced ones did not: docs/reach.md.)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np

from ..parallel import run_tasks
from ..physics.attitude import quat_exp, quat_multiply
from ..problem.constraints import Constraint, default_constraints
from ..problem.residual import Problem
from .continuation import ContinuationResult, held_fraction, track
from .drift_start import (
    RESTORED_SHORT,
    DriftStart,
    confirmed_from,
    drift_start,
    rounded_down,
)
from .loop_start import LOOP_TURN, loop_on_axis, stays_put
from .options import SolveOptions
from .restore import broken_constraint, broken_rows_first
from .tracked import BranchPoint

__all__ = ["DirectionReach", "ReachEstimate", "default_directions", "reach_set"]


@dataclass(frozen=True)
class DirectionReach:
    """How far continuation got in one direction.

    Attributes:
        axis: unit rotation axis (base frame at the quintic path's attitude).
        reached: largest rotation about ``axis`` reached by a solved path (rad).
        asked: the rotation continuation headed for (rad).
        stopped_by: why it stopped ("" when it reached ``asked``).
        evaluations: residual evaluations spent on this direction.
        beta: free coefficients of the path that reaches ``reached`` (rad or m).
        breaks: a lazy constraint (velocity or effort limits) that path breaks at the
            problem's duration ("" when none): planning would ask for a longer duration.
    """

    axis: np.ndarray
    reached: float
    asked: float
    stopped_by: str
    evaluations: int
    beta: np.ndarray | None = None
    breaks: str = ""


@dataclass(frozen=True)
class ReachEstimate:
    """Inner estimate of the reachable attitude set around the quintic path's attitude.

    Attributes:
        quintic_quaternion: attitude reached by the plain quintic path, ``[x, y, z, w]``.
        directions: per direction, how far continuation got.
        freedom: free coefficients per joint of the path family used.
    """

    quintic_quaternion: np.ndarray
    directions: tuple[DirectionReach, ...]
    freedom: tuple[int, ...]


def default_directions() -> np.ndarray:
    """The six axis directions, then the eight cube diagonals (unit rows, (14, 3))."""
    axes = np.vstack([np.eye(3), -np.eye(3)])
    corners = np.array(
        [[x, y, z] for x in (1.0, -1.0) for y in (1.0, -1.0) for z in (1.0, -1.0)]
    ) / math.sqrt(3.0)
    return np.vstack([axes, corners])


#: The rotation each direction heads for by default (rad).
DEFAULT_MAX_ANGLE = math.radians(60.0)
#: Tries to confirm a direction's furthest turn as the planner would solve it (a count).
CONFIRM_TRIES = 3


def _target(problem: Problem, quintic: np.ndarray, axis: np.ndarray, angle: float) -> Problem:
    """The problem heading for ``angle`` (rad) about ``axis`` from the drift attitude."""
    return problem.with_goal(quat_multiply(quintic, quat_exp(angle * axis)))


def _furthest(
    problem: Problem,
    quintic: np.ndarray,
    axis: np.ndarray,
    angle: float,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    stall: bool,
    trace: list[BranchPoint] | None = None,
    origin: np.ndarray | None = None,
) -> ContinuationResult:
    """Continuation towards ``angle`` about ``axis`` (rad) within ``constraints``.

    From ``origin`` (a path on the branch towards that axis; default the quintic path),
    accepted points appended to ``trace``.
    """
    return track(_target(problem, quintic, axis, angle), constraints, options, origin, stall, trace)


def _parting(trace: Sequence[BranchPoint], turn: float) -> BranchPoint:
    """Where a continuation towards ``turn`` (rad) leaves the traced branch.

    The continuation's steps are angles, so one heading for a nearer goal about the same
    axis tries the same targets as the traced one until a step would reach its goal: the
    first traced point whose next step reaches ``turn``. From there on it takes a shorter
    last step of its own.
    """
    for point in trace:
        if point.turn + point.next_step >= turn:
            return point
    return trace[-1]


def _confirmed(
    problem: Problem,
    quintic: np.ndarray,
    axis: np.ndarray,
    reached: float,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    step: float,
    trace: Sequence[BranchPoint],
) -> tuple[float, np.ndarray]:
    """The largest turn up to ``reached`` that the planner's own continuation solves.

    Tracking towards a farther goal (``trace``) solves the points on the way only to the
    intermediate tolerance; the planner heads for the goal itself (final tolerance, stall
    check), taking the traced steps up to where it parts from the branch (:func:`_parting`):
    resumed from there. The turn is rounded down to a multiple of ``step`` (rad; 0: not),
    as reported; when the planner stops short, the next try (at most :data:`CONFIRM_TRIES`)
    asks for the traced point before. Returns the turn (rad) and its path.
    """
    for _ in range(CONFIRM_TRIES):
        reached = rounded_down(reached, step)
        if reached <= 0.0:
            break
        part = _parting(trace, reached)
        result = _furthest(
            problem, quintic, axis, reached, constraints, options, True, None, part.beta
        )
        if result.reached:
            return reached, result.beta
        reached = max((b.turn for b in trace if b.turn < reached - step), default=0.0)
    return 0.0, trace[0].beta


def _imposed(
    problem: Problem,
    quintic: np.ndarray,
    axis: np.ndarray,
    angle: float,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    step: float,
    origin: np.ndarray,
) -> tuple[float, str, np.ndarray]:
    """The planner's continuation within ``constraints`` towards ``angle`` (rad), rounded.

    From ``origin`` (a path at the drift attitude). Where it stops short, the turn it reached
    is confirmed (:func:`_confirmed`). Returns the turn (rad), why it stopped short ("" when
    it did not) and its path.
    """
    angle = rounded_down(angle, step)
    if angle <= 0.0:
        return 0.0, "", origin
    trace: list[BranchPoint] = []
    result = _furthest(problem, quintic, axis, angle, constraints, options, True, trace, origin)
    if result.reached:
        return angle, "", result.beta
    turn, beta = _confirmed(
        problem, quintic, axis, result.fraction * angle, constraints, options, step, trace
    )
    return turn, result.stopped_by, beta


def _direction(
    problem: Problem,
    quintic: np.ndarray,
    axis: np.ndarray,
    angle: float,
    tracked: Sequence[Constraint],
    eager: Sequence[Constraint],
    options: SolveOptions,
    confirm: bool,
    step: float,
    origin: np.ndarray,
) -> tuple[float, str, np.ndarray]:
    """How far one direction goes: the turn (rad), why it stopped short, its path.

    From ``origin``, a path at the drift attitude within the eager constraints
    (:func:`.drift_start.drift_start`). The deferred constraints (``eager`` but not
    ``tracked``) are checked on the path where the direction ends; only when that path breaks
    one is the direction tracked again with every eager constraint imposed, as the planner
    imposes them (:func:`_imposed`, from the turn reached without them: never farther), and
    the confirmation without them is
    skipped.
    """
    trace: list[BranchPoint] = []
    result = _furthest(problem, quintic, axis, angle, tracked, options, confirm, trace, origin)
    reached, stopped_by, beta = result.fraction * angle, result.stopped_by, result.beta
    deferred = len(tracked) < len(eager)
    if not confirm:  # the bounds estimate: as far as the budget goes
        if deferred and broken_constraint(problem, eager, beta):
            result = _furthest(problem, quintic, axis, angle, eager, options, False, None, origin)
        if not result.reached:  # as far as the path covers on the problem's own grid
            target = _target(problem, quintic, axis, angle)
            return held_fraction(target, result) * angle, result.stopped_by, result.beta
        return angle, result.stopped_by, result.beta
    broken = broken_rows_first(problem, eager, beta) if deferred else ""
    if not result.reached and not broken:  # solved only to the intermediate tolerance
        reached, beta = _confirmed(problem, quintic, axis, reached, tracked, options, step, trace)
        broken = broken_rows_first(problem, eager, beta) if deferred and reached > 0.0 else ""
    if broken:  # as the planner solves it, with every eager constraint imposed
        reached, why, beta = _imposed(problem, quintic, axis, reached, eager, options, step, origin)
        stopped_by = why or stopped_by
    return reached, stopped_by, beta


#: Called after each direction: (directions done, in all, its reach), in the order they finish.
ReachProgress = Callable[[int, int, DirectionReach], None]


@dataclass(frozen=True)
class _Spent:
    """One direction's reach and the momentum-map evaluations it spent (a count)."""

    reach: DirectionReach
    map_evaluations: int


@dataclass(frozen=True)
class _Shared:
    """What every direction of :func:`reach_set` reads (the quintic attitude ``[x, y, z, w]``)."""

    problem: Problem
    quintic: np.ndarray
    start: DriftStart
    tracked: tuple[Constraint, ...]
    eager: tuple[Constraint, ...]
    lazy: tuple[Constraint, ...]
    options: SolveOptions
    confirm: bool
    step: float


def _one_direction(shared: _Shared, axis: np.ndarray, angle: float) -> _Spent:
    """One direction of :func:`reach_set`: about ``axis`` (base frame), up to ``angle`` (rad)."""
    problem, start, eager = shared.problem, shared.start, list(shared.eager)
    axis = axis / np.linalg.norm(axis)
    angle = float(angle)
    before, maps = problem.evaluations, problem.map_evaluations
    # no path within the constraints at the drift attitude: none to report
    reached, stopped_by, beta = 0.0, start.why_not, start.beta
    origin, quintic, offset = start.beta, shared.quintic, 0.0
    if angle > 0.0 and origin is not None and stays_put(problem):  # loops: start on one
        loop = loop_on_axis(problem, quintic, axis, eager, shared.options, min(angle, LOOP_TURN))
        origin, stopped_by, offset, beta = loop.beta, loop.why_not, loop.turn, loop.beta
        quintic, reached = quat_multiply(quintic, quat_exp(offset * axis)), offset
    if angle > offset and origin is not None:  # (from a loop: the turns go on from it)
        reached, stopped_by, beta = _direction(
            problem,
            quintic,
            axis,
            angle - offset,
            list(shared.tracked),
            eager,
            shared.options,
            shared.confirm,
            shared.step,
            origin,
        )
        reached += offset
        if shared.confirm and start.restored is not None and reached > 0.0:
            target = partial(_target, problem, shared.quintic, axis)
            found = confirmed_from(
                start.restored, target, reached, eager, shared.options, shared.step
            )
            if found.halved:
                said = "this turn" if found.turn > 0.0 else "no turn about this axis"
                stopped_by = RESTORED_SHORT.format(said)
            # turn 0: the drift attitude, which the path every direction starts on reaches
            reached, beta = found.turn, found.beta if found.turn > 0.0 else origin
    lazy = list(shared.lazy)
    breaks = broken_constraint(problem, lazy, beta) if lazy and beta is not None else ""
    evaluations = problem.evaluations - before
    direction = DirectionReach(axis, reached, angle, stopped_by, evaluations, beta, breaks)
    return _Spent(direction, problem.map_evaluations - maps)


def reach_set(
    problem: Problem,
    directions: np.ndarray | None = None,
    max_angle: float | np.ndarray = DEFAULT_MAX_ANGLE,
    constraints: Sequence[Constraint] | None = None,
    options: SolveOptions | None = None,
    progress: ReachProgress | None = None,
    deferred: Sequence[Constraint] = (),
    confirm: bool = True,
    step: float = 0.0,
    jobs: int = 1,
) -> ReachEstimate:
    """Continue as far as possible from the quintic attitude in each direction.

    With ``confirm`` each direction is tracked as the planner tracks a goal there (its
    continuation with the stall check); when it stops short, the turn where it stopped is
    confirmed as the planner would solve it (:func:`_confirmed`).

    The constraints planning imposes from the start are tracked; the lazy ones (imposed by
    planning only once a path breaks them: velocity and effort limits) are checked on the
    furthest path of each direction and named in :attr:`DirectionReach.breaks`, as planning
    would find them. Constraints in ``deferred`` (costly ones such as clearance) are checked
    on that furthest path too, and only when it breaks one is the direction tracked again with
    it imposed. Every budget is a count (``options.max_evaluations`` per direction and pass).

    The directions are independent: each one's result depends on the problem, its axis and
    angle and the constraints alone, so ``jobs`` worker processes
    (:func:`freefloat.parallel.run_tasks`) give the same estimate, bit for bit, in the same
    order; the problem's evaluation counter then counts the workers' evaluations too.

    Args:
        problem: a spatial problem (its goal is ignored; not changed).
        directions: rotation axes (rows, base frame); default :func:`default_directions`.
        max_angle: the rotation to head for in each direction (rad, below pi): one for all,
            or one per direction (e.g. an outer bound of that direction).
        constraints: path constraints; default joint position, velocity and effort limits.
        options: solver settings (the evaluation budget applies per continuation pass: a
            direction makes one, and up to :data:`CONFIRM_TRIES` more each time it confirms a
            turn, plus one when it imposes a deferred constraint; when the quintic path breaks
            a constraint, one pass shared by every direction reaches the drift attitude first
            and up to :data:`~.drift_start.RESTORED_TRIES` more confirm each turn from plan's
            restored start, :mod:`.drift_start`).
        progress: called after each direction (see :data:`ReachProgress`).
        deferred: constraints among ``constraints`` to check at the end of a direction
            rather than track.
        confirm: track as the planner does and confirm where it stops (see above); False
            tracks each direction to its budget without the stall check and reports where it
            got, solved to the intermediate tolerance on the intermediate grid (``freefloat
            bounds``; :mod:`.continuation`).
        step: a turn that stops short is confirmed rounded down to a multiple of this (rad;
            0: not rounded), the precision it is reported at.
        jobs: worker processes (1: every direction in this process).
    """
    if problem.planar:
        raise ValueError("reach_set is for spatial problems; planar ones have exact bounds")
    options = options or SolveOptions()
    constraints = default_constraints() if constraints is None else list(constraints)
    eager = [c for c in constraints if not c.lazy]
    lazy = [c for c in constraints if c.lazy]
    tracked = [c for c in eager if not any(c is d for d in deferred)]
    directions = default_directions() if directions is None else np.atleast_2d(directions)
    angles = np.broadcast_to(np.asarray(max_angle, dtype=float), (len(directions),))
    quintic = problem.achieved(np.zeros(problem.n_free))
    shared = _Shared(
        problem,
        quintic,
        drift_start(problem, eager, options),  # shared by every direction
        tuple(tracked),
        tuple(eager),
        tuple(lazy),
        options,
        confirm,
        step,
    )

    def one(index: int) -> _Spent:
        return _one_direction(shared, np.asarray(directions[index], dtype=float), angles[index])

    finished = [0]

    def done(index: int, spent: _Spent) -> None:
        finished[0] += 1
        if progress is not None:
            progress(finished[0], len(directions), spent.reach)

    here, here_maps = problem.evaluations, problem.map_evaluations
    found = run_tasks(one, len(directions), jobs, done)
    if problem.evaluations == here:  # worker processes did the work: counted here
        problem.counter.evaluations = here + sum(f.reach.evaluations for f in found)
        problem.counter.map_evaluations = here_maps + sum(f.map_evaluations for f in found)
    freedom = tuple(d - 5 for d in problem.family.degrees)
    return ReachEstimate(quintic, tuple(f.reach for f in found), freedom)
