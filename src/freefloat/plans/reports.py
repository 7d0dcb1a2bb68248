"""The plan's records of what it honours and minimises, built from the plug-ins themselves.

A plan records every constraint by its registered name with its parameters
(:func:`constraint_records`), its objective with its parameters (:func:`objective_report`,
:func:`norm_report`) and its clearance in the ``safety`` record (:func:`safety_report`), so
that ``freefloat verify`` rebuilds each from the registries. A plug-in that is not in its
registry is refused before any work (:func:`check_registered`): its plan could not be verified.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np

from ..errors import InputError
from ..problem.constraints import CONSTRAINTS, Clearance, Constraint
from ..problem.constraints.registry import SAFETY_RECORDED, cached_collision_model
from ..problem.objectives import DEFAULT_OBJECTIVE, OBJECTIVES, Objective, objective_named
from ..problem.residual import Problem
from ..problem.scenario import Scenario
from ..progress import LOGGER
from ..robot.collision import known_srdf
from ..solvers.minimise import Minimised
from .guarantees import ConstraintRecord, ObjectiveReport, SafetyReport

__all__ = [
    "as_rebuilt",
    "check_registered",
    "constraint_records",
    "norm_report",
    "objective_report",
    "safety_report",
]


def check_registered(objective: Objective, constraints: Sequence[Constraint]) -> None:
    """Refuse plug-ins ``freefloat verify`` could not rebuild from a plan's records.

    Raises:
        InputError: an objective or constraint not in its registry under its name, or two
            constraints of one name.
    """
    if OBJECTIVES.get(objective.name) is not type(objective):
        raise InputError(
            f"objective {objective.name!r} ({type(objective).__name__}) is not in the registry: "
            "add it to freefloat.problem.objectives.OBJECTIVES so that its plan can be verified "
            "(docs/developers.md)"
        )
    constraint_records(constraints)


def constraint_records(constraints: Sequence[Constraint]) -> list[ConstraintRecord]:
    """The plan's constraint records (clearance aside: :func:`safety_report`).

    Raises:
        InputError: a constraint not in the registry under its name, or two of one name.
    """
    records: list[ConstraintRecord] = []
    for constraint in constraints:
        if constraint.name in SAFETY_RECORDED:
            continue
        if CONSTRAINTS.get(constraint.name) is not type(constraint):
            raise InputError(
                f"constraint {constraint.name!r} ({type(constraint).__name__}) is not in the "
                "registry: add it to freefloat.problem.constraints.CONSTRAINTS so that its plan "
                "can be verified (docs/developers.md)"
            )
        if any(r.name == constraint.name for r in records):
            raise InputError(f"two constraints named {constraint.name!r}; give each once")
        records.append(ConstraintRecord(constraint.name, constraint.to_record()))
    return records


def as_rebuilt(constraints: Sequence[Constraint]) -> list[Constraint]:
    """The constraints in the order ``freefloat verify`` rebuilds them from a plan.

    The recorded ones in their order, then those the ``safety`` record describes: the plan's
    checks are then listed in the order its verification recomputes them.
    """
    recorded = [c for c in constraints if c.name not in SAFETY_RECORDED]
    return recorded + [c for c in constraints if c.name in SAFETY_RECORDED]


def objective_report(minimised: Minimised) -> ObjectiveReport:
    """The record of a minimised objective: value, quadrature, levels and parameters."""
    objective = minimised.objective
    return ObjectiveReport(
        name=objective.name,
        unit=objective.unit,
        value=minimised.value,
        error_estimate=minimised.error_estimate,
        quadrature_nodes=objective.nodes_used,
        duration_power=objective.duration_power,
        start_value=minimised.start_value,
        levels=list(minimised.levels),
        parameters=objective.to_record(),
    )


def norm_report(problem: Problem, beta: np.ndarray) -> ObjectiveReport:
    """The record of a minimum-norm plan (the search's own choice)."""
    norm = objective_named(DEFAULT_OBJECTIVE)
    value = norm.evaluate(problem, beta).value
    return ObjectiveReport(name=norm.name, unit=norm.unit, value=value, start_value=value)


def safety_report(scenario: Scenario, constraints: Sequence[Constraint]) -> SafetyReport:
    """The plan's record of what it was kept clear of, warning of what it could not check."""
    clearance = next((c for c in constraints if isinstance(c, Clearance)), None)
    safety = scenario.safety
    if not safety.check:
        note = "not checked ([safety] check = false)"
        LOGGER.info("clearance: %s", note)
        return SafetyReport(checked=False, margin_m=safety.margin, note=note)
    model = (
        clearance.model
        if clearance is not None
        else cached_collision_model(
            scenario.robot, safety.srdf or known_srdf(scenario.robot), safety.obstacles
        )
    )
    note = ""
    if model.uncovered:
        bodies = ", ".join(model.uncovered)
        note = f"no collision geometry for {bodies}"
        LOGGER.warning("clearance: not checked for %s (no collision geometry)", bodies)
    if clearance is None or not clearance.applies_to(scenario.robot):
        note = f"not checked ({note or 'no pairs to check'})"
        return SafetyReport(checked=False, margin_m=safety.margin, note=note)
    if LOGGER.isEnabledFor(logging.INFO):
        extra = [f"{h.name} {100.0 * h.extra_fraction:+.0f} %" for h in clearance.model.hulls()]
        if extra:
            LOGGER.info("clearance kept on true hulls; their extra volume: %s", ", ".join(extra))
    srdf = clearance.model.srdf
    return SafetyReport(
        checked=True,
        margin_m=clearance.margin,
        srdf=None if srdf is None else str(srdf),
        obstacles=list(clearance.model.obstacles),
        note=note,
    )
