"""Solve ``h(beta) = 0`` for the free path coefficients (docs/method.md section 5).

One dispatcher, one signature per strategy: ``strategy(problem, constraints, options) ->
Attempt``. The dispatcher picks the strategy from the problem's shape (or the one asked for),
then polishes the candidates with minimum-norm Gauss-Newton steps, keeps those whose path
honours every constraint, and certifies the attitude integration at the root of least norm
(doubling the steps of a copy of the problem when needed, and polishing the root again on the
finer grid); a root that this polishing moves onto a path breaking a constraint gives way to
the next one, if any stays within. The problem it is given is never changed.

A solution is returned only when the residual is below the tolerance; otherwise
:class:`~freefloat.errors.SolverError` reports the best residual reached and what was tried.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import NoReturn

import numpy as np

from ..errors import SolverError, UnreachableAttitudeError
from ..physics.attitude import relative_rotvec
from ..plugins import Registry, plugin_function
from ..problem.constraints import Constraint, default_constraints
from ..problem.residual import Problem
from .certify import Certified, certify
from .continuation import continuation
from .multistart import multistart
from .newton import polish
from .options import Attempt, Root, Solution, SolveOptions, Strategy
from .restore import broken_constraint, feasible_start, first_broken
from .scan import scan

__all__ = ["STRATEGIES", "choose_strategy", "solve"]

StrategyFunction = Callable[[Problem, Sequence[Constraint], SolveOptions, np.ndarray], Attempt]

#: The strategy functions by name: the one list (a new strategy is one module and one line, or
#: a ``freefloat.strategies`` entry point of another package).
STRATEGIES: Registry[StrategyFunction] = Registry(
    "strategy",
    {
        Strategy.SCAN.value: scan,
        Strategy.MULTISTART.value: multistart,
        Strategy.CONTINUATION.value: continuation,
    },
    plugin_function("strategy"),
)


def choose_strategy(problem: Problem, options: SolveOptions) -> str:
    """The strategy's name for this problem: the one asked for, else by the problem's shape.

    One unknown and one equation: ``scan``. Spatial problems: ``continuation`` when it is
    registered, else ``multistart``; planar problems with several unknowns: ``multistart``.
    """
    if options.strategy is not None:
        return options.strategy
    if problem.n_free == 1 and problem.n_equations == 1:
        return Strategy.SCAN.value
    if not problem.planar and Strategy.CONTINUATION.value in STRATEGIES:
        return Strategy.CONTINUATION.value
    return Strategy.MULTISTART.value


def solve(
    problem: Problem,
    options: SolveOptions | None = None,
    constraints: Sequence[Constraint] | None = None,
    start: np.ndarray | None = None,
) -> Solution:
    """Find the free coefficients that bring the base to its goal attitude.

    Args:
        problem: the problem (not changed).
        options: solver settings.
        constraints: path constraints to honour; default joint position, velocity and effort
            limits.
        start: a path (within the constraints) to start from instead of the quintic path,
            e.g. where a search with less freedom stopped; ignored when it breaks one.

    Raises:
        SolverError: no ``beta`` with a residual below the tolerance was found within the
            constraints.
    """
    options = options or SolveOptions()
    constraints = default_constraints() if constraints is None else list(constraints)
    tol = options.tolerance
    start_time = time.perf_counter()
    start_evaluations = problem.evaluations
    strategy, attempt, start, restored = _attempt(problem, constraints, options, start)
    tried = restored + list(attempt.tried)

    blocked = list(attempt.blocked_by)
    roots, best_vector = _roots(problem, attempt, constraints, tol, tried, blocked)
    roots.sort(key=lambda r: float(r.beta @ r.beta))
    # Certify the integration at the chosen root; refine the grid and polish when needed.
    certified = _certified(problem, roots, constraints, tol, tried)
    if certified is None:
        _refuse(problem, attempt, start, tried, best_vector, tuple(dict.fromkeys(blocked)))
    chosen = Root(certified.beta, certified.residual, problem.path_length(certified.beta))
    return Solution(
        beta=chosen.beta,
        residual=chosen.residual,
        method=attempt.method,
        iterations=attempt.iterations,
        evaluations=problem.evaluations - start_evaluations,
        wall_time=time.perf_counter() - start_time,
        roots=(chosen, *roots),
        integration_error=certified.integration_error,
        steps=certified.problem.steps,
        strategy=strategy,
        tried=tuple(_dedupe(tried)),
    )


def _certified(
    problem: Problem,
    roots: list[Root],
    constraints: Sequence[Constraint],
    tol: float,
    tried: list[str],
) -> Certified | None:
    """The first of ``roots`` that stays within the constraints once certified (popped).

    A root is polished again on each finer grid (:func:`.certify.certify`); where that moves
    it, it is checked again: a wild root (a path that turns many times, found on a coarse
    grid) can move onto a path that breaks a constraint the first one kept (a planar
    correction: 76.66 deg out of a 60 deg cone). The next root is then certified instead
    (said in ``tried`` when one stays within). When none stays within, the first is
    returned as before: the planner's later stages (the nearest root within the
    constraints) start from it and bring it back inside, as they do a root a hair past a
    joint limit; a caller without such stages checks the solution itself
    (:mod:`freefloat.robust.correction`). None when there is no root.

    Raises:
        SolverError: the grid cannot be refined enough at a root to certify it.
    """
    first: Certified | None = None
    dropped: list[str] = []
    while roots:
        chosen = roots.pop(0)
        certified = certify(problem, chosen.beta, chosen.residual, tol)
        if not certified.passed:
            if first is not None:
                return first
            raise SolverError(
                "attitude integration error "
                f"{certified.integration_error:.3g} rad is too large to certify the plan",
                certified.residual,
                _dedupe(tried),
            )
        moved = not np.array_equal(certified.beta, chosen.beta)
        broken = first_broken(certified.problem, constraints, certified.beta) if moved else None
        if broken is None:
            tried += dropped
            return certified
        dropped.append(f"a root polished on a finer grid breaks {broken}")
        first = first or certified
    return first


def _attempt(
    problem: Problem,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    given: np.ndarray | None,
) -> tuple[str, Attempt, np.ndarray, list[str]]:
    """Run the strategy: (its name, its attempt, where it started, what restoration did)."""
    zero = np.zeros(problem.n_free)
    # Restoration serves the constraints every path must meet from the start; a lazy one
    # (imposed only once a path broke it) is left to the strategy and the root filter.
    eager = [c for c in constraints if not c.lazy]
    quintic = first_broken(problem, eager, zero)
    quintic_breaks = "" if quintic is None else str(quintic)
    start, restored = _start(problem, constraints, quintic_breaks, given, options)
    if np.linalg.norm(problem.residual(zero)) < 0.01 * options.tolerance and not quintic_breaks:
        attempt = Attempt(candidates=[zero], method="none (the quintic path already reaches it)")
        return Strategy.NONE.value, attempt, start, restored
    strategy = choose_strategy(problem, options)
    if strategy not in STRATEGIES:
        raise SolverError(
            f"strategy {strategy!r} is not available; available: " + ", ".join(STRATEGIES),
            float(np.linalg.norm(problem.residual(zero))),
        )
    try:
        attempt = STRATEGIES[strategy](problem, constraints, options, start)
    except (np.linalg.LinAlgError, FloatingPointError, ValueError) as exc:
        # A numerical breakdown (an SVD that does not converge on non-finite values) is a
        # failed attempt with a reason, never a crash.
        attempt = Attempt(tried=[f"{strategy}: numerical failure ({exc})"])
    if quintic is not None and not np.any(start):  # no path within it to start from
        attempt.blocked_by = (*attempt.blocked_by, quintic.name)
    return strategy, attempt, start, restored


def _refuse(
    problem: Problem,
    attempt: Attempt,
    start: np.ndarray,
    tried: list[str],
    best_vector: np.ndarray,
    blocked: tuple[str, ...],
) -> NoReturn:
    """Raise the refusal of an attempt with no root (``best_vector``: its best residual, rad).

    ``blocked``: the names of the constraints that stood in the way (the error's
    ``blocked_by``).

    Raises:
        UnreachableAttitudeError: the strategy stopped on the way (out of reach); every
            figure is taken at the path where it stopped.
        SolverError: otherwise.
    """
    if attempt.stopped_by and (attempt.last_beta is not None or attempt.message):
        # Out of reach: every figure of the error is taken at the path where the search
        # stopped (how far it got, and what remains of the way), its start when it took no
        # step (then it has no path to hand on: ``last_beta`` is None; only a strategy that
        # says how far it got, in its message, is refused so: a search that spent its budget
        # without a path to show stays a plain SolverError).
        on = attempt.last_beta
        stopped_at = problem.residual(start if on is None else on)
        turn = relative_rotvec(problem.achieved(start), problem.goal_quaternion)
        asked = float(np.linalg.norm(turn))
        raise UnreachableAttitudeError(
            attempt.message,
            float(np.linalg.norm(stopped_at)),
            reached=attempt.reached_fraction * asked,
            asked=asked,
            tried=_dedupe(tried),
            per_axis=stopped_at.tolist(),
            stopped_by=attempt.stopped_by,
            last_beta=None if on is None else on.tolist(),
            axis=(turn / max(asked, 1e-300)).tolist(),
            problem=problem,
            blocked_by=blocked,
        )
    raise SolverError(
        attempt.message or "no path within the constraints reaches the goal attitude",
        float(np.linalg.norm(best_vector)),
        _dedupe(tried),
        per_axis=best_vector.tolist(),
        stopped_by=attempt.stopped_by,
        reached_fraction=attempt.reached_fraction,
        last_beta=None if attempt.last_beta is None else attempt.last_beta.tolist(),
        blocked_by=blocked,
    )


def _dedupe(items: list[str]) -> list[str]:
    """Items in order, repeated ones counted (keeps error messages short)."""
    counts: dict[str, int] = {}
    for item in items:
        counts[item] = counts.get(item, 0) + 1
    return [item if n == 1 else f"{item} (x{n})" for item, n in counts.items()]


def _start(
    problem: Problem,
    constraints: Sequence[Constraint],
    quintic_breaks: str,
    given: np.ndarray | None,
    options: SolveOptions,
) -> tuple[np.ndarray, list[str]]:
    """Where the strategy starts, and what was done to start there (for the record).

    ``given`` when it is within the constraints; else the quintic path, or the nearest path
    within the eager constraints when the quintic breaks one. The start is in rad or m.
    """
    zero = np.zeros(problem.n_free)
    if given is not None and np.any(given) and not broken_constraint(problem, constraints, given):
        return np.asarray(given, dtype=float), [
            "continued from where the search with less freedom stopped"
        ]
    if not quintic_breaks:
        return zero, []
    found = feasible_start(problem, [c for c in constraints if not c.lazy], options)
    how = (
        "started from the nearest path within the constraints"
        if found is not None
        else "no path within the constraints found to start from"
    )
    return (zero if found is None else found), [f"the quintic path breaks {quintic_breaks}: {how}"]


def _roots(
    problem: Problem,
    attempt: Attempt,
    constraints: Sequence[Constraint],
    tol: float,
    tried: list[str],
    blocked: list[str],
) -> tuple[list[Root], np.ndarray]:
    """The attempt's candidates, polished, that are roots within the constraints.

    Returns them with the residual vector (rad) closest to zero among the other candidates
    within the constraints and the quintic path (what a refusal reports when no root is kept,
    :func:`_certified`); appends what was dropped to ``tried``, and the name of each
    constraint a dropped root broke to ``blocked``.
    """
    zero = np.zeros(problem.n_free)
    roots = []
    best_vector = problem.residual(zero)
    for index, beta in enumerate(attempt.candidates):
        if index in attempt.residuals:  # refined to 1e-14 rad already: no polishing
            vector = attempt.residuals[index]
        else:
            try:
                beta, vector = polish(problem, beta, tol)
            except (np.linalg.LinAlgError, FloatingPointError, ValueError):
                tried.append("a candidate could not be polished (numerical failure)")
                continue
        residual = float(np.linalg.norm(vector))
        broken = first_broken(problem, constraints, beta)
        if broken is not None:
            tried.append(f"a root breaks {broken}")
            blocked.append(broken.name)
            continue
        if residual < tol:
            roots.append(Root(beta, residual, problem.path_length(beta)))
        elif residual < np.linalg.norm(best_vector):
            best_vector = vector
    return roots, best_vector
