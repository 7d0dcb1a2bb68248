"""Nonlinear least squares within a box: Levenberg-Marquardt steps, projected.

Minimises ``|r(x)|^2`` over ``lower <= x <= upper`` for a residual ``r`` without derivatives
(its Jacobian by central differences). Each iteration solves Levenberg's damped normal
equations ``(J^T J + lambda I) dx = -J^T r`` over the unknowns free to move (an unknown at a
bound whose descent direction points out of the box is held there), clips the step to the
box, and takes it when the sum of squares falls (then ``lambda`` shrinks), else grows
``lambda`` and tries again. The damping is the identity's, not ``diag(J^T J)``'s, so every
step is the shortest one for the decrease it buys: where the residual leaves unknowns free
(an end-effector position reached by more joints than it needs), the search ends near its
start. Near a zero-residual solution the steps are Gauss-Newton steps and converge
quadratically. Budgets are counts (iterations and residual evaluations).

The inverse kinematics of end-effector goals uses it (:mod:`.cartesian`). Written here (not
SciPy's ``least_squares``) so that a scenario with such goals does not pay SciPy's optimiser
import, about 0.2 s, in each fresh process.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["BoxFit", "box_least_squares"]

#: Iterations at most (a count).
MAX_ITERATIONS = 200
#: First damping ``lambda``, relative to the largest diagonal entry of ``J^T J``.
FIRST_DAMPING = 1e-3
#: Longest step (the unknowns' units, Euclidean norm): the linear model is not trusted
#: further, so a search does not leap past the solution nearest its start.
MAX_STEP = 0.5
#: Damping beyond which no step lowers the sum of squares: the search stops there.
LARGEST_DAMPING = 1e16
#: Central-difference step, relative to ``max(1, |x_i|)``: the cube root of the epsilon.
_STEP = 2.220446049250313e-16 ** (1.0 / 3.0)


@dataclass(frozen=True)
class BoxFit:
    """Where a box least-squares search ended.

    Attributes:
        x: the best point found (inside the box; the unknowns' units).
        residual: the residual there.
        norm: ``|residual|`` (the residual's Euclidean norm).
        iterations: iterations made (a count).
        evaluations: residual evaluations (a count, differences included).
        converged: the search ended at ``target`` or where no step lowers the norm (a local
            minimum within the box, to rounding); False: the iteration budget ran out first.
    """

    x: np.ndarray
    residual: np.ndarray
    norm: float
    iterations: int
    evaluations: int
    converged: bool


def box_least_squares(
    residual: Callable[[np.ndarray], np.ndarray],
    start: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    target: float = 0.0,
    max_iterations: int = MAX_ITERATIONS,
) -> BoxFit:
    """A local minimum of ``|residual(x)|`` within ``[lower, upper]``, from ``start``.

    Args:
        residual: ``r(x)``, a finite vector for every ``x`` in the box.
        start: the first point (clipped into the box).
        lower: the box's lower corner (``-inf`` allowed).
        upper: its upper corner (``>= lower``; ``inf`` allowed).
        target: stop once ``|r|`` is at or below this (0: only when no step lowers it).
        max_iterations: iterations at most (a count).
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    x = np.clip(np.asarray(start, dtype=float), lower, upper)
    r = np.asarray(residual(x), dtype=float)
    squares, evaluations, damping, iterations = float(r @ r), 1, -1.0, 0
    while math.sqrt(squares) > target:
        if iterations >= max_iterations:
            return BoxFit(x, r, math.sqrt(squares), iterations, evaluations, False)
        iterations += 1
        jacobian, spent = _differences(residual, x, r, lower, upper)
        evaluations += spent
        gradient = jacobian.T @ r
        free = ~(((x <= lower) & (gradient > 0.0)) | ((x >= upper) & (gradient < 0.0)))
        if not np.any(gradient[free]):  # a stationary point of the sum of squares in the box
            break
        normal = jacobian[:, free].T @ jacobian[:, free]
        largest = max(float(np.diag(normal).max()), 1e-300)
        if damping < 0.0:
            damping = FIRST_DAMPING * largest
        moved = False
        while damping <= LARGEST_DAMPING * largest:
            step = np.zeros_like(x)
            try:
                step[free] = np.linalg.solve(
                    normal + damping * np.eye(len(normal)), -gradient[free]
                )
            except np.linalg.LinAlgError:
                damping *= 4.0
                continue
            length = float(np.linalg.norm(step))
            if length > MAX_STEP:  # far from a solution the model is not trusted further
                step *= MAX_STEP / length
            trial = np.clip(x + step, lower, upper)
            if np.array_equal(trial, x):  # the step is lost to rounding: nothing left to gain
                break
            trial_r = np.asarray(residual(trial), dtype=float)
            evaluations += 1
            if float(trial_r @ trial_r) < squares:
                x, r, squares, moved = trial, trial_r, float(trial_r @ trial_r), True
                damping = max(damping / 3.0, 1e-300)
                break
            damping *= 4.0
        if not moved:
            break
    return BoxFit(x, r, math.sqrt(squares), iterations, evaluations, True)


def _differences(
    residual: Callable[[np.ndarray], np.ndarray],
    x: np.ndarray,
    r: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
) -> tuple[np.ndarray, int]:
    """The residual's Jacobian at ``x`` (where it is ``r``) by central differences, in the box.

    Also the residual evaluations it took (a count). Where a central step would leave the
    box, the difference is taken over the part of ``[x - h, x + h]`` inside it (one-sided at a
    bound); an unknown whose box has no width gets a zero column without an evaluation.
    """
    columns, spent = [], 0
    for i in range(len(x)):
        h = _STEP * max(1.0, abs(float(x[i])))
        ahead, behind = x.copy(), x.copy()
        ahead[i] = min(x[i] + h, upper[i])
        behind[i] = max(x[i] - h, lower[i])
        span = ahead[i] - behind[i]
        if span <= 0.0:  # a box of zero width: this unknown cannot move
            columns.append(np.zeros_like(r))
            continue
        up, down = (
            np.asarray(residual(ahead), dtype=float),
            np.asarray(residual(behind), dtype=float),
        )
        columns.append((up - down) / span)
        spent += 2
    return np.stack(columns, axis=1), spent
