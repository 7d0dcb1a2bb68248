"""Automatic freedom for an objective: raise the degree while the objective keeps falling.

After the search has found a root (the paper's minimum-norm path, with the least freedom that
reaches the goal), an objective other than ``min_norm`` is minimised over the roots
(:func:`.optimise.optimise`) with the same freedom, then with ``k`` free coefficients on every
joint for ``k`` in :data:`LEVELS` (spatial problems: :data:`SPATIAL_LEVELS`), each level
starting from the previous best (the same path, embedded in the larger family). It stops when
a level lowers the objective by less than :data:`MIN_GAIN` of its value, or at the last level.
The orthonormal basis (:mod:`freefloat.problem.basis`) keeps the end conditions exactly at
every degree, so high levels cost only time. A scenario's ``[path] extra`` is the starting
freedom; ``[path] raise_freedom = false`` keeps exactly that freedom. Every level is
recorded. Budgets are counts (SLSQP iterations per run, :data:`EVALUATION_BUDGET` objective
evaluations over all levels), so the result is the same on every machine.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from ..problem.build import problem_from_scenario
from ..problem.constraints import Constraint
from ..problem.objectives import Level, Objective
from ..problem.scenario import Scenario
from .certify import Certified, certify
from .optimise import optimise
from .options import Root, SolveOptions
from .restore import broken_constraint
from .search import SearchResult

__all__ = ["LEVELS", "MIN_GAIN", "SPATIAL_LEVELS", "Level", "Minimised", "minimise"]

#: Free coefficients per joint tried in turn by automatic freedom on planar problems (the
#: orthonormal basis is exact at any of them; the worked example's least effort falls to
#: within 1.7 % of the optimal-control figure at 16).
LEVELS = (4, 8, 16)
#: A level must lower the objective by this fraction of its value to try the next one.
MIN_GAIN = 0.005
#: Objective evaluations all levels together may spend, divided by the number of joints (each
#: evaluation costs torque derivatives of every joint at every node): 2000 for the two-joint
#: worked example, 571 for a Panda, 333 for a 12-joint chain.
EVALUATION_BUDGET = 4000
#: SLSQP iterations per run (a level runs at most ``optimise.ROUNDS`` times).
ITERATIONS_PER_LEVEL = 100
#: Levels a spatial problem tries beyond its own freedom (each costs many attitude
#: integrations and, with clearance, many distance queries).
SPATIAL_LEVELS = (2,)


@dataclass
class Minimised:
    """The search result with the objective minimised.

    Attributes:
        found: the solved problem and solution (the best level's).
        objective: the objective, with the quadrature it converged on.
        value: its value at the solution (unit).
        error_estimate: numerical error of ``value`` (unit).
        start_value: its value at the minimum-norm root the search found.
        levels: every level tried, in order.
    """

    found: SearchResult
    objective: Objective
    value: float
    error_estimate: float
    start_value: float
    levels: list[Level] = field(default_factory=list)


def minimise(
    scenario: Scenario,
    found: SearchResult,
    objective: Objective,
    options: SolveOptions,
    constraints: Sequence[Constraint],
) -> Minimised:
    """Minimise ``objective`` from the search's root, raising the freedom automatically.

    Args:
        scenario: the resolved scenario that was searched.
        found: the search's result (its root honours every constraint).
        objective: what to minimise.
        options: solver settings (attitude tolerance, rad).
        constraints: the path constraints to keep.
    """
    robot = scenario.robot
    names = robot.joint_names
    problem, beta = found.problem, found.solution.beta
    objective = objective.converged(problem, beta)
    start_value = objective.evaluate(problem, beta).value
    offset = np.array([2.0 * np.pi * found.full_turns.get(n, 0) for n in names], dtype=float)
    base = [found.freedom[n] for n in names]
    plans: list[list[int]] = [base]
    if scenario.raise_freedom:
        levels_tried = LEVELS if problem.planar else SPATIAL_LEVELS
        plans += [[max(b, k) for b in base] for k in levels_tried if k > min(base)]
    levels: list[Level] = []
    budget = EVALUATION_BUDGET // max(1, robot.n)
    best_problem, best_beta, best_value, best_freedom = problem, beta, start_value, base
    # A start that breaks a constraint (a lazy one the search did not impose) is beaten by any
    # path within every constraint, whatever its value.
    feasible = not broken_constraint(problem, constraints, beta)
    for counts in plans:
        if counts == best_freedom and levels:
            continue
        if counts == base:
            level_problem, start = problem, beta
        else:
            level_problem = problem_from_scenario(
                scenario, extra=counts, goal_offset=offset, mmap=problem.mmap, check_bounds=False
            )
            embedded = level_problem.family.embed(best_problem.family, best_beta)
            if embedded is None:
                break
            start = embedded
        if budget <= 0:
            break
        result = optimise(
            level_problem, start, objective, constraints, options, ITERATIONS_PER_LEVEL, budget
        )
        budget -= result.evaluations
        freedom = dict(zip(names, counts, strict=True))
        levels.append(Level(freedom, result.value, result.iterations, result.note))
        gain = best_value - result.value if feasible else math.inf
        if result.improved and (result.value < best_value or not feasible):
            best_problem, best_beta, best_value, best_freedom = (
                level_problem,
                result.beta,
                result.value,
                counts,
            )
            feasible = True  # optimise keeps only paths within every constraint
        if len(levels) > 1 and feasible and gain < MIN_GAIN * abs(best_value):
            break

    def keep_start() -> Minimised:
        estimate = objective.error_estimate(problem, beta)
        return Minimised(found, objective, start_value, estimate, start_value, levels)

    if best_beta is beta:
        return keep_start()
    residual = float(np.linalg.norm(best_problem.residual(best_beta)))
    checked = certify(best_problem, best_beta, residual, options.tolerance)
    if not checked.passed or broken_constraint(checked.problem, constraints, checked.beta):
        # keep the search's root: it was certified
        levels.append(
            Level(
                dict(zip(names, best_freedom, strict=True)),
                best_value,
                0,
                "could not be certified (integration or constraints)",
            )
        )
        return keep_start()
    return _minimised(found, objective, checked, best_freedom, start_value, levels)


def _minimised(
    found: SearchResult,
    objective: Objective,
    checked: Certified,
    best_freedom: list[int],
    start_value: float,
    levels: list[Level],
) -> Minimised:
    """The result at the certified best path (its objective converged there too)."""
    names = found.problem.robot.joint_names
    objective = objective.converged(checked.problem, checked.beta)  # at the final path too
    value = objective.evaluate(checked.problem, checked.beta).value
    solution = replace(
        found.solution,
        beta=checked.beta,
        residual=checked.residual,
        roots=(Root(checked.beta, checked.residual, checked.problem.path_length(checked.beta)),),
        integration_error=checked.integration_error,
        steps=checked.problem.steps,
        method=f"{found.solution.method}, then SLSQP on {objective.name}",
    )
    result_found = replace(
        found,
        problem=checked.problem,
        solution=solution,
        freedom=dict(zip(names, best_freedom, strict=True)),
    )
    return Minimised(
        result_found,
        objective,
        value,
        objective.error_estimate(checked.problem, checked.beta),
        start_value,
        levels,
    )
