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
from dataclasses import dataclass

import numpy as np

from ..problem.constraints import DEFAULT_INSTANTS, Constraint
from ..problem.residual import Problem

__all__ = [
    "MAX_ADDED_INSTANTS",
    "NO_DIPS",
    "Linearised",
    "RowCache",
    "linear_rows",
    "linearised",
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


@dataclass(frozen=True)
class Linearised:
    """The rows of the constraints that are not affine, measured at one path.

    The corrector measures them (clearance: exact distance queries) at its first iterate and
    where it would accept a path, and takes their linearisation ``g0 + G (beta - beta0)``
    between (a simplified Newton method for the inequality rows; the residual and its
    Jacobian stay exact at every iterate).

    Attributes:
        beta: the path they were measured at (free coefficients, rad or m).
        rows: per constraint (its index in the list), the values ``g0`` (its unit) and the
            Jacobian ``G`` (its unit per unit of ``beta``) there.
    """

    beta: np.ndarray
    rows: dict[int, tuple[np.ndarray, np.ndarray]]

    def at(self, index: int, beta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Constraint ``index``'s rows linearised at ``beta``: values and Jacobian."""
        g0, g_mat = self.rows[index]
        return g0 + g_mat @ (beta - self.beta), g_mat

    def trusted_at(self, beta: np.ndarray) -> bool:
        """Whether every row stays inside at ``beta`` even were its change twice as large.

        ``g0 + 2 max(G (beta - beta0), 0) <= 0`` for every row: the linearisation is then
        kept; otherwise the rows are measured again (a row at or near its limit, or one
        outside where it was measured, is always measured at the iterate itself).
        """
        step = beta - self.beta
        return all(
            bool(np.all(g0 + 2.0 * np.maximum(g_mat @ step, 0.0) <= 0.0))
            for g0, g_mat in self.rows.values()
        )

    def measured_at(self, beta: np.ndarray) -> bool:
        """Whether the rows were measured at ``beta`` itself (then they are exact)."""
        return bool(np.array_equal(self.beta, beta))


def linear_rows(
    problem: Problem,
    constraints: Sequence[Constraint],
    beta: np.ndarray,
    instants: np.ndarray,
    cache: RowCache,
    dips: np.ndarray = NO_DIPS,
    about: Linearised | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Stacked constraint values ``g`` and Jacobian ``G`` at ``beta`` (g <= 0 feasible).

    Affine constraints are evaluated once per instants (``cache``, one path family), then
    ``g = g0 + G beta``, and at the path's own tight instants
    (:meth:`~freefloat.problem.constraints.Constraint.tight_instants`, a joint's extremes),
    so that a path these rows hold inside stays inside between the instants too. A constraint
    with its own instants is asked at the default ones and ``dips`` (:func:`rows_instants`).
    With ``about``, the constraints that are not affine are not measured: their rows are
    the linearisation about the path they were measured at (:class:`Linearised`).
    """
    values, rows = [np.zeros(0)], [np.zeros((0, problem.n_free))]
    for index, constraint in enumerate(constraints):
        if not constraint.applies_to(problem.robot):
            continue
        if not constraint.affine:
            if about is None:
                g, g_mat = _costly_rows(problem, constraint, beta, instants, dips)
            else:
                g, g_mat = about.at(index, beta)
            values.append(g)
            rows.append(g_mat)
            continue
        tight = constraint.tight_instants(problem, beta)
        if len(tight):
            at_tight = constraint.rows(problem, beta, tight)
            values.append(at_tight.values)
            rows.append(at_tight.jacobian)
        at = rows_instants(constraint, instants, dips)
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
    return np.concatenate(values), np.concatenate(rows)


def _costly_rows(
    problem: Problem,
    constraint: Constraint,
    beta: np.ndarray,
    instants: np.ndarray,
    dips: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """A constraint's rows measured at ``beta``: at its tight instants, then at its instants.

    Both in one call (an attitude bound integrates the path once for all of them), except for
    a constraint that picks its own instants (clearance), whose rows are asked as they are.
    """
    at = rows_instants(constraint, instants, dips)
    tight = constraint.tight_instants(problem, beta)
    if len(tight) and not constraint.own_instants:
        at = np.concatenate([tight, at])
    elif len(tight):
        first = constraint.rows(problem, beta, tight)
        rest = constraint.rows(problem, beta, at)
        return (
            np.concatenate([first.values, rest.values]),
            np.concatenate([first.jacobian, rest.jacobian]),
        )
    found = constraint.rows(problem, beta, at)
    return found.values, found.jacobian


def linearised(
    problem: Problem,
    constraints: Sequence[Constraint],
    beta: np.ndarray,
    instants: np.ndarray,
    dips: np.ndarray = NO_DIPS,
) -> Linearised:
    """The rows of the constraints that are not affine, measured at ``beta`` and kept.

    The same rows :func:`linear_rows` measures at ``beta`` (instants and dips as there).
    """
    found = {
        index: _costly_rows(problem, constraint, beta, instants, dips)
        for index, constraint in enumerate(constraints)
        if not constraint.affine and constraint.applies_to(problem.robot)
    }
    return Linearised(np.array(beta, dtype=float), found)


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
