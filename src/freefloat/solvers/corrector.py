"""The continuation's corrector: Newton onto a target attitude, then inside everywhere.

:func:`correct` takes minimum-norm Newton steps with the exact Jacobian and every constraint
linearised at its instants (``g + G d <= 0``, :func:`.predictor.newton_correction`);
:func:`corrected_step` corrects a predicted path and, when the exact dense check finds it outside
between those instants, corrects it again at its tightest instants and dips
(:func:`.rows.with_critical`, :func:`.rows.with_dips`). :mod:`.continuation` calls it once per
step.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..problem.constraints import Constraint
from ..problem.residual import Problem
from .predictor import newton_correction
from .restore import broken_constraint
from .rows import (
    NO_DIPS,
    Linearised,
    RowCache,
    linear_rows,
    linearised,
    with_critical,
    with_dips,
    with_picked,
)

__all__ = ["CORRECTOR_ITERATIONS", "Rows", "Step", "correct", "corrected_step"]

#: Newton iterations per corrector.
CORRECTOR_ITERATIONS = 8


def correct(
    problem: Problem,
    constraints: Sequence[Constraint],
    beta: np.ndarray,
    tol: float,
    instants: np.ndarray,
    cache: RowCache,
    dips: np.ndarray = NO_DIPS,
) -> tuple[np.ndarray | None, np.ndarray, np.ndarray, int]:
    """Newton corrector from ``beta``: (solved beta or None, residual, Jacobian, iterations).

    The rows of the constraints that are not affine (clearance: exact distance queries;
    effort limits, the end-effector cone) are measured at the first iterate and then
    linearised about it (:class:`.rows.Linearised`) while every row stays inside at twice
    its predicted rise (:meth:`~.rows.Linearised.trusted_at`; an iterate where the
    linearisation brings a row near its limit is measured itself). Where the corrector
    would accept a path they are measured at that path, which is accepted only inside them,
    and otherwise corrected on from there. The residual, its Jacobian and the affine rows are
    exact at every iterate. The instants the constraints with their own instants pick where
    measured are kept for the next ones (:func:`.rows.with_picked`): rows that jump with the
    iterate would let Newton chase them instead of converging. The corrector gives up early
    when a Newton step did not halve the residual (the predicted step was too long), except
    once: after a step that took the path back inside rows, which may raise the residual.
    """
    r, jac = problem.residual_and_jacobian(beta)
    previous, was_inside, excused = math.inf, True, False
    about: Linearised | None = None
    for iteration in range(1, CORRECTOR_ITERATIONS + 1):
        norm = float(np.linalg.norm(r))
        if about is None or not about.trusted_at(beta):
            about, dips = _measured(problem, constraints, beta, instants, dips)
        g, g_mat = linear_rows(problem, constraints, beta, instants, cache, dips, about)
        inside = _inside(g)
        if norm < tol and inside and not about.measured_at(beta):  # exact where it accepts
            about, dips = _measured(problem, constraints, beta, instants, dips)
            g, g_mat = linear_rows(problem, constraints, beta, instants, cache, dips, about)
            inside = _inside(g)
        if norm < tol and inside:
            return beta, r, jac, iteration
        if iteration > 2 and norm > 0.5 * previous and norm > 1e3 * tol:
            if was_inside or excused:
                break  # not contracting: the step was too long
            excused = True
        d = newton_correction(jac, r, g, g_mat)
        if d is None:
            break
        beta, previous, was_inside = beta + d, norm, inside
        r, jac = problem.residual_and_jacobian(beta)
    g = linear_rows(problem, constraints, beta, instants, cache, dips)[0]
    if float(np.linalg.norm(r)) < tol and _inside(g):
        return beta, r, jac, CORRECTOR_ITERATIONS
    return None, r, jac, CORRECTOR_ITERATIONS


def _measured(
    problem: Problem,
    constraints: Sequence[Constraint],
    beta: np.ndarray,
    instants: np.ndarray,
    dips: np.ndarray,
) -> tuple[Linearised, np.ndarray]:
    """The rows that are not affine measured at ``beta``, and ``dips`` with the instants picked."""
    about = linearised(problem, constraints, beta, instants, dips)
    return about, with_picked(problem, constraints, beta, dips)


def _inside(g: np.ndarray) -> bool:
    """Whether every linearised row ``g`` (its constraint's unit) is at or inside its limit."""
    return len(g) == 0 or float(np.max(g)) <= 0.0


def _dense_ok(problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray) -> bool:
    """Whether ``beta``'s path honours every constraint everywhere (exact dense check)."""
    return not broken_constraint(problem, constraints, beta)


@dataclass(frozen=True)
class Step:
    """One continuation step's corrected path (:func:`corrected_step`).

    Attributes:
        beta: the corrected path's free coefficients (rad or m), None when none was found.
        residual: its residual (rad).
        jacobian: the residual's Jacobian there (rad per unit of ``beta``).
        iterations: the first corrector's Newton iterations (they set the next step).
        spent: every corrector's iterations.
        instants: the instants now imposed (normalised).
        dips: the instants where the dense check found a dip, now imposed on the constraints
            with their own instants (:func:`.rows.with_dips`; normalised).
    """

    beta: np.ndarray | None
    residual: np.ndarray
    jacobian: np.ndarray
    iterations: int
    spent: int
    instants: np.ndarray
    dips: np.ndarray


@dataclass(frozen=True)
class Rows:
    """Where a step's rows sit: the instants, the dips (see :class:`Step`) and the row cache."""

    instants: np.ndarray
    dips: np.ndarray
    cache: RowCache


def corrected_step(
    problem: Problem,
    target: Problem,
    constraints: Sequence[Constraint],
    predicted: np.ndarray,
    tol: float,
    at: Rows,
) -> Step:
    """Correct the ``predicted`` path onto ``target`` (``tol``, rad), then densely inside."""
    solved, r, jac, its = correct(
        target, constraints, predicted, tol, at.instants, at.cache, at.dips
    )
    if solved is not None and not _dense_ok(problem, constraints, solved):
        return _densely(problem, target, constraints, solved, tol, at, its)
    return Step(solved, r, jac, its, its, at.instants, at.dips)


def _densely(
    problem: Problem,
    target: Problem,
    constraints: Sequence[Constraint],
    solved: np.ndarray,
    tol: float,
    at: Rows,
    spent: int,
) -> Step:
    """Correct a path inside at the instants but not everywhere, at its tightest instants.

    Up to three times: add the path's tightest instants, and the instants of its dips below
    the limit of a constraint with its own instants (:func:`.rows.with_dips`), and correct
    again. ``spent``: the corrector iterations so far. Returns the step with its path (None
    when it stays outside) and the instants and dips now imposed.
    """
    r = jac = np.zeros(0)
    instants, dips, first = at.instants, at.dips, spent
    for _ in range(3):
        instants = with_critical(problem, constraints, solved, instants)
        dips = with_dips(problem, constraints, solved, dips)
        found, r, jac, more = correct(target, constraints, solved, tol, instants, at.cache, dips)
        spent += more
        if found is None:
            return Step(None, r, jac, first, spent, instants, dips)
        solved = found
        if _dense_ok(problem, constraints, solved):
            return Step(solved, r, jac, first, spent, instants, dips)
    return Step(None, r, jac, first, spent, instants, dips)
