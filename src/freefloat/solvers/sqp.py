"""Minimum-norm sequential quadratic programming with every constraint (SciPy's SLSQP)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..problem.constraints import Constraint
from ..problem.residual import Problem
from .options import SolveOptions

__all__ = ["minimum_norm_sqp"]


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
    for constraint in constraints:
        if not constraint.applies_to(problem.robot):
            continue
        if constraint.affine:  # g(b) = g(0) + G b: evaluate once
            rows = constraint.rows(problem, np.zeros(problem.n_free))
            if rows.count:
                g0, g_mat = rows.values, rows.jacobian
                eqs.append(
                    {
                        "type": "ineq",
                        "fun": lambda b, g0=g0, g=g_mat: -(g0 + g @ b),
                        "jac": lambda b, g=g_mat: -g,
                    }
                )
        else:
            eqs.append(
                {
                    "type": "ineq",
                    "fun": lambda b, c=constraint: -c.rows(problem, b).values,
                    "jac": lambda b, c=constraint: -c.rows(problem, b).jacobian,
                }
            )
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
