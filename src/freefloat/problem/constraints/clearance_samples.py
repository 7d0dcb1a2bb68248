"""Samples of clearance along a path: what the dense check measured, and its minima.

Helpers of :mod:`freefloat.problem.constraints.clearance` (the constraint's module stays a
readable size): the record of a path's measured samples with each pair's bounds and the
spheres' lever arms there, the bound of the clearance between two samples, the intervals
that bound leaves undecided, the local minima of sampled values and their refinement in
time, the rows already measured at one ``beta`` (:class:`RowsAtBeta`) and the pairs the rows
take (:class:`MovedPairs`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ...robot.collision import Closest, CollisionModel
from ...robot.motion_bound import BOUND_SLACK
from ..paths import JointPolynomials, PathFamily
from ..rate_bounds import rate_bounds
from ..scalar_minimum import scalar_minimum

__all__ = [
    "Measured",
    "MovedPairs",
    "RowsAtBeta",
    "arms_table",
    "bounds_between",
    "lever_arms",
    "local_minima",
    "lowest_minima",
    "minima_floors",
    "pair_bounds",
    "refined_minima",
    "refinement",
    "undecided",
]


@dataclass(frozen=True)
class Measured:
    """The samples of a path the dense check measured, and what it bounded from them.

    Attributes:
        known: (S,) smallest distance over the pairs per sample (m; NaN where spared).
        lower: (S, P) lower bounds of every pair's distance per sample (m; NaN where spared).
        bound: a lower bound of the clearance along the whole path (m).
        arms: (S, G, N) the bounding spheres' lever arms about the joint axes per sample (m;
            NaN where spared; (S, 0) for a model without lever arms).
    """

    known: np.ndarray
    lower: np.ndarray
    bound: float
    arms: np.ndarray


class MovedPairs:
    """The pairs the free coefficients of a path family move, for the solver rows.

    :meth:`CollisionModel.pairs_moved_by` the joints with free coefficients; None (every
    pair) when they move all of them or none. The last family's answer is kept.
    """

    def __init__(self, model: CollisionModel) -> None:
        self._model = model
        self._family: PathFamily | None = None
        self._among: np.ndarray | None = None

    def __call__(self, family: PathFamily) -> np.ndarray | None:
        """(P,) which pairs the rows of ``family``'s paths take, or None for every pair."""
        if family is not self._family:
            moved = self._model.pairs_moved_by(np.array(family.degrees) > 5)
            self._family, self._among = family, None if moved.all() or not moved.any() else moved
        return self._among


class RowsAtBeta:
    """The rows (value, m; Jacobian row, m per unit of ``beta``) measured at one path, per instant.

    A solver asks for the rows at one ``beta`` more than once with other instants (the
    predictor after the corrector, without the corrector's picked instants): an instant
    measured at that ``beta`` is not measured again. An instant's row does not depend on the
    other instants asked with it (the smallest distance and its pair do not depend on the
    batch: :meth:`CollisionModel.closest_many`), so the rows are those of a fresh query, to
    rounding (the joints of a batch come from one matrix product). Only the last ``beta`` (of
    one path family) is kept.
    """

    def __init__(self) -> None:
        self._family: object = None
        self._beta = b""
        self._known: dict[float, tuple[float, np.ndarray]] = {}

    def rows(
        self,
        family: object,
        beta: np.ndarray,
        instants: np.ndarray,
        measure: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
    ) -> tuple[np.ndarray, np.ndarray]:
        """Values and Jacobian at the normalised ``instants``; ``measure`` for those not known.

        ``measure(instants)`` gives the values (K,) and Jacobian (K, F) at ``instants``.
        """
        key = beta.tobytes()
        if family is not self._family or key != self._beta:
            self._family, self._beta, self._known = family, key, {}
        wanted = instants.tolist()
        known = self._known
        missing = list(dict.fromkeys(s for s in wanted if s not in known))  # in order, once
        if missing:
            values, jacobian = measure(np.array(missing))
            known.update(zip(missing, zip(values.tolist(), jacobian, strict=True), strict=True))
        width = len(beta)
        return (
            np.array([known[s][0] for s in wanted], dtype=float),
            np.array([known[s][1] for s in wanted], dtype=float).reshape(len(wanted), width),
        )


