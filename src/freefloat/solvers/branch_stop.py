"""Why a continuation branch stops: a singular map, a constraint ahead, or the freedom.

Helpers of :func:`.continuation.track`: where the step size falls below its floor, or the pace
check stalls the branch, the constraint a step along the tangent would break
(:func:`ahead`; where none, the one without which the failed step converges onto a path that
breaks it, :func:`.in_the_way.in_the_way`), and the reason a refusal gives
(:func:`why_stopped`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..problem.constraints import Constraint
from ..problem.residual import Problem
from .corrector import Rows
from .in_the_way import in_the_way
from .restore import Broken

__all__ = [
    "NEAR_SINGULAR",
    "PROBE",
    "SINGULAR",
    "STEP_ON",
    "WEAK",
    "ahead",
    "blocker",
    "singular",
    "why_stopped",
]

#: Singular-value ratio below which dh/dbeta counts as singular.
SINGULAR = 1e-9
#: Singular-value ratio below which a refusal notes that dh/dbeta nearly loses rank.
NEAR_SINGULAR = 1e-3
#: Largest singular value (rad per unit of beta) below which a refusal notes that the map is
#: weak in every direction (shipped servicers: 0.16-0.22): a turn then asks joint motions of
#: many turns, and the limit a step along the tangent meets says little.
WEAK = 1e-5
#: The longest step (a fraction of the way) at which a stopped branch looks for a constraint
#: ahead (:func:`ahead`).
PROBE = 0.05
#: What a constraint's figure ahead is measured on (:func:`ahead`): a trial step along the
#: tangent, long where the map is weak, not a path the search kept.
STEP_ON = "on the path a step on would take"


def ahead(
    problem: Problem,
    constraints: Sequence[Constraint],
    beta: np.ndarray,
    tangent: np.ndarray,
    jac: np.ndarray,
    step: float,
) -> Broken | None:
    """The first constraint a step along ``tangent`` from ``beta`` would break, or None.

    The step the branch was taking first (``step``, a fraction of the way): what it breaks is
    what stopped it; only when it breaks nothing, a step of :data:`PROBE`. A step of one size
    alone would name the wrong one: on a weak map the tangent is long, and a joint's position
    limit far away is broken at :data:`PROBE` as surely as the velocity limit the branch is
    pressed against. None on a singular map ``jac`` too: the tangent is then meaningless (see
    :func:`why_stopped`).
    """
    if singular(jac):
        return None
    for size in sorted({min(step, PROBE), PROBE}):
        ahead = beta + tangent * size
        for constraint in constraints:
            if constraint.applies_to(problem.robot):
                excess = constraint.violation(problem, ahead)
                if excess.value > 0.0:
                    return Broken(constraint.name, f"{excess.detail} ({STEP_ON})")
    return None


def blocker(
    problem: Problem,
    target: Problem,
    constraints: Sequence[Constraint],
    at_point: tuple[np.ndarray, np.ndarray, np.ndarray],
    step: float,
    tol: float,
    rows: Rows,
) -> Broken | None:
    """What stopped a branch whose ``step`` (towards ``target``) failed at its floor.

    ``at_point``: the branch's path, tangent and Jacobian. The constraint the step breaks
    ahead (:func:`ahead`); where none is, the one without which the step converges onto a
    path that breaks it (:func:`.in_the_way.in_the_way`); None on a singular map or when
    neither names one.
    """
    beta, tangent, jac = at_point
    blocked = ahead(problem, constraints, beta, tangent, jac, step)
    if blocked is None and not singular(jac):
        blocked = in_the_way(problem, target, constraints, beta + step * tangent, tol, rows)
    return blocked


def why_stopped(blocked: Broken | None, jac: np.ndarray) -> str:
    """Why the branch cannot go on: a singular map, a constraint ahead, or freedom.

    A map weak in every direction (:data:`WEAK`) or nearly singular is named before it. A
    constraint is named with "ahead" and where the path a step along the tangent breaks it
    (:func:`ahead`, :data:`STEP_ON` in its detail; or, with :data:`~.in_the_way.WITHOUT`
    in its detail, where the path the failed step converges to without it breaks it:
    :func:`.in_the_way.in_the_way`); its figure is that path's, beyond the limit, while the
    branch itself keeps it. A
    singular map first: the tangent is then the least-squares one, its length set by the
    smallest singular value, and a constraint it would break ahead says nothing of the
    branch (a step of 10^8 rad breaks every joint limit).
    """
    smallest, ratio = _gains(jac)
    if ratio < SINGULAR or smallest < 1e-9:
        return "a singular map (dh/dbeta loses rank)"
    if blocked is not None:  # on the path a short step on
        ahead = f"{blocked.name} ahead: {blocked.detail}"
        if smallest / ratio < WEAK:  # every gain tiny: any turn asks joint motions of turns
            return (
                f"a weak map (its largest gain {smallest / ratio:.1g} rad per unit of the "
                f"free coefficients), so a step on is long: {ahead}"
            )
        if ratio < NEAR_SINGULAR:  # the cause first: a small turn about the weakest
            # direction asks large joint motions, so the constraint a step meets may lie far
            return (
                f"a nearly singular map (its weakest gain {ratio:.1g} of its strongest), "
                f"so a step on is long: {ahead}"
            )
        return ahead
    return "freedom exhausted (the corrector does not converge with this path family)"


def _gains(jac: np.ndarray) -> tuple[float, float]:
    """The smallest singular value of ``jac`` (rad per unit of beta), and over the largest."""
    sigma = np.linalg.svd(jac, compute_uv=False)
    return float(sigma[-1]), float(sigma[-1] / max(sigma[0], 1e-300))


def singular(jac: np.ndarray) -> bool:
    """Whether the residual's Jacobian ``jac`` (rad per unit of beta) counts as rank deficient.

    Its smallest singular value below :data:`SINGULAR` times its largest, or below 1e-9.
    """
    smallest, ratio = _gains(jac)
    return ratio < SINGULAR or smallest < 1e-9
