"""Feasibility restoration: a path that honours every constraint, before the attitude.

When the quintic path (``beta = 0``) breaks a constraint (it sweeps the arm through the hull,
say), the strategies start instead from the minimum-norm ``beta`` whose path honours every
constraint, attitude ignored (SciPy's SLSQP). They then bring the attitude to its goal from
that feasible path.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..problem.constraints import DEFAULT_INSTANTS, Constraint, ConstraintRows
from ..problem.constraints.clearance import SOLVER_SLACK
from ..problem.residual import Problem
from .options import SolveOptions
from .sqp import Function, constraint_functions

__all__ = ["Broken", "broken_constraint", "broken_rows_first", "feasible_start", "first_broken"]


@dataclass(frozen=True)
class Broken:
    """A constraint a path breaks.

    Attributes:
        name: the constraint's name.
        detail: where (a joint, a pair, a time), for people.
    """

    name: str
    detail: str

    def __str__(self) -> str:
        return f"{self.name} ({self.detail})"


def first_broken(
    problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray
) -> Broken | None:
    """The first constraint the path at ``beta`` breaks beyond its tolerance, or None."""
    for constraint in constraints:
        if constraint.applies_to(problem.robot):
            excess = constraint.violation(problem, beta)
            if not excess.value <= constraint.tolerance + excess.error_estimate:  # NaN: broken
                return Broken(constraint.name, excess.detail)
    return None


def broken_constraint(problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray) -> str:
    """``"name (where)"`` of the first constraint the path at ``beta`` breaks, or ``""``."""
    broken = first_broken(problem, constraints, beta)
    return "" if broken is None else str(broken)


def broken_rows_first(problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray) -> str:
    """:func:`broken_constraint`, asking the constraints with their own instants rows first.

    Such a constraint (clearance) asks its rows for at most :data:`SOLVER_SLACK` beyond the
    limit, so a row above that and the constraint's tolerance is a measured excess: the path
    breaks it, and the dense check, which on a path deep in collision measures nearly every
    sample, is not needed (it finds the smallest value along the path, at most the row's).
    Otherwise the dense check decides, as :func:`broken_constraint` does.
    """
    for constraint in constraints:
        if not constraint.own_instants or not constraint.applies_to(problem.robot):
            continue
        worst = float(np.max(constraint.rows(problem, beta).values, initial=-math.inf))
        if worst > SOLVER_SLACK + constraint.tolerance:
            over = f"{worst - SOLVER_SLACK:.3g} {constraint.unit}"
            return f"{constraint.name} (a solver row {over} beyond the limit)"
    return broken_constraint(problem, constraints, beta)


def feasible_start(
    problem: Problem, constraints: Sequence[Constraint], options: SolveOptions
) -> np.ndarray | None:
    """Minimum-norm ``beta`` whose path honours every constraint, or None if none is found.

    SLSQP's rows sit at fixed instants, and a path on a limit there can go beyond it between
    them (the spacecraft's swing peaking between two rows, say): the instants where the
    result breaks a constraint (:meth:`Constraint.critical_times`) are then added and SLSQP
    runs again from it, at most :data:`RESTORE_ROUNDS` runs. When that finds none from the
    quintic path, SLSQP is led there by relaxed rows (:func:`_relaxed_start`) and the rounds
    run again from where it led.
    """
    active = [c for c in constraints if c.applies_to(problem.robot)]
    if not constraint_functions(problem, active):
        return np.zeros(problem.n_free)
    found = _restored(problem, active, options, np.zeros(problem.n_free))
    if found is None:
        led = _relaxed_start(problem, active, options)
        found = None if led is None else _restored(problem, active, options, led)
    return found


#: SLSQP runs of :func:`feasible_start` at most (a count).
RESTORE_ROUNDS = 3
#: The fractions of the quintic path's own excess each constraint's rows are allowed on the
#: way to none (:func:`_relaxed_start`).
RELAXATION = (0.5, 0.25, 0.125, 0.0)


def _restored(
    problem: Problem, active: Sequence[Constraint], options: SolveOptions, start: np.ndarray
) -> np.ndarray | None:
    """:func:`feasible_start`'s rounds from ``start``: the path within every constraint, or None."""
    instants, beta = DEFAULT_INSTANTS, start
    for _ in range(RESTORE_ROUNDS):
        found = _least_norm_within(problem, active, options, instants, beta)
        if found is None:
            return None
        beta = found
        broken = [c for c in active if first_broken(problem, [c], beta) is not None]
        if not broken:
            return beta
        path = problem.polynomials(beta)
        critical = [c.critical_times(problem.robot, path) / path.duration for c in broken]
        more = np.union1d(instants, np.clip(np.concatenate(critical), 0.0, 1.0))
        if len(more) == len(instants):  # nothing new to ask
            return None
        instants = more
    return None


def _relaxed_start(
    problem: Problem, active: Sequence[Constraint], options: SolveOptions
) -> np.ndarray | None:
    """A path near the constraints' rows, reached through rows relaxed less and less.

    SLSQP from the quintic path can stall far outside nonlinear rows (the swing bound of a
    heavy payload on Canadarm2: 9 deg beyond it, after no step). Each constraint's rows are
    allowed a fraction (:data:`RELAXATION`) of the quintic path's largest excess at the
    default instants, at which that path is inside, and each SLSQP run starts from the last
    one's result, down to no allowance. None when nothing lies beyond the rows at the quintic
    path (the plain rounds already ran without allowance), a row is not a number, SLSQP
    fails numerically, or a run does not get halfway from the last allowance to its own (the
    tighter ones would fail too).
    """
    zero = np.zeros(problem.n_free)
    functions = _functions(problem, active, DEFAULT_INSTANTS)
    excess = [_beyond(fun, zero) for fun, _ in functions]
    if not all(math.isfinite(e) for e in excess) or max(excess, default=0.0) <= 0.0:
        return None  # rows not a number, or nothing to relax: the plain rounds decided
    beta, before = zero, excess
    for fraction in RELAXATION:
        allowance = [fraction * e for e in excess]
        found = _least_norm_within(problem, active, options, DEFAULT_INSTANTS, beta, allowance)
        if found is None:
            return None
        beta = found
        left = [_beyond(fun, beta) for fun, _ in functions]
        if not all(
            v <= a + 0.5 * (b - a) + 1e-9 for v, a, b in zip(left, allowance, before, strict=True)
        ):  # not halfway from the last allowance to this one (or not a number): give up
            return None
        before = allowance
    return beta


def _beyond(fun: Function, beta: np.ndarray) -> float:
    """How far the rows ``fun`` (SLSQP's sign) lie beyond their limits at ``beta`` (NaN kept)."""
    values = np.asarray(fun(beta), dtype=float)
    if not np.all(np.isfinite(values)):
        return math.nan
    return max(0.0, -float(np.min(values, initial=0.0)))


def _least_norm_within(
    problem: Problem,
    active: Sequence[Constraint],
    options: SolveOptions,
    instants: np.ndarray,
    start: np.ndarray,
    allowance: Sequence[float] | None = None,
) -> np.ndarray | None:
    """SLSQP's minimum-norm ``beta`` within the rows at ``instants``, from ``start``.

    ``allowance``: how far beyond its limit each constraint's rows may go (its unit; one per
    pair of :func:`_functions`); default none.
    """
    from scipy.optimize import minimize  # imported when needed: it costs start-up time

    pairs = _functions(problem, active, instants)
    extra = [0.0] * len(pairs) if allowance is None else list(allowance)
    rows = [
        {"type": "ineq", "fun": lambda b, f=fun, e=e: f(b) + e, "jac": jac}
        for (fun, jac), e in zip(pairs, extra, strict=True)
    ]
    try:
        result = minimize(
            lambda b: 0.5 * float(b @ b),
            start,
            jac=lambda b: b,
            method="SLSQP",
            constraints=rows,
            options={"ftol": 1e-12, "maxiter": options.max_iterations},
        )
    except (ValueError, np.linalg.LinAlgError, FloatingPointError):
        return None
    beta = np.asarray(result.x, dtype=float)
    return beta if np.all(np.isfinite(beta)) else None


def _functions(
    problem: Problem, active: Sequence[Constraint], instants: np.ndarray
) -> list[tuple[Function, Function]]:
    """SLSQP's ``(g, dg/dbeta)`` pairs (``g >= 0`` feasible): the rows, then the ends' rows.

    :func:`.sqp.constraint_functions` at ``instants``, and each constraint's
    :meth:`~freefloat.problem.constraints.Constraint.end_rows` (a start path ends anywhere).
    """
    pairs = constraint_functions(problem, active, instants)
    for constraint in active:
        if constraint.end_rows(problem, np.zeros(problem.n_free)).count:
            pairs.append(_end_functions(problem, constraint))
    return pairs


def _end_functions(problem: Problem, constraint: Constraint) -> tuple[Function, Function]:
    """A constraint's end rows as SLSQP's ``(g, dg/dbeta)`` (``g >= 0`` feasible).

    Measured once per ``beta`` for both (SLSQP asks for the values, then the Jacobian, at
    each point; the swing's end row integrates the whole path).
    """
    last: list[tuple[bytes, ConstraintRows]] = []

    def rows(beta: np.ndarray) -> ConstraintRows:
        key = np.asarray(beta, dtype=float).tobytes()
        if not last or last[0][0] != key:
            last[:] = [(key, constraint.end_rows(problem, beta))]
        return last[0][1]

    def values(beta: np.ndarray) -> np.ndarray:
        return -rows(beta).values

    def jacobian(beta: np.ndarray) -> np.ndarray:
        return -rows(beta).jacobian

    return values, jacobian