def pair_bounds(found: Closest) -> np.ndarray:
    """(B, P) the pairs' lower bounds (m) of a batch of queries."""
    assert found.lower is not None
    return found.lower


def bounds_between(
    model: CollisionModel,
    path: JointPolynomials,
    times: tuple[np.ndarray, np.ndarray],
    lower: tuple[np.ndarray, np.ndarray],
    arms: tuple[np.ndarray, np.ndarray],
) -> np.ndarray:
    """(I,) lower bounds (m) of the clearance over I intervals, from bounds at both ends.

    ``times``: (I,) the intervals' starts and ends (s); ``lower``: (I, P) lower bounds of
    every pair's distance there (m; the measured distance where measured); ``arms``: the
    spheres' :func:`lever_arms` there (m). Per pair: the mean of its bounds less half the
    interval times how fast that pair's distance can change on it (bounds of the joint rates
    times the bodies' lever arms about the joints' axes, never above their motion weights:
    :meth:`~freefloat.robot.pair_levers.PairLevers.speeds`); the clearance's bound is the
    smallest, less :data:`BOUND_SLACK`. The model must have motion weights.
    """
    assert model.weights is not None
    t0, t1 = times
    rates = rate_bounds(path, t0, t1)
    if model.levers is None:  # a model with motion weights alone
        speed = rates @ model.weights.T  # (I, P), m/s
    else:
        speed = model.levers.speeds(rates, t1 - t0, arms)
    per_pair = 0.5 * (lower[0] + lower[1] - speed * (t1 - t0)[:, None])
    per_pair = np.nan_to_num(per_pair, nan=-math.inf)  # no bound: nothing spared
    return np.min(per_pair, axis=1) - BOUND_SLACK


def lever_arms(model: CollisionModel, q: np.ndarray) -> np.ndarray:
    """(B, G, N) the spheres' lever arms about the joint axes at (B, N) joints ``q`` (m).

    :meth:`~freefloat.robot.pair_levers.PairLevers.arms`; (B, 0) for a model without them.
    """
    return np.zeros((len(q), 0)) if model.levers is None else model.levers.arms(q)


def arms_table(model: CollisionModel, count: int) -> np.ndarray:
    """(count, G, N) lever arms (m) all NaN, to be filled by :func:`lever_arms` as measured."""
    shape = (0,) if model.levers is None else model.levers.reach.shape
    return np.full((count, *shape), math.nan)


