"""The plan's objective record, recomputed from its path.

``objective.value`` is recomputed by the named objective, rebuilt from the registry with the
record's ``parameters``, at the plan's free coefficients, on the quadrature the record names,
and must agree to :data:`RELATIVE_TOLERANCE` of its size (the computation is the planner's
own, so only rounding separates them); ``error_estimate`` must
agree to that plus half of itself. The unit and duration power must be the objective's, and a
minimum-norm plan's ``start_value`` (the search's root) must be at least its ``value`` (a
refinement only lowers it); every objective is non-negative.
Files before format 4 measured ``min_norm`` in their monomial basis: it is recomputed there.
What cannot be recomputed from the file is the search's history: the value on the
minimum-norm path the search found first (for other objectives) and the freedom levels tried.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import FreeFloatError, PlanMismatchError
from ..plans.format import Plan
from ..plans.versions import MONOMIAL_BASIS
from ..problem.objectives import DEFAULT_OBJECTIVE, OBJECTIVES, MinNorm, Objective
from ..problem.residual import Problem

__all__ = ["MAX_NODES", "RELATIVE_TOLERANCE", "check_objective"]

#: Agreement asked of a recomputed objective value, relative to its size.
RELATIVE_TOLERANCE = 1e-9
#: Most quadrature nodes a plan may name (the planner stops doubling at 512).
MAX_NODES = 512


def _mismatch(field: str, message: str) -> PlanMismatchError:
    return PlanMismatchError(f"objective.{field}", math.inf, 0.0, message=message)


def _old_norm(plan: Plan) -> float:
    """``min_norm`` of a file before format 4 (rad^2).

    The squared norm of its free coefficients in the old monomial basis, ``sum_j (b_j T^j)^2``
    for the ``t^j`` coefficients ``b_j``.
    """
    total = 0.0
    for values in plan.free_parameters.values():
        for k, value in enumerate(values):
            total += (value * plan.duration ** (6 + k)) ** 2
    return total


def check_objective(plan: Plan, problem: Problem, beta: np.ndarray) -> None:
    """Recompute the plan's objective record (see the module docstring).

    Args:
        plan: the plan.
        problem: its problem, rebuilt from the file.
        beta: its free coefficients (rad or m).

    Raises:
        PlanMismatchError: the first field of the record that disagrees, named.
    """
    record = plan.objective
    if record.value is None:  # written before objectives existed: a minimum-norm plan
        return
    if record.name not in OBJECTIVES:
        raise _mismatch(
            "name", f"unknown objective {record.name!r}; valid: {', '.join(OBJECTIVES)}"
        )
    try:
        objective: Objective = OBJECTIVES[record.name].from_record(record.parameters)
    except FreeFloatError as exc:
        raise _mismatch("parameters", str(exc)) from None
    if objective.exact:
        if record.quadrature_nodes != 0:
            raise _mismatch(
                "quadrature_nodes",
                f"{record.name} is exact: no nodes, not {record.quadrature_nodes}",
            )
    else:
        if not 1 <= record.quadrature_nodes <= MAX_NODES:
            raise _mismatch(
                "quadrature_nodes", f"{record.quadrature_nodes} is not in 1..{MAX_NODES}"
            )
        objective = objective.with_nodes(record.quadrature_nodes)
    if record.unit != objective.unit:
        raise _mismatch("unit", f"{record.name} is in {objective.unit}, not {record.unit!r}")
    if record.duration_power != objective.duration_power:
        raise _mismatch(
            "duration_power",
            f"{record.name} scales as T^-{objective.duration_power}, not "
            f"T^-{record.duration_power}",
        )
    value = objective.evaluate(problem, beta).value
    if plan.basis == MONOMIAL_BASIS and record.name == MinNorm.name:
        value = _old_norm(plan)
    scale = RELATIVE_TOLERANCE * max(abs(value), 1e-300)
    if not abs(record.value - value) <= scale:
        raise PlanMismatchError("objective.value", abs(record.value - value), scale, objective.unit)
    estimate = objective.error_estimate(problem, beta)
    if not abs(record.error_estimate - estimate) <= scale + 0.5 * estimate:
        raise PlanMismatchError(
            "objective.error_estimate",
            abs(record.error_estimate - estimate),
            scale + 0.5 * estimate,
            objective.unit,
        )
    if record.name == DEFAULT_OBJECTIVE and not (
        record.start_value is not None and record.start_value >= record.value
    ):
        raise _mismatch("start_value", "a minimum-norm plan's start value is at least its value")
    if record.start_value is None or not (
        math.isfinite(record.start_value) and record.start_value >= 0
    ):
        raise _mismatch("start_value", "every objective is finite and non-negative")
