"""The ``continuation`` strategy: track the solution from the quintic attitude to the goal.

The quintic path (``beta = 0``) reaches its own attitude ``q_0`` exactly. The target slides
along the geodesic from ``q_0`` to the goal, ``q(lam) = q_0 exp(lam delta)`` with ``lam`` from
0 to 1 (``delta``: rotation vector, rad), and the solution ``beta(lam)`` is tracked:

- predictor: the minimum-norm tangent ``dbeta/dlam`` with ``J t = delta`` (at a solution the
  residual moves by ``-delta`` per unit ``lam``) whose predicted path keeps every linearised
  constraint row near its limit inside over the step (:func:`.predictor.tangent`);
- corrector: Newton steps with the exact Jacobian, each the minimum-norm correction ``d`` with
  ``J d = -h`` and every constraint linearised, ``g + G d <= 0`` (a small QP, quadprog);
- step size: doubled after an easy correction, halved after a failed one;
- grid: the targets on the way are solved to :data:`INTERMEDIATE_TOLERANCE` on half the
  problem's integration steps (:data:`INTERMEDIATE_STEPS`; at sixth order their error there is
  64 times that of the full grid, which is chosen for 1e-12 rad on the quintic path; along the
  shipped servicers' branches the two differ by at most 4e-6 rad, far below that tolerance;
  docs/method.md), the goal itself on the full grid to the final tolerance.

Every budget is a count (steps, residual evaluations), never a time, so the same problem gives
the same answer on any machine. When the step size falls below its floor, the strategy stops
and says how far it got (``reached_fraction``) and why (a constraint of a named joint, a
singular map, or the freedom of the path family exhausted). It also stops once stalled: when,
at the pace of its last :data:`PACE_WINDOW` steps, the rest of the step budget
(:data:`MAX_STEPS`) would end short of the goal (a count too, so as reproducible).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import partial

import numpy as np

from ..errors import UnreachableAttitudeError
from ..physics.attitude import quat_exp, quat_multiply, relative_rotvec
from ..problem.constraints import DEFAULT_INSTANTS, Constraint
from ..problem.residual import Problem
from ..progress import heartbeat
from .branch_stop import ahead, blocker, singular, why_stopped
from .corrector import Rows, correct, corrected_step
from .multistart import multistart
from .options import POLISH, Attempt, SolveOptions
from .predictor import tangent
from .restore import Broken, first_broken
from .rows import NO_DIPS, RowCache, linear_rows
from .tracked import BranchPoint, ContinuationResult

__all__ = ["ContinuationResult", "continuation", "held_fraction", "track"]

#: First step as an angle of the target's travel (rad).
FIRST_STEP = math.radians(3.0)
#: Smallest step, as an angle of the target's travel (rad; about 0.01 deg).
MIN_STEP = 1.7e-4
#: Largest number of continuation steps (accepted or not).
MAX_STEPS = 400
#: Steps over which the progress is measured for the pace check (see :func:`track`).
PACE_WINDOW = 20
#: Residual (rad) an intermediate corrector must reach (about 0.006 deg: the next step corrects
#: it anyway; only the goal itself is solved to the tolerance).
INTERMEDIATE_TOLERANCE = 1e-4
#: The targets on the way are solved on the problem's integration steps divided by this
#: (at least 16 steps): their tolerance allows it, and the node rates cost half as much.
INTERMEDIATE_STEPS = 2
#: Why a continuation stops when its corrector finds no path within the constraints at its
#: start (a local search: a path elsewhere may exist; the planner's restored start is one).
NO_START = (
    "its start path breaks a constraint and the corrector found no path within the "
    "constraints at that path's own attitude"
)


def _tangent(
    problem: Problem,
    constraints: Sequence[Constraint],
    beta: np.ndarray,
    jac: np.ndarray,
    delta: np.ndarray,
    instants: np.ndarray,
    cache: RowCache,
    step: float | None = None,
    dips: np.ndarray = NO_DIPS,
) -> np.ndarray:
    """:func:`.predictor.tangent` with the constraints' rows at ``beta`` (``step``: see there)."""
    g, g_mat = linear_rows(problem, constraints, beta, instants, cache, dips)
    return tangent(jac, delta, g, g_mat, step)


