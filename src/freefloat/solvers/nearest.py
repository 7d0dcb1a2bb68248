"""The root nearest the quintic, for a search's path that strays far from its start-goal spans.

Every objective starts from the path this returns (the default objective keeps it).

The search's root is the minimum-norm root its continuation reached, with the least freedom
that reaches the goal; on some robots (a heavy satellite whose small arm must turn it) that root
still swings a joint far beyond its start-goal span. When the largest such excursion exceeds
:data:`NATURAL_EXCURSION`, the default objective (the smallest deviation from the quintic,
``|beta|^2``) is minimised over the roots with more freedom: at each level of
:data:`LEVELS` free coefficients per joint (a joint the search gave none, one a scenario's
``[path] extra`` holds, keeps none), from the previous path embedded in the larger family,
by sequential quadratic programming with the exact Hessian of the objective
(:func:`.least_norm.least_norm_root`); when that root breaks a constraint, by the same steps
with the constraints linearised as rows of a small quadratic program, from the previous path,
which honours them (:func:`.least_norm.least_norm_root_within`; the lazy ones, effort limits,
only when the root found without them breaks them, as the search imposes them). A level
is kept only if its path is certified (integration refined, :func:`.certify.certify`), honours
every constraint and deviates less; the levels stop once the excursion is natural. Planar
problems keep the search's root (the paper's examples and their roots are unchanged). Budgets
are counts (:data:`.least_norm.FREE_ITERATIONS` steps without the constraints per level,
:data:`.least_norm.ITERATIONS` per round within them).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..problem.build import problem_from_scenario
from ..problem.constraints import Constraint
from ..problem.paths import excursions
from ..problem.residual import Problem
from ..problem.scenario import Scenario
from .certify import certify
from .least_norm import LeastNorm, least_norm_root, least_norm_root_within
from .options import Root, SolveOptions
from .restore import broken_constraint
from .search import SearchResult

__all__ = ["LEVELS", "NATURAL_EXCURSION", "Nearest", "nearest_root"]

#: A default path whose joints stay within this of their start-goal spans (rad) is kept.
NATURAL_EXCURSION = np.radians(60.0)
#: Free coefficients per joint tried in turn when the search's path is not natural.
LEVELS = (3, 4, 6)


@dataclass(frozen=True)
class Nearest:
    """The default path after refinement.

    Attributes:
        found: the search result to plan with (the search's own when nothing better was found).
        tried: what each level gave, for the record.
    """

    found: SearchResult
    tried: tuple[str, ...]


def _largest_excursion(problem: Problem, beta: np.ndarray) -> float:
    family = problem.family
    return float(excursions(problem.polynomials(beta), family.start, family.goal).max())


def _within(
    problem: Problem,
    start: np.ndarray,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    free: np.ndarray,
) -> LeastNorm:
    """:func:`.least_norm.least_norm_root_within`, the lazy constraints imposed when broken.

    As the search does, the steps first keep the eager constraints alone (the effort limits'
    rows cost a torque derivative per instant); only when their root breaks a lazy one are
    the steps taken again with every constraint (rad or m).
    """
    eager = [c for c in constraints if not c.lazy]
    if len(eager) < len(constraints):
        found = least_norm_root_within(problem, start, eager, options, free)
        lazy = [c for c in constraints if c.lazy]
        if found.honoured and not broken_constraint(problem, lazy, found.beta):
            return found
    return least_norm_root_within(problem, start, constraints, options, free)


def nearest_root(
    scenario: Scenario,
    found: SearchResult,
    options: SolveOptions,
    constraints: Sequence[Constraint],
) -> Nearest:
    """The search's result, or a root nearer the quintic when its path is not natural.

    Args:
        scenario: the resolved scenario that was searched.
        found: the search's result.
        options: solver settings (attitude tolerance, rad).
        constraints: the path constraints every root must keep.
    """
    problem, beta = found.problem, found.solution.beta
    if problem.planar or not scenario.raise_freedom:
        return Nearest(found, ())
    if _largest_excursion(problem, beta) <= NATURAL_EXCURSION:
        return Nearest(found, ())
    names = scenario.robot.joint_names
    offset = np.array([2.0 * np.pi * found.full_turns.get(n, 0) for n in names], dtype=float)
    base = [found.freedom[n] for n in names]
    # whether the constraints bind: the eager ones, the likelier to, checked first
    eager_first = sorted(constraints, key=lambda c: c.lazy)
    best = found
    tried: list[str] = []
    for k in LEVELS:
        counts = [max(b, k) if b > 0 else 0 for b in base]  # a held joint stays held
        if counts == [best.freedom[n] for n in names]:
            continue
        level = problem_from_scenario(
            scenario, extra=counts, goal_offset=offset, mmap=problem.mmap, check_bounds=False
        )
        start = level.family.embed(best.problem.family, best.solution.beta)
        if start is None:
            break
        free = least_norm_root(level, start, options)
        candidate, how = free.beta, "least-norm SQP"
        residual = float(np.linalg.norm(free.residual))  # no second integration of its path
        if broken_constraint(level, eager_first, candidate):  # the constraints bind
            within = _within(level, start, constraints, options, candidate)
            candidate, residual = within.beta, within.residual
            how = "least-norm SQP within the constraints"
        checked = certify(level, candidate, residual, options.tolerance)
        deviation = float(checked.beta @ checked.beta)
        best_deviation = float(best.solution.beta @ best.solution.beta)
        if (
            not checked.passed
            or deviation >= best_deviation
            or broken_constraint(checked.problem, constraints, checked.beta)
        ):
            tried.append(f"nearest root, freedom {k}: not kept")
            continue
        excursion = _largest_excursion(checked.problem, checked.beta)
        tried.append(
            f"nearest root, freedom {k}: deviation {np.degrees(np.sqrt(deviation)):.3g} deg RMS, "
            f"largest excursion {np.degrees(excursion):.3g} deg"
        )
        length = checked.problem.path_length(checked.beta)
        solution = replace(
            found.solution,
            beta=checked.beta,
            residual=checked.residual,
            roots=(Root(checked.beta, checked.residual, length),),
            integration_error=checked.integration_error,
            steps=checked.problem.steps,
            method=f"{found.solution.method}, then {how} with {k} per joint",
        )
        best = replace(
            found,
            problem=checked.problem,
            solution=solution,
            freedom=dict(zip(names, counts, strict=True)),
        )
        if excursion <= NATURAL_EXCURSION:
            break
    return Nearest(best, tuple(tried))