def lowest_minima(values: np.ndarray) -> list[int]:
    """Indices of the two lowest local minima of ``values`` (or the two lowest apart)."""
    n = len(values)
    minima = local_minima(values)
    order = [int(k) for k in minima[np.argsort(np.asarray(values)[minima], kind="stable")]]
    if len(order) < 2:
        far = [int(k) for k in np.argsort(values, kind="stable") if abs(int(k) - order[0]) > 2]
        order.append(far[0] if far else (order[0] + n // 2) % n)
    return order[:2]


def refined_minima(
    model: CollisionModel,
    path: JointPolynomials,
    t: np.ndarray,
    sampled: np.ndarray,
    minima: np.ndarray,
    floors: np.ndarray | None = None,
) -> tuple[float, float, int]:
    """The smallest sampled clearance (m), its time (s) and pair, minima refined.

    ``sampled``: the smallest distance over the pairs (m) at the times ``t`` (s). The sampled
    local minima at ``minima`` are refined by a bounded scalar search between their
    neighbouring samples (:func:`~freefloat.problem.scalar_minimum.scalar_minimum`), in
    order; with ``floors`` (m, one per minimum: a lower bound of the clearance between those
    samples, :func:`minima_floors`), a minimum whose floor is not below the smallest found so
    far is not searched: its search could not find less, so the answer is the same.
    """

    def lowest(s: float) -> tuple[float, int]:
        return model.closest_value(path.positions(np.array([s]))[0], s / path.duration)

    count = len(t)
    k_best = int(np.argmin(sampled))
    best, best_t = float(sampled[k_best]), float(t[k_best])
    best_pair = lowest(best_t)[1]
    for i, index in enumerate(minima):
        if floors is not None and floors[i] >= best:
            continue
        k = int(index)
        lo, hi = float(t[max(k - 1, 0)]), float(t[min(k + 1, count - 1)])
        result = scalar_minimum(lambda s: lowest(s)[0], lo, hi, 1e-9 * max(1.0, path.duration))
        if result.value < best:
            best, best_t = result.value, result.x
            best_pair = lowest(best_t)[1]
    return best, best_t, best_pair


def minima_floors(
    model: CollisionModel,
    path: JointPolynomials,
    t: np.ndarray,
    minima: np.ndarray,
    tables: tuple[np.ndarray, np.ndarray],
) -> np.ndarray:
    """(M,) lower bounds (m) of the clearance between the samples next to each minimum.

    ``t``: the samples' times (s), ascending; ``minima``: indices into them;
    ``tables``: the pairs' bounds (m) and the spheres' lever arms (m) at each sample, in the
    same order (NaN where a sample was not measured: no bound there, -inf). The smaller of
    :func:`bounds_between` over the interval before each minimum and the one after it, over
    which :func:`refined_minima` searches.
    """
    if not len(minima):
        return np.zeros(0)
    last = len(t) - 1
    before, after = np.maximum(minima - 1, 0), np.minimum(minima + 1, last)
    first = np.concatenate([before, minima])
    second = np.concatenate([minima, after])
    table, arms = tables
    bound = bounds_between(
        model,
        path,
        (t[first], t[second]),
        (table[first], table[second]),
        (arms[first], arms[second]),
    )
    return np.minimum(bound[: len(minima)], bound[len(minima) :])  # -inf where spared


def refinement(grid: np.ndarray, k: int, count: int) -> np.ndarray:
    """``count`` instants on each side of grid point ``k`` (normalised), none on the grid."""
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    return np.linspace(lo, hi, 2 * count + 2)[1:-1]


def local_minima(values: np.ndarray) -> np.ndarray:
    """Indices of the local minima of ``values`` (an end counts against its one neighbour)."""
    left = np.concatenate([[np.inf], values[:-1]])
    right = np.concatenate([values[1:], [np.inf]])
    return np.flatnonzero((values <= left) & (values <= right))


def undecided(
    model: CollisionModel,
    path: JointPolynomials,
    ends: np.ndarray,
    tables: tuple[np.ndarray, np.ndarray],
    limit: float,
    below: float | None = None,
) -> np.ndarray:
    """Which intervals may dip below ``limit`` (m) unseen (a boolean per column of ``ends``).

    ``ends``: rows t0, t1 (s), v0, v1 (m), and the rows of ``tables`` (the pairs' bounds and
    the spheres' lever arms, m) at both ends. Both ends measured and above ``limit`` (a sample
    below it is a dip seen), and the bound between them (:func:`bounds_between`) below it, or
    below ``below`` (m, at most ``limit``) when given: an interval whose bound is above the
    smallest value measured anywhere cannot hold the path's smallest clearance.
    """
    seen = ~np.isnan(ends[2]) & ~np.isnan(ends[3]) & (ends[2] >= limit) & (ends[3] >= limit)
    bound = np.full(ends.shape[1], math.inf)
    if np.any(seen):
        first, second = ends[4, seen].astype(int), ends[5, seen].astype(int)
        table, arms = tables
        bound[seen] = bounds_between(
            model,
            path,
            (ends[0, seen], ends[1, seen]),
            (table[first], table[second]),
            (arms[first], arms[second]),
        )
    return bound < (limit if below is None else min(below, limit))
