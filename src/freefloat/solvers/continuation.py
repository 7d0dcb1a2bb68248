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
from dataclasses import dataclass
from functools import partial

import numpy as np

from ..errors import UnreachableAttitudeError
from ..physics.attitude import quat_conjugate, quat_exp, quat_log, quat_multiply
from ..problem.constraints import DEFAULT_INSTANTS, Constraint
from ..problem.residual import Problem
from ..progress import heartbeat
from .multistart import multistart
from .options import POLISH, Attempt, SolveOptions
from .predictor import newton_correction, tangent
from .restore import Broken, broken_constraint, first_broken
from .rows import NO_DIPS, RowCache, linear_rows, with_critical, with_dips, with_picked
from .tracked import BranchPoint, ContinuationResult

__all__ = ["ContinuationResult", "continuation", "track"]

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
#: Newton iterations per corrector.
CORRECTOR_ITERATIONS = 8
#: Why a continuation stops when no path within the constraints is found at its start.
NO_START = "no path within the constraints reaches even the quintic path's own attitude"
#: Singular-value ratio below which dh/dbeta counts as singular.
SINGULAR = 1e-9


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


def _target(problem: Problem, start: np.ndarray, delta: np.ndarray, lam: float) -> Problem:
    return problem.with_goal(quat_multiply(start, quat_exp(lam * delta)))


def _correct(
    problem: Problem,
    constraints: Sequence[Constraint],
    beta: np.ndarray,
    tol: float,
    instants: np.ndarray,
    cache: RowCache,
    dips: np.ndarray = NO_DIPS,
) -> tuple[np.ndarray | None, np.ndarray, np.ndarray, int]:
    """Newton corrector from ``beta``: (solved beta or None, residual, Jacobian, iterations).

    The instants the constraints with their own instants pick at each iterate are kept for
    the next ones (:func:`.rows.with_picked`): rows that jump with the iterate would let
    Newton chase them instead of converging. The corrector gives up early when a Newton step
    did not halve the residual (the predicted step was too long), except once: after a step
    that took the path back inside rows, which may raise the residual.
    """
    r, jac = problem.residual_and_jacobian(beta)
    previous, was_inside, excused = math.inf, True, False
    for iteration in range(1, CORRECTOR_ITERATIONS + 1):
        norm = float(np.linalg.norm(r))
        g, g_mat = linear_rows(problem, constraints, beta, instants, cache, dips)
        dips = with_picked(problem, constraints, beta, dips)
        inside = _inside(g)
        if norm < tol and inside:
            return beta, r, jac, iteration
        if iteration > 2 and norm > 0.5 * previous and norm > 1e3 * tol:
            if was_inside or excused:
                break  # not contracting: the step was too long
            excused = True
        d = newton_correction(jac, r, g, g_mat)
        if d is None:
            break
        beta, previous, was_inside = beta + d, norm, inside
        r, jac = problem.residual_and_jacobian(beta)
    g = linear_rows(problem, constraints, beta, instants, cache, dips)[0]
    if float(np.linalg.norm(r)) < tol and _inside(g):
        return beta, r, jac, CORRECTOR_ITERATIONS
    return None, r, jac, CORRECTOR_ITERATIONS


def _inside(g: np.ndarray) -> bool:
    """Whether every linearised row ``g`` (its constraint's unit) is at or inside its limit."""
    return len(g) == 0 or float(np.max(g)) <= 0.0


def _dense_ok(problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray) -> bool:
    """Whether ``beta``'s path honours every constraint everywhere (exact dense check)."""
    return not broken_constraint(problem, constraints, beta)


def _ahead(
    problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray, tangent: np.ndarray
) -> Broken | None:
    """The first constraint a short step along ``tangent`` from ``beta`` would break, or None."""
    ahead = beta + tangent * 0.05
    for constraint in constraints:
        if constraint.applies_to(problem.robot):
            excess = constraint.violation(problem, ahead)
            if excess.value > 0.0:
                return Broken(constraint.name, excess.detail)
    return None


