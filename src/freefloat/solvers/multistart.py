"""The ``multistart`` strategy: Newton-type searches from several deterministic starts.

As many unknowns as equations: Broyden's quasi-Newton method with a backtracking line search,
then Levenberg-Marquardt from the same start where it fails (dh/dbeta nearly singular).
More unknowns, or a square root that breaks a constraint: minimum-norm SQP with every
constraint. Several starts are needed because dh/dbeta is singular at the quintic path when
free coefficients of one power move several joints. The budget is a count of residual
evaluations, never a time.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..problem.constraints import Constraint
from ..problem.residual import Problem
from .newton import broyden, levenberg_marquardt, starts
from .options import Attempt, SolveOptions
from .restore import first_broken
from .sqp import minimum_norm_sqp

__all__ = ["multistart"]


def multistart(
    problem: Problem,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    start: np.ndarray | None = None,
) -> Attempt:
    """Search from ``start`` (the quintic path, or a feasible one) and deterministic offsets."""
    origin = np.zeros(problem.n_free) if start is None else np.asarray(start, dtype=float)
    tol = options.tolerance
    square = problem.n_free == problem.n_equations
    attempt = Attempt(method="Broyden quasi-Newton" if square else "SQP minimum norm (SLSQP)")
    first_evaluation = problem.evaluations
    found = 0
    for label, offset in starts(problem.n_free, options.starts):
        begin = origin + offset
        if np.any(origin) and label == "the quintic path":
            label = "the nearest path within the constraints"
        if problem.evaluations - first_evaluation > options.max_evaluations:
            attempt.tried.append(
                f"stopped: budget of {options.max_evaluations} residual evaluations spent"
            )
            attempt.stopped_by = "evaluation budget"
            break
        name = "minimum-norm SQP with constraints"
        try:
            beta = None
            if square:
                beta, its = broyden(problem, begin, options)
                name = "Broyden"
                if np.linalg.norm(problem.residual(beta)) > tol:
                    beta, its = levenberg_marquardt(problem, begin, options)
                    name = "Broyden, then Levenberg-Marquardt"
                broken = first_broken(problem, constraints, beta)
                if np.linalg.norm(problem.residual(beta)) > tol or broken is not None:
                    note = f" (a root breaks {broken})" if broken is not None else ""
                    attempt.tried.append(f"{name} from {label}{note}")
                    if broken is not None:
                        attempt.blocked_by = (*attempt.blocked_by, broken.name)
                    beta = None
                    name = "SQP with constraints"
            if beta is None:
                beta, its = minimum_norm_sqp(problem, begin, constraints, options)
        except (np.linalg.LinAlgError, FloatingPointError, ValueError) as exc:
            # An optimiser that diverges is a failed attempt, not a crash.
            attempt.tried.append(f"{name} from {label}: diverged ({type(exc).__name__})")
            continue
        attempt.tried.append(f"{name} from {label}")
        attempt.candidates.append(beta)
        if np.linalg.norm(problem.residual(beta)) < tol:
            if found == 0:
                attempt.iterations = its
                if name == "Broyden, then Levenberg-Marquardt":
                    attempt.method = "Levenberg-Marquardt"
                elif name != "Broyden":
                    attempt.method = "SQP minimum norm (SLSQP) with constraints"
            found += 1
            if found >= options.keep_solutions:
                break
    return attempt
