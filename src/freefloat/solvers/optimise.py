"""The root that minimises an objective, within every constraint (docs/method.md section 13).

Starting from a root ``beta_0`` (``h(beta_0) = 0``), SciPy's SLSQP minimises the objective
subject to ``h(beta) = 0`` (exact Jacobian) and the path constraints. It works in coordinates
``z`` with ``beta = beta_0 + S z``, where ``S^T G S = I`` for the Gram matrix ``G`` of the
basis polynomials' second derivatives: in ``z`` the integral of squared accelerations is a
unit sphere, which keeps high-degree bases well conditioned. The objective is divided by its
value at ``beta_0``. The result is polished back onto ``h = 0`` by minimum-norm Newton steps
and kept only if it honours every constraint and lowers the objective (or ``beta_0`` broke a
constraint); otherwise ``beta_0`` stands. Constraints are rows at fixed instants during one
SLSQP run; when the result breaks one between them, the run is repeated from there with the
path's tightest instants added (at most :data:`ROUNDS` runs). The budget is SLSQP's iteration
count.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..problem.constraints import DEFAULT_INSTANTS, Constraint
from ..problem.objectives import Objective, gauss_legendre
from ..problem.residual import Problem
from .newton import polish
from .options import SolveOptions
from .restore import broken_constraint
from .sqp import constraint_functions

__all__ = ["ROUNDS", "Optimised", "optimise"]

#: SLSQP runs at most, each adding the instants where the last one broke a constraint.
ROUNDS = 3


@dataclass(frozen=True)
class Optimised:
    """Where the objective's minimisation ended.

    Attributes:
        beta: the root kept (``beta_0`` when nothing better was found).
        value: the objective there (its unit).
        start_value: the objective at ``beta_0``.
        iterations: SLSQP iterations.
        improved: whether ``beta`` differs from ``beta_0``.
        note: why ``beta_0`` was kept, when it was.
    """

    beta: np.ndarray
    value: float
    start_value: float
    iterations: int
    improved: bool
    note: str = ""


def acceleration_coordinates(problem: Problem) -> np.ndarray:
    """``S`` with ``S^T G S = I``, ``G = int_0^1 (dq''/dbeta)^T (dq''/dbeta) ds``.

    From the QR factors of the square-root-weighted second-derivative map on Gauss-Legendre
    nodes (exact integration), not from a Cholesky factor of ``G``: that squares the condition
    number of a high-degree monomial basis.
    """
    s, w = gauss_legendre(max(problem.family.degrees))
    dqss = problem.family.affine_samples(s).dqss
    weighted = (np.sqrt(w)[:, None, None] * dqss).reshape(-1, problem.n_free)
    r = np.linalg.qr(weighted, mode="r")
    return np.linalg.solve(r, np.eye(problem.n_free))


def optimise(
    problem: Problem,
    beta: np.ndarray,
    objective: Objective,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    max_iterations: int = 200,
) -> Optimised:
    """Minimise ``objective`` over the roots, from the root ``beta`` (see the module docstring).

    Args:
        problem: the problem (not changed).
        beta: a root (within the constraints, or a start that breaks one: the result then
            honours them or ``beta`` stands).
        objective: what to minimise.
        constraints: path constraints to keep.
        options: solver settings (attitude tolerance, rad).
        max_iterations: SLSQP iteration budget.
    """
    from scipy.optimize import minimize  # imported when first used

    beta0 = np.asarray(beta, dtype=float)
    start = objective.evaluate(problem, beta0)
    if problem.n_free == 0:
        return Optimised(beta0, start.value, start.value, 0, False, "no free coefficients")
    scale = start.value if start.value > 0 else 1.0
    s_mat = acceleration_coordinates(problem)

    def to_beta(z: np.ndarray) -> np.ndarray:
        return beta0 + s_mat @ z

    memo: dict[bytes, object] = {}

    def cached(kind: str, z: np.ndarray, make):  # type: ignore[no-untyped-def]
        key = kind.encode() + np.asarray(z, dtype=float).tobytes()
        if key not in memo:
            if len(memo) > 64:
                memo.clear()
            memo[key] = make(to_beta(z))
        return memo[key]

    def fun(z: np.ndarray) -> float:
        return cached("j", z, lambda b: objective.evaluate(problem, b)).value / scale

    def grad(z: np.ndarray) -> np.ndarray:
        found = cached("j", z, lambda b: objective.evaluate(problem, b))
        return (s_mat.T @ found.gradient) / scale

    def h(z: np.ndarray) -> np.ndarray:
        return cached("h", z, problem.residual_and_jacobian)[0]

    def dh(z: np.ndarray) -> np.ndarray:
        return cached("h", z, problem.residual_and_jacobian)[1] @ s_mat

    instants = DEFAULT_INSTANTS
    z = np.zeros(problem.n_free)
    iterations = 0
    for _ in range(ROUNDS):
        cons: list[dict[str, object]] = [{"type": "eq", "fun": h, "jac": dh}]
        for g, dg in constraint_functions(problem, constraints, instants):
            cons.append(
                {
                    "type": "ineq",
                    "fun": lambda z, g=g: g(to_beta(z)),
                    "jac": lambda z, dg=dg: dg(to_beta(z)) @ s_mat,
                }
            )
        with np.errstate(all="ignore"):
            result = minimize(
                fun,
                z,
                jac=grad,
                method="SLSQP",
                constraints=cons,
                options={"ftol": 1e-12, "maxiter": int(max_iterations)},
            )
        iterations += int(result.nit)
        z = np.asarray(result.x, dtype=float)
        candidate = to_beta(z)
        if not np.all(np.isfinite(candidate)):
            return Optimised(beta0, start.value, start.value, iterations, False, "diverged")
        try:
            candidate, vector = polish(problem, candidate, options.tolerance)
        except (np.linalg.LinAlgError, FloatingPointError, ValueError):
            return Optimised(beta0, start.value, start.value, iterations, False, "polish failed")
        if float(np.linalg.norm(vector)) >= options.tolerance:
            return Optimised(beta0, start.value, start.value, iterations, False, "left the goal")
        broken = broken_constraint(problem, constraints, candidate)
        if not broken:
            break
        # Rows hold at the instants but not between them: add the path's tightest instants.
        path = problem.polynomials(candidate)
        extra = [
            np.asarray(c.critical_times(problem.robot, path)) / problem.duration
            for c in constraints
            if c.applies_to(problem.robot)
        ]
        instants = np.unique(np.clip(np.concatenate([instants, *extra]), 0.0, 1.0))
    else:
        return Optimised(beta0, start.value, start.value, iterations, False, f"breaks {broken}")
    value = objective.evaluate(problem, candidate).value
    if not value < start.value and not broken_constraint(problem, constraints, beta0):
        return Optimised(beta0, start.value, start.value, iterations, False, "no lower value")
    return Optimised(candidate, value, start.value, iterations, True)