def _why(blocked: Broken | None, jac: np.ndarray) -> str:
    """Why the branch cannot go on: a constraint ahead, a singular map, or freedom."""
    if blocked is not None:
        return f"{blocked.name}: {blocked.detail}"
    sigma = np.linalg.svd(jac, compute_uv=False)
    if sigma[-1] < SINGULAR * max(sigma[0], 1e-300) or sigma[-1] < 1e-9:
        return "a singular map (dh/dbeta loses rank)"
    return "freedom exhausted (the corrector does not converge with this path family)"


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
    """
    zero = np.zeros(problem.n_free) if origin is None else np.asarray(origin, dtype=float)
    start = problem.achieved(zero)
    delta = quat_log(quat_multiply(quat_conjugate(start), problem.goal_quaternion))
    angle = float(np.linalg.norm(delta))
    axis = delta / angle if angle > 0 else np.array([0.0, 0.0, 1.0])
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
        solved, r, jac, iterations = _correct(
            here, constraints, beta, INTERMEDIATE_TOLERANCE, instants, cache
        )
        if solved is None:  # the start could not be brought within what it broke
            return ContinuationResult(beta, 0, angle, axis, r, 0, iterations, NO_START, broke.name)
        beta = solved
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
            blocked = _ahead(problem, constraints, beta, tangent)
            gain = lam - reached[steps - PACE_WINDOW]
            stopped_by = (
                f"{_why(blocked, jac)} (stalled: "
                f"{math.degrees(gain * angle):.2g} deg in the last {PACE_WINDOW} steps)"
            )
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
        at = _Rows(instants, dips, cache)
        done = _step(problem, target, constraints, beta + step * tangent, tol, at)
        iterations, instants, dips = iterations + done.spent, done.instants, done.dips
        if done.beta is None:
            reached.append(lam)
            dl = 0.5 * step
            if dl * angle < MIN_STEP:
                blocked = _ahead(problem, constraints, beta, tangent)
                stopped_by = _why(blocked, jac)
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


@dataclass(frozen=True)
class _Step:
    """One continuation step's corrected path (:func:`_step`).

    Attributes:
        beta: the corrected path's free coefficients (rad or m), None when none was found.
        residual: its residual (rad).
        jacobian: the residual's Jacobian there (rad per unit of ``beta``).
        iterations: the first corrector's Newton iterations (they set the next step).
        spent: every corrector's iterations.
        instants: the instants now imposed (normalised).
        dips: the instants where the dense check found a dip, now imposed on the constraints
            with their own instants (:func:`.rows.with_dips`; normalised).
    """

    beta: np.ndarray | None
    residual: np.ndarray
    jacobian: np.ndarray
    iterations: int
    spent: int
    instants: np.ndarray
    dips: np.ndarray


@dataclass(frozen=True)
class _Rows:
    """Where a step's rows sit: the instants, the dips (see :class:`_Step`) and the row cache."""

    instants: np.ndarray
    dips: np.ndarray
    cache: RowCache


def _step(
    problem: Problem,
    target: Problem,
    constraints: Sequence[Constraint],
    predicted: np.ndarray,
    tol: float,
    at: _Rows,
) -> _Step:
    """Correct the ``predicted`` path onto ``target`` (``tol``, rad), then densely inside."""
    solved, r, jac, its = _correct(
        target, constraints, predicted, tol, at.instants, at.cache, at.dips
    )
    if solved is not None and not _dense_ok(problem, constraints, solved):
        return _densely(problem, target, constraints, solved, tol, at, its)
    return _Step(solved, r, jac, its, its, at.instants, at.dips)


def _stalled(lam: float, reached: Sequence[float], steps: int) -> bool:
    """Whether, at the pace of the last :data:`PACE_WINDOW` steps, the goal is out of reach.

    ``lam``: the fraction of the way reached (0-1); ``reached``: ``lam`` after each step.
    """
    if steps < PACE_WINDOW:
        return False
    gain = lam - reached[steps - PACE_WINDOW]
    return lam + gain * (MAX_STEPS - steps) / PACE_WINDOW < 1.0


def _densely(
    problem: Problem,
    target: Problem,
    constraints: Sequence[Constraint],
    solved: np.ndarray,
    tol: float,
    at: _Rows,
    spent: int,
) -> _Step:
    """Correct a path inside at the instants but not everywhere, at its tightest instants.

    Up to three times: add the path's tightest instants, and the instants of its dips below
    the limit of a constraint with its own instants (:func:`.rows.with_dips`), and correct
    again. ``spent``: the corrector iterations so far. Returns the step with its path (None
    when it stays outside) and the instants and dips now imposed.
    """
    r = jac = np.zeros(0)
    instants, dips, first = at.instants, at.dips, spent
    for _ in range(3):
        instants = with_critical(problem, constraints, solved, instants)
        dips = with_dips(problem, constraints, solved, dips)
        found, r, jac, more = _correct(target, constraints, solved, tol, instants, at.cache, dips)
        spent += more
        if found is None:
            return _Step(None, r, jac, first, spent, instants, dips)
        solved = found
        if _dense_ok(problem, constraints, solved):
            return _Step(solved, r, jac, first, spent, instants, dips)
    return _Step(None, r, jac, first, spent, instants, dips)


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
        reached_fraction=result.fraction,
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
    phrase = UnreachableAttitudeError.turn_phrase(result.fraction * result.angle, result.angle)
    where = f"axis {axis} from the {origin} path's attitude"
    attempt.message = f"{phrase} about this direction ({where}); stopped by {result.stopped_by}"
    return attempt
