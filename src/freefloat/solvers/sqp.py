"""Sequential quadratic programming with every constraint (SciPy's SLSQP).

:func:`constraint_functions` turns the path constraints into SLSQP's inequality functions of
``beta`` (affine ones evaluated once); :func:`minimum_norm_sqp` finds the minimum-norm root
with them, and :mod:`.optimise` the root that minimises another objective.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from ..problem.constraints import DEFAULT_INSTANTS, Constraint, ConstraintRows
from ..problem.residual import Problem
from .options import SolveOptions
from .rows import NO_DIPS, rows_instants

__all__ = ["constraint_functions", "minimum_norm_sqp"]

Function = Callable[[np.ndarray], np.ndarray]


def constraint_functions(
    problem: Problem,
    constraints: Sequence[Constraint],
    instants: np.ndarray = DEFAULT_INSTANTS,
) -> list[tuple[Function, Function]]:
    """``(g, dg/dbeta)`` pairs with ``g(beta) >= 0`` feasible (SLSQP's sign), one per constraint.

    Affine constraints (``g = g0 + G beta``) are evaluated once; the others once per ``beta``
    for both the values and the Jacobian. ``instants`` are the normalised instants of the rows
    (constraints that choose their own instants, as clearance does, keep to theirs:
    :func:`.rows.rows_instants`).
    """
    out: list[tuple[Function, Function]] = []
    for constraint in constraints:
        if not constraint.applies_to(problem.robot):
            continue
        at = rows_instants(constraint, instants, NO_DIPS)
        if constraint.affine:
            rows = constraint.rows(problem, np.zeros(problem.n_free), at)
            if rows.count:

                def values(
                    b: np.ndarray, g0: np.ndarray = rows.values, g: np.ndarray = rows.jacobian
                ) -> np.ndarray:
                    return -(g0 + g @ b)

                def jacobian(b: np.ndarray, g: np.ndarray = rows.jacobian) -> np.ndarray:
                    return -g

                out.append((values, jacobian))
        else:
            memo: dict[bytes, ConstraintRows] = {}

            def rows_at(
                b: np.ndarray,
                c: Constraint = constraint,
                memo: dict = memo,
                at: np.ndarray = at,
            ) -> ConstraintRows:
                key = np.asarray(b, dtype=float).tobytes()
                if key not in memo:
                    memo.clear()
                    memo[key] = c.rows(problem, b, at)
                return memo[key]

            def row_values(
                b: np.ndarray, rows_at: Callable[..., ConstraintRows] = rows_at
            ) -> np.ndarray:
                return -rows_at(b).values

            def row_jacobian(
                b: np.ndarray, rows_at: Callable[..., ConstraintRows] = rows_at
            ) -> np.ndarray:
                return -rows_at(b).jacobian

            out.append((row_values, row_jacobian))
    return out


def minimum_norm_sqp(
    problem: Problem,
    beta: np.ndarray,
    constraints: Sequence[Constraint],
    options: SolveOptions,
) -> tuple[np.ndarray, int]:
    """Minimum-norm ``beta`` with ``h(beta) = 0`` and every constraint along the path."""
    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def evaluate(b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = np.asarray(b, dtype=float).tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = problem.residual_and_jacobian(b)
        return cache[key]

    eqs: list[dict[str, object]] = [
        {"type": "eq", "fun": lambda b: evaluate(b)[0], "jac": lambda b: evaluate(b)[1]}
    ]
    eqs += [
        {"type": "ineq", "fun": fun, "jac": jac}
        for fun, jac in constraint_functions(problem, constraints)
    ]
    from scipy.optimize import minimize  # imported when first used

    result = minimize(
        lambda b: 0.5 * float(b @ b),
        beta,
        jac=lambda b: b,
        method="SLSQP",
        constraints=eqs,
        options={"ftol": 1e-16, "maxiter": options.max_iterations},
    )
    return np.asarray(result.x, dtype=float), int(result.nit)
