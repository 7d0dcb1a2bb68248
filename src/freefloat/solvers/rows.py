"""Linearised constraint rows for the Newton-type solvers (continuation, least-norm roots).

:func:`linear_rows` stacks every constraint's values ``g`` (``g <= 0`` feasible, each in its
constraint's unit) and their Jacobian ``G = dg/dbeta`` at a set of normalised instants; the
rows of affine constraints (joint limits) are computed once per path family and instants.
:func:`with_critical` adds the instants where a path is tightest, so that a path held inside
at the instants is pushed inside between them too.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..problem.constraints import DEFAULT_INSTANTS, Constraint
from ..problem.residual import Problem

__all__ = [
    "MAX_ADDED_INSTANTS",
    "RowCache",
    "linear_rows",
    "tightest_instants",
    "with_critical",
]

#: Most instants kept besides the default ones (the tightest instants found on the way).
MAX_ADDED_INSTANTS = 256

#: Affine constraint rows at beta = 0 by (constraint index, instants), for one path family.
RowCache = dict[tuple[int, bytes], tuple[np.ndarray, np.ndarray]]


def linear_rows(
    problem: Problem,
    constraints: Sequence[Constraint],
    beta: np.ndarray,
    instants: np.ndarray,
    cache: RowCache,
) -> tuple[np.ndarray, np.ndarray]:
    """Stacked constraint values ``g`` and Jacobian ``G`` at ``beta`` (g <= 0 feasible).

    Affine constraints are evaluated once per instants (``cache``, one path family), then
    ``g = g0 + G beta``, and at the path's own tight instants
    (:meth:`~freefloat.problem.constraints.Constraint.tight_instants`, a joint's extremes),
    so that a path these rows hold inside stays inside between the instants too.
    """
    values, rows = [np.zeros(0)], [np.zeros((0, problem.n_free))]
    for index, constraint in enumerate(constraints):
        if not constraint.applies_to(problem.robot):
            continue
        tight = constraint.tight_instants(problem, beta)
        if len(tight):
            at_tight = constraint.rows(problem, beta, tight)
            values.append(at_tight.values)
            rows.append(at_tight.jacobian)
        if constraint.affine:
            key = (index, instants.tobytes())
            cached = cache.get(key)
            if cached is None:
                at_zero = constraint.rows(problem, np.zeros(problem.n_free), instants)
                cached = (at_zero.values, at_zero.jacobian)
                if len(cache) > 64:
                    cache.clear()
                cache[key] = cached
            values.append(cached[0] + cached[1] @ beta)
            rows.append(cached[1])
        else:
            r = constraint.rows(problem, beta, instants)
            values.append(r.values)
            rows.append(r.jacobian)
    return np.concatenate(values), np.concatenate(rows)


def tightest_instants(
    problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray
) -> np.ndarray:
    """The normalised times where each constraint is tightest on the path at ``beta``.

    Constraints that pick their own instants (clearance) are left out.
    """
    path = problem.polynomials(beta)
    extra = [
        np.asarray(c.critical_times(problem.robot, path), dtype=float) / problem.duration
        for c in constraints
        if not c.own_instants
    ]
    return np.concatenate([np.zeros(0), *extra])


def with_critical(
    problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray, instants: np.ndarray
) -> np.ndarray:
    """``instants`` kept to the defaults and their last added, with the path's tightest.

    The default instants, the last :data:`MAX_ADDED_INSTANTS` others of ``instants``, the
    tightest instants of the path at ``beta`` (:func:`tightest_instants`), and those where a
    constraint with its own instants (clearance) finds the path beyond its limit
    (:meth:`~freefloat.problem.constraints.Constraint.critical_times`): its rows there let
    the corrector take the path back inside at the dip.
    """
    path = problem.polynomials(beta)
    dips = [
        np.asarray(c.critical_times(problem.robot, path), dtype=float) / problem.duration
        for c in constraints
        if c.own_instants
    ]
    extra = np.concatenate([tightest_instants(problem, constraints, beta), *dips])
    added = np.setdiff1d(instants, DEFAULT_INSTANTS)[-MAX_ADDED_INSTANTS:]
    return np.unique(np.concatenate([DEFAULT_INSTANTS, added, extra]).clip(0.0, 1.0))