def _way(start: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """The geodesic from ``start`` to ``goal`` (``[x, y, z, w]``): rotation vector, angle, axis.

    The rotation vector and angle in rad, in the start's frame; the axis is z when they agree.
    """
    delta = relative_rotvec(start, goal)
    angle = float(np.linalg.norm(delta))
    return delta, angle, delta / angle if angle > 0 else np.array([0.0, 0.0, 1.0])


def _target(problem: Problem, start: np.ndarray, delta: np.ndarray, lam: float) -> Problem:
    return problem.with_goal(quat_multiply(start, quat_exp(lam * delta)))


def _where(reached: float, angle: float, steps: int, evaluations: int) -> str:
    """A progress line: how far along (rad, printed in deg) after how much work."""
    return (
        f"continuation: {math.degrees(reached):.4g} of {math.degrees(angle):.4g} deg after "
        f"{steps} steps ({evaluations} residual evaluations)"
    )


def track(
    problem: Problem,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    origin: np.ndarray | None = None,
    stall: bool = True,
    trace: list[BranchPoint] | None = None,
) -> ContinuationResult:
    """Continue from ``origin`` (default ``beta = 0``) at its own attitude towards the goal.

    ``origin`` is the quintic path, or a path within the constraints when the quintic path
    breaks one (the dispatcher's feasibility restoration). The problem is not changed (targets
    on the way are copies, :meth:`Problem.with_goal`). With ``stall`` (the planner's default)
    it stops once the pace of its last :data:`PACE_WINDOW` steps cannot reach the goal within
    the step budget; without, it goes on until a budget or the step floor stops it (the reach
    estimate of ``freefloat bounds``, which wants the furthest point within its budget).
    With ``trace``, the start and every accepted point are appended to it (the reach
    estimate resumes from them; those on the way are solved on the intermediate grid).
    Where the map is singular at the start (a path that does not move, say: every free
    coefficient's first-order effect on the attitude vanishes) there is no tangent to follow,
    and it stops there, "a singular map", without a step.
    """
    zero = np.zeros(problem.n_free) if origin is None else np.asarray(origin, dtype=float)
    start = problem.achieved(zero)
    delta, angle, axis = _way(start, problem.goal_quaternion)
    final_tol = POLISH * options.tolerance
    first_evaluation = problem.evaluations
    instants, dips = DEFAULT_INSTANTS, NO_DIPS
    cache: RowCache = {}
    beta, lam, iterations, steps = zero, 0.0, 0, 0
    here = _target(problem, start, delta, 0.0)
    coarse = problem.with_steps(max(problem.steps // INTERMEDIATE_STEPS, 16))  # on the way
    r, jac = here.residual_and_jacobian(beta)
    broke = first_broken(problem, constraints, beta)  # the quintic's: brought inside first
    if broke is not None:
        solved, r, jac, iterations = correct(
            here, constraints, beta, INTERMEDIATE_TOLERANCE, instants, cache
        )
        if solved is None:  # the start could not be brought within what it broke
            return ContinuationResult(beta, 0, angle, axis, r, 0, iterations, NO_START, broke.name)
        beta = solved
    if angle > 0.0 and singular(jac):  # no tangent to follow: a step would be meaningless
        why = why_stopped(None, jac)
        return ContinuationResult(beta, 0, angle, axis, r, 0, iterations, why, "")
    dl = min(1.0, FIRST_STEP / angle) if angle > 0 else 1.0
    if trace is not None:
        trace.append(BranchPoint(0.0, beta, dl * angle))
    stopped_by = ""
    blocked: Broken | None = None  # the constraint that stopped the branch, if one did
    reached = [0.0]  # lam after each step: the pace check's history
    while lam < 1.0:
        if steps >= MAX_STEPS:
            stopped_by = f"step budget ({MAX_STEPS} continuation steps)"
            break
        if stall and _stalled(lam, reached, steps):
            # At the pace of the last steps the step budget ends short of the goal: stop now
            # rather than spend the budget on the same refusal.
            tangent = _tangent(problem, constraints, beta, jac, delta, instants, cache, dips=dips)
            blocked = ahead(problem, constraints, beta, tangent, jac, dl)
            stopped_by = _stall_reason(blocked, jac, (lam - reached[steps - PACE_WINDOW]) * angle)
            break
        if problem.evaluations - first_evaluation > options.max_evaluations:
            stopped_by = f"evaluation budget ({options.max_evaluations} residual evaluations)"
            break
        steps += 1
        heartbeat(
            partial(_where, lam * angle, angle, steps, problem.evaluations - first_evaluation)
        )
        step = min(dl, 1.0 - lam)
        tangent = _tangent(problem, constraints, beta, jac, delta, instants, cache, step, dips)
        last = lam + step >= 1.0
        target = _target(problem if last else coarse, start, delta, 1.0 if last else lam + step)
        tol = final_tol if last else INTERMEDIATE_TOLERANCE
        at = Rows(instants, dips, cache)
        done = corrected_step(problem, target, constraints, beta + step * tangent, tol, at)
        iterations, instants, dips = iterations + done.spent, done.instants, done.dips
        if done.beta is None:
            reached.append(lam)
            dl = 0.5 * step
            if dl * angle < MIN_STEP:
                point = (beta, tangent, jac)
                blocked = blocker(problem, target, constraints, point, step, tol, at)
                stopped_by = why_stopped(blocked, jac)
                break
            continue
        beta, lam, r, jac = done.beta, 1.0 if last else lam + step, done.residual, done.jacobian
        reached.append(lam)
        its = done.iterations
        dl = step * (2.0 if its <= 4 else 1.0 if its <= 5 else 0.5)
        if trace is not None:
            trace.append(BranchPoint(lam * angle, beta, dl * angle))
    return ContinuationResult(
        beta, lam, angle, axis, r, steps, iterations, stopped_by, blocked.name if blocked else ""
    )


def _stall_reason(blocked: Broken | None, jac: np.ndarray, gain: float) -> str:
    """Why a stalled branch stops: :func:`.branch_stop.why_stopped` and its ``gain`` (rad)."""
    return (
        f"{why_stopped(blocked, jac)} (stalled: "
        f"{math.degrees(gain):.2g} deg in the last {PACE_WINDOW} steps)"
    )


def _stalled(lam: float, reached: Sequence[float], steps: int) -> bool:
    """Whether, at the pace of the last :data:`PACE_WINDOW` steps, the goal is out of reach.

    ``lam``: the fraction of the way reached (0-1); ``reached``: ``lam`` after each step.
    """
    if steps < PACE_WINDOW:
        return False
    gain = lam - reached[steps - PACE_WINDOW]
    return lam + gain * (MAX_STEPS - steps) / PACE_WINDOW < 1.0


def continuation(
    problem: Problem,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    start: np.ndarray | None = None,
) -> Attempt:
    """The strategy: :func:`track` from ``start``, then the goal's solution or how far it got."""
    result = track(problem, constraints, options, start)
    attempt = Attempt(
        method="continuation (tangent predictor, minimum-norm Newton corrector with constraints)",
        iterations=result.iterations,
        reached_fraction=result.fraction if result.reached else held_fraction(problem, result),
    )
    attempt.tried.append(
        f"continuation over {math.degrees(result.angle):.4g} deg in {result.steps} steps"
    )
    if result.reached:
        attempt.candidates.append(result.beta)  # the dispatcher recomputes its residual
        return attempt
    if problem.n_free == problem.n_equations:
        # A square system leaves the corrector no room to slide along a limit: the Newton-type
        # searches of the multistart strategy (counted budget) get their turn.
        fallback = multistart(problem, constraints, options, start)
        attempt.tried += [f"continuation stopped at {result.fraction_text} of the way"]
        attempt.tried += fallback.tried
        attempt.blocked_by = tuple(dict.fromkeys(attempt.blocked_by + fallback.blocked_by))
        if fallback.candidates:
            fallback.tried, fallback.blocked_by = attempt.tried, attempt.blocked_by
            return fallback
    attempt.stopped_by = result.stopped_by
    attempt.blocked_by = (result.blocked_by,) if result.blocked_by else ()
    attempt.last_beta = result.beta if result.fraction > 0.0 else None
    axis = ", ".join(f"{x:.3f}" for x in result.axis)
    origin = "starting" if start is not None and np.any(start) else "quintic"
    phrase = UnreachableAttitudeError.turn_phrase(
        attempt.reached_fraction * result.angle, result.angle
    )
    where = f"axis {axis} from the {origin} path's attitude"
    attempt.message = f"{phrase} about this direction ({where}); stopped by {result.stopped_by}"
    return attempt


def held_fraction(problem: Problem, result: ContinuationResult) -> float:
    """The fraction of the way the path a branch stopped on holds on the problem's own grid.

    Targets on the way are solved on a coarser grid (:data:`INTERMEDIATE_STEPS`); on a wild
    path its integration error can be large (ETS-VII heading 179 deg away: the path it stopped
    on is 0.011 deg from the goal on the coarse grid, 30.8 deg on the problem's). The
    fraction is then at most ``(angle - miss) / angle``, ``miss`` the path's distance to the
    goal on the problem's grid (rad): a refusal (or ``bounds``) never claims more of the way
    than the path it stopped on covers, and its figures agree.
    """
    if result.angle <= 0.0:
        return result.fraction
    miss = float(np.linalg.norm(problem.residual(result.beta)))
    return min(result.fraction, max(0.0, (result.angle - miss) / result.angle))
