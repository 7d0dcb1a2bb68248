"""Newton-type building blocks: minimum-norm polishing, Broyden, Levenberg-Marquardt, starts."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..problem.residual import Problem
from .options import POLISH, SolveOptions

__all__ = [
    "SINGULAR",
    "Polished",
    "broyden",
    "levenberg_marquardt",
    "polish",
    "polish_at",
    "starts",
]

#: Singular values below this fraction of the largest are left out of a Broyden step: a start
#: where the map loses rank (an exactly symmetric path) would otherwise step ~1e10 rad away.
SINGULAR = 1e-10


def polish(
    problem: Problem, beta: np.ndarray, tol: float, iterations: int = 8
) -> tuple[np.ndarray, np.ndarray]:
    """Minimum-norm Gauss-Newton corrections until the residual is well below ``tol``.

    Returns the corrected ``beta`` and its residual vector. A candidate whose residual or
    Jacobian is not finite (a diverged search) is returned as it is, to be rejected; it never
    reaches the least-squares solver.
    """
    r = problem.residual(beta)
    if np.linalg.norm(r) < POLISH * tol or not np.all(np.isfinite(r)):
        return beta, r
    for _ in range(iterations):
        jac = problem.jacobian(beta)  # only while a step is still to be taken
        if not np.all(np.isfinite(jac)):
            break
        trial = beta - np.linalg.lstsq(jac, r, rcond=None)[0]
        r_trial = problem.residual(trial)
        if np.linalg.norm(r_trial) >= np.linalg.norm(r):
            break
        beta, r = trial, r_trial
        if np.linalg.norm(r) < POLISH * tol:
            break
    return beta, r


@dataclass(frozen=True)
class Polished:
    """A root polished by :func:`polish_at`.

    Attributes:
        beta: the polished free coefficients (rad or m).
        residual: ``h(beta)`` (rad).
        jacobian: ``dh/dbeta`` at ``beta`` (rad per unit of beta).
    """

    beta: np.ndarray
    residual: np.ndarray
    jacobian: np.ndarray


def polish_at(
    problem: Problem,
    beta: np.ndarray,
    tol: float,
    iterations: int = 8,
    evaluated: tuple[np.ndarray, np.ndarray] | None = None,
) -> Polished:
    """:func:`polish`'s iterates, with ``h`` and its Jacobian evaluated together at each.

    For a caller that takes its next step from the result: the Jacobian there comes with it,
    and no point's residual is integrated twice (once alone, once with the Jacobian).
    ``evaluated``: ``(h, dh/dbeta)`` at ``beta`` when the caller has them (rad, rad per unit).
    """
    r, jac = evaluated if evaluated is not None else problem.residual_and_jacobian(beta)
    for _ in range(iterations):
        small = np.linalg.norm(r) < POLISH * tol
        if small or not np.all(np.isfinite(r)) or not np.all(np.isfinite(jac)):
            break
        trial = beta - np.linalg.lstsq(jac, r, rcond=None)[0]
        r_trial, jac_trial = problem.residual_and_jacobian(trial)
        if np.linalg.norm(r_trial) >= np.linalg.norm(r):
            break
        beta, r, jac = trial, r_trial, jac_trial
    return Polished(beta, r, jac)


def broyden(problem: Problem, beta: np.ndarray, options: SolveOptions) -> tuple[np.ndarray, int]:
    """Broyden quasi-Newton with a backtracking line search from ``beta``; (beta, iterations)."""
    r, jac = problem.residual_and_jacobian(beta)
    refreshed = True
    for iteration in range(1, options.max_iterations + 1):
        if np.linalg.norm(r) < POLISH * options.tolerance:
            return beta, iteration
        step = -np.linalg.lstsq(jac, r, rcond=SINGULAR)[0]
        t = 1.0
        while t > 1e-4:
            trial = beta + t * step
            r_trial = problem.residual(trial)
            if np.linalg.norm(r_trial) < (1.0 - 1e-4 * t) * np.linalg.norm(r):
                break
            t *= 0.5
        else:
            if refreshed:
                return beta, iteration
            jac, refreshed = problem.jacobian(beta), True
            continue
        s = trial - beta
        jac = jac + np.outer(r_trial - r - jac @ s, s) / (s @ s)
        beta, r, refreshed = trial, r_trial, False
    return beta, options.max_iterations


def starts(n: int, count: int) -> list[tuple[str, np.ndarray]]:
    """The quintic path, then ``count - 1`` deterministic pseudo-random starts.

    Their sizes, 0.01, 0.03 and 0.1 rad, are RMS deviations from the quintic (``|beta|`` in the
    orthonormal basis): those of the sizes 1, 3 and 10 the monomial basis used to take.
    """
    rng = np.random.default_rng(20070101)
    out = [("the quintic path", np.zeros(n))]
    for k in range(1, count):
        scale = (0.01, 0.03, 0.1)[(k - 1) // 4 % 3]
        direction = rng.normal(size=n)
        beta = scale * direction / np.linalg.norm(direction)
        out.append((f"start {k} (|beta| = {scale:g})", beta))
    return out


def levenberg_marquardt(
    problem: Problem, beta: np.ndarray, options: SolveOptions
) -> tuple[np.ndarray, int]:
    """Damped Gauss-Newton (MINPACK's LM): robust where dh/dbeta is nearly singular."""
    from scipy.optimize import least_squares  # imported when first used

    result = least_squares(
        problem.residual,
        beta,
        jac=problem.jacobian,
        method="lm",
        xtol=1e-15,
        ftol=1e-15,
        gtol=1e-15,
        max_nfev=options.max_iterations,
    )
    return np.asarray(result.x, dtype=float), int(result.nfev)
