"""Linearised constraint rows for the Newton-type solvers (continuation, least-norm roots).

:func:`linear_rows` stacks every constraint's values ``g`` (``g <= 0`` feasible, each in its
constraint's unit) and their Jacobian ``G = dg/dbeta`` at a set of normalised instants; the
rows of affine constraints (joint limits) are computed once per path family and instants.
:func:`with_critical` adds the instants where a path is tightest, so that a path held inside
at the instants is pushed inside between them too; :func:`with_dips` the instants where a
constraint that picks its own instants (clearance) found the path beyond its limit, where that
constraint alone gets rows besides its own.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..problem.constraints import DEFAULT_INSTANTS, Constraint
from ..problem.residual import Problem

__all__ = [
    "MAX_ADDED_INSTANTS",
    "NO_DIPS",
    "RowCache",
    "linear_rows",
    "rows_instants",
    "tightest_instants",
    "with_critical",
    "with_dips",
    "with_picked",
]

#: Most instants kept besides the default ones (the tightest instants found on the way).
MAX_ADDED_INSTANTS = 256

#: No dips (:func:`with_dips`): constraints with their own instants keep to them.
NO_DIPS = np.zeros(0)

#: Affine constraint rows at beta = 0 by (constraint index, instants), for one path family.
RowCache = dict[tuple[int, bytes], tuple[np.ndarray, np.ndarray]]


def linear_rows(
    problem: Problem,
    constraints: Sequence[Constraint],
    beta: np.ndarray,
    instants: np.ndarray,
    cache: RowCache,
    dips: np.ndarray = NO_DIPS,
) -> tuple[np.ndarray, np.ndarray]:
    """Stacked constraint values ``g`` and Jacobian ``G`` at ``beta`` (g <= 0 feasible).

    Affine constraints are evaluated once per instants (``cache``, one path family), then
    ``g = g0 + G beta``, and at the path's own tight instants
    (:meth:`~freefloat.problem.constraints.Constraint.tight_instants`, a joint's extremes),
    so that a path these rows hold inside stays inside between the instants too. A constraint
    with its own instants is asked at the default ones and ``dips`` (:func:`rows_instants`).
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
        at = rows_instants(constraint, instants, dips)
        if constraint.affine:
            key = (index, at.tobytes())
            cached = cache.get(key)
            if cached is None:
                at_zero = constraint.rows(problem, np.zeros(problem.n_free), at)
                cached = (at_zero.values, at_zero.jacobian)
                if len(cache) > 64:
                    cache.clear()
                cache[key] = cached
            values.append(cached[0] + cached[1] @ beta)
            rows.append(cached[1])
        else:
            r = constraint.rows(problem, beta, at)
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

    The default instants, the last :data:`MAX_ADDED_INSTANTS` others of ``instants``, and the
    tightest instants of the path at ``beta`` (:func:`tightest_instants`).
    """
    extra = tightest_instants(problem, constraints, beta)
    added = np.setdiff1d(instants, DEFAULT_INSTANTS)[-MAX_ADDED_INSTANTS:]
    return np.unique(np.concatenate([DEFAULT_INSTANTS, added, extra]).clip(0.0, 1.0))


def with_dips(
    problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray, dips: np.ndarray
) -> np.ndarray:
    """``dips`` with the instants where the path at ``beta`` dips beyond a limit.

    The limits of the constraints with their own instants
    (:meth:`~freefloat.problem.constraints.Constraint.critical_times`, normalised), in the
    order found, each once, the last :data:`MAX_ADDED_INSTANTS` kept. Only such constraints
    (clearance) get rows there (:func:`rows_instants`): the corrector then takes the path
    back inside at the dip, where the constraint's own instants would bring back the same
    path.
    """
    path = problem.polynomials(beta)
    found = [
        np.asarray(c.critical_times(problem.robot, path), dtype=float) / problem.duration
        for c in constraints
        if c.own_instants and c.applies_to(problem.robot)
    ]
    return _joined(dips, found)


def with_picked(
    problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray, dips: np.ndarray
) -> np.ndarray:
    """``dips`` with the instants the constraints with their own instants pick at ``beta``.

    (:meth:`~freefloat.problem.constraints.Constraint.picked_instants`.) A corrector that
    passes them on keeps rows at the instants of every iterate, not only at those its last
    iterate picked. ``dips`` are all kept: past :data:`MAX_ADDED_INSTANTS`, new picks are not
    added.
    """
    found = [
        c.picked_instants(problem, beta)
        for c in constraints
        if c.own_instants and c.applies_to(problem.robot)
    ]
    new = np.setdiff1d(np.concatenate([np.zeros(0), *found]), dips)
    return np.concatenate([dips, new[: max(0, MAX_ADDED_INSTANTS - len(dips))]])


def _joined(dips: np.ndarray, found: Sequence[np.ndarray]) -> np.ndarray:
    """``dips`` then ``found`` (normalised), each once in the order met, the last kept."""
    joined = np.concatenate([dips, *found]).clip(0.0, 1.0)
    _, first = np.unique(joined, return_index=True)
    return joined[np.sort(first)][-MAX_ADDED_INSTANTS:]


def rows_instants(constraint: Constraint, instants: np.ndarray, dips: np.ndarray) -> np.ndarray:
    """The instants ``constraint``'s rows are asked at.

    ``instants``, or for a constraint with its own instants (clearance) the default ones and
    the ``dips`` (:func:`with_dips`).
    """
    if not constraint.own_instants:
        return instants
    return np.union1d(DEFAULT_INSTANTS, dips) if len(dips) else DEFAULT_INSTANTS
