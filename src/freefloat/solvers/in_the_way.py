"""What stands in the way of a continuation step that failed: the constraints, tried one by one.

A branch stops when its step has been halved below its floor and the corrector still finds no
path within the constraints. The constraint a short step along the tangent breaks names the
cause when there is one (:func:`.continuation.track`); but the tangent keeps the rows it knows
inside, so a constraint can block the corrector without being broken ahead, and the refusal
then blamed the path family's freedom. Here the failed step is corrected again without each
constraint in turn: a constraint without which the step converges onto a path that breaks it
is the one in the way. Only a branch that stops so pays for it: one corrected step per
constraint (a corrector, and up to three more at the dips it finds), its residual evaluations
counted with the branch's.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..problem.constraints import Constraint
from ..problem.residual import Problem
from .corrector import Rows, corrected_step
from .restore import Broken

__all__ = ["WITHOUT", "in_the_way"]

#: Appended to the detail of a constraint found in the way (the path it describes is the one
#: the step converges to without that constraint).
WITHOUT = "on the path the failed step converges to without it"


def in_the_way(
    problem: Problem,
    target: Problem,
    constraints: Sequence[Constraint],
    predicted: np.ndarray,
    tol: float,
    at: Rows,
) -> Broken | None:
    """The first constraint without which the failed step converges onto a path breaking it.

    Args:
        problem: the problem whose dense checks the step must pass.
        target: the step's target (its goal attitude on the way).
        constraints: the constraints the step was corrected within.
        predicted: the failed step's predicted path (free coefficients, rad or m).
        tol: the step's residual tolerance (rad).
        at: the step's instants and dips (its row cache is not used: a cache's keys are
            positions in the constraint list, which changes here).

    Returns None when no single constraint is in the way (the corrector fails without each
    one too, or converges onto a path that keeps it).
    """
    for constraint in constraints:
        if not constraint.applies_to(problem.robot):
            continue
        others = [c for c in constraints if c is not constraint]
        alone = Rows(at.instants, at.dips, {})
        try:
            done = corrected_step(problem, target, others, predicted, tol, alone)
        except (np.linalg.LinAlgError, FloatingPointError, ValueError):
            continue  # a numerical failure without it says nothing of this constraint
        if done.beta is None:
            continue
        excess = constraint.violation(problem, done.beta)
        if excess.value > 0.0:
            return Broken(constraint.name, f"{excess.detail} ({WITHOUT})")
    return None
