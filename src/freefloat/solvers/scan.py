"""One unknown, one equation (planar, one free coefficient): every root in a bracket.

Sign changes of ``h`` on a coarse grid across the bracket are refined with Brent's method or,
with a planar map, all at once by safeguarded Newton steps with the exact slope; the
minimum-norm root is chosen by the dispatcher and the others are listed in the plan.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..problem.constraints import Constraint
from ..problem.residual import Problem
from .options import Attempt, SolveOptions

__all__ = ["bracket_roots", "scan"]


def scan(
    problem: Problem,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    start: np.ndarray | None = None,
) -> Attempt:
    """The ``scan`` strategy: all roots of the scalar residual in the bracket.

    The bracket is scanned whole, so ``start`` is not used; the dispatcher keeps the roots
    whose paths honour the constraints.
    """
    candidates, iterations, residuals = bracket_roots(problem, options)
    label = "safeguarded Newton" if problem.planar_map is not None else "Brent secant"
    tried = [
        f"{options.scan_points}-point scan of a bracket of +-{options.max_deviation:g} rad "
        "path deviation"
    ]
    if not candidates:
        tried.append("no sign change of h in the bracket")
    return Attempt(
        candidates=candidates,
        method=f"bracket scan + {label}",
        iterations=iterations,
        residuals=dict(enumerate(residuals)),
        tried=tried,
    )


def bracket_roots(
    problem: Problem, options: SolveOptions
) -> tuple[list[np.ndarray], int, list[np.ndarray]]:
    """All roots of the scalar residual in the bracket.

    Returns the roots, the iterations, and the residuals of the roots when known.

    Sign changes on a coarse grid are refined with Brent's method, or, with a planar map,
    all at once by safeguarded Newton steps with the exact slope.
    """
    shape = problem.family.affine_samples(np.linspace(0.0, 1.0, 201)).dq[:, :, 0]
    half_width = options.max_deviation / np.abs(shape).max()
    grid = np.linspace(-half_width, half_width, options.scan_points)
    coarse = problem.with_steps(max(16, problem.steps // 4))  # sign changes need less accuracy
    assert problem.yaw_change is not None
    values = coarse.yaw_changes(grid[:, None]) - problem.yaw_change

    changes = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))
    if problem.planar_map is not None:
        lo, hi = grid[changes], grid[changes + 1]
        seed = lo - values[changes] * (hi - lo) / (values[changes + 1] - values[changes])
        return _newton_brackets(problem, lo, hi, seed)

    def scalar(b: float) -> float:
        return float(problem.residual(np.array([b]))[0])

    roots, iterations = [], 0
    for i in changes:
        lo, hi = grid[i], grid[i + 1]
        f_lo, f_hi = scalar(lo), scalar(hi)
        if np.sign(f_lo) == np.sign(f_hi):  # the coarse scan saw a change the fine one does not
            continue
        from scipy.optimize import brentq  # imported when first used

        root, info = brentq(
            scalar, lo, hi, xtol=1e-13, rtol=4 * np.finfo(float).eps, full_output=True
        )
        iterations += info.iterations
        roots.append(np.array([root]))
    return roots, iterations, []


def _newton_brackets(
    problem: Problem, lo: np.ndarray, hi: np.ndarray, seed: np.ndarray, iterations: int = 60
) -> tuple[list[np.ndarray], int, list[np.ndarray]]:
    """Refine every bracketed root at once (vectorised over the brackets).

    Newton steps with the exact slope, kept inside each bracket by bisection.
    """
    assert problem.yaw_change is not None
    target = problem.yaw_change
    if len(lo) == 0:
        return [], 0, []
    values = problem.yaw_changes(np.concatenate([lo, hi])[:, None])
    f_lo, f_hi = values[: len(lo)] - target, values[len(lo) :] - target
    keep = np.sign(f_lo) != np.sign(f_hi)  # the coarse scan saw a change the fine one does not
    lo, hi, f_lo = lo[keep], hi[keep], f_lo[keep]
    x = np.clip(seed[keep], lo, hi)  # the secant point of the coarse scan
    done = iterations
    f = np.full(len(x), np.inf)
    for iteration in range(1, iterations + 1):
        f, slope = problem.yaw_changes_and_slopes(x)
        f = f - target
        if np.all(np.abs(f) < 1e-14):
            done = iteration
            return [np.array([r]) for r in x], done, [np.array([v]) for v in f]
        left = np.sign(f) == np.sign(f_lo)
        lo, f_lo = np.where(left, x, lo), np.where(left, f, f_lo)
        hi = np.where(left, hi, x)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = x - f / slope
        inside = np.isfinite(newton) & (newton > lo) & (newton < hi)
        x = np.where(np.abs(f) < 1e-14, x, np.where(inside, newton, 0.5 * (lo + hi)))
    return [np.array([root]) for root in x], done, []
