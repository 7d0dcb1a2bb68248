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

from ..problem.constraints import DEFAULT_INSTANTS, Constraint
from ..problem.constraints.clearance import SOLVER_SLACK
from ..problem.residual import Problem
from .options import SolveOptions
from .sqp import constraint_functions

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
    runs again from it, at most :data:`RESTORE_ROUNDS` runs.
    """
    active = [c for c in constraints if c.applies_to(problem.robot)]
    if not constraint_functions(problem, active):
        return np.zeros(problem.n_free)
    instants, beta = DEFAULT_INSTANTS, np.zeros(problem.n_free)
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


#: SLSQP runs of :func:`feasible_start` at most (a count).
RESTORE_ROUNDS = 3


def _least_norm_within(
    problem: Problem,
    active: Sequence[Constraint],
    options: SolveOptions,
    instants: np.ndarray,
    start: np.ndarray,
) -> np.ndarray | None:
    """SLSQP's minimum-norm ``beta`` within the rows at ``instants``, from ``start``."""
    from scipy.optimize import minimize  # imported when needed: it costs start-up time

    rows = [
        {"type": "ineq", "fun": fun, "jac": jac}
        for fun, jac in constraint_functions(problem, active, instants)
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
