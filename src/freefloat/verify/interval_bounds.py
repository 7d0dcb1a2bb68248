"""Lower bounds of a pair's distance over an interval whose ends are measured (or one end).

For the clearance certificate (:mod:`freefloat.verify.certificate`): the mean of the exact
distances at the ends less half the pair's speed times the width (from the bodies' reach, or
their lever arms, :mod:`.interval_levers`), and the least over the pair's leaf pairs of the
same bound with each leaf pair's own gaps and speed (:func:`leaf_bound`). Every bound holds for
the distance at every instant of the interval, so the largest of them does.
"""

from __future__ import annotations

import math

import numpy as np

from .instants import Instants
from .interval_levers import IntervalLevers

__all__ = ["halves", "leaf_bound", "leaf_value"]


def halves(
    work: tuple[Instants, IntervalLevers],
    k: int,
    times: tuple[float, float, float],
    rates: np.ndarray,
    threshold: float,
) -> list[float]:
    """Lower bounds (m) of pair k's distance on the two halves of an interval, ends measured.

    ``times``: start, middle and end (s); ``rates``: (2, N) the joint-rate bounds on each half.
    Each half's bound is the mean of its ends less half the pair's speed times its width;
    each finer bound only while the last leaves a half below ``threshold`` (m): the whole
    bodies' speed from their reach, then from their lever arms (:mod:`.levers`), then the leaf
    pairs' bound (:func:`leaf_bound`, on the leaves' lever arms). Each is a lower bound, so
    the larger is.
    """
    store, levers = work
    i = levers.interval(times[0])
    ends = [store.distance(t, k) for t in times]
    widths = (times[1] - times[0], times[2] - times[1])
    speeds = (rates @ store.mesh.pair_reach[:, k]).tolist()
    values = [0.5 * (ends[h] + ends[h + 1] - speeds[h] * widths[h]) for h in range(2)]
    if min(values) < threshold:
        speeds = (rates @ levers.pair(i, k)).tolist()
        values = [0.5 * (ends[h] + ends[h + 1] - speeds[h] * widths[h]) for h in range(2)]
    if min(values) < threshold and min(ends) > 0.0:
        leaves = levers.leaves(i, k) @ rates.T  # (R, 2)
        for h in range(2):
            if values[h] < threshold:
                gaps = (store.gaps(times[h], k), store.gaps(times[h + 1], k))
                leaf = leaf_bound((ends[h], ends[h + 1]), gaps, leaves[:, h] * widths[h])
                values[h] = max(values[h], leaf)
    return values


def leaf_bound(
    ends: tuple[float, float], gaps: tuple[np.ndarray, np.ndarray], travel: np.ndarray
) -> float:
    """The least over a pair's leaf pairs of their own Lipschitz bounds on an interval (m).

    ``ends``: the pair's exact distances at the interval's ends (m; -inf where not measured:
    then each leaf pair's distance there is at least its value at the start less its travel);
    ``gaps``: its leaf pairs' gaps there (m); ``travel``: how far each leaf pair's distance
    can move over the interval (m). Both ends clear (a measured end positive): a penetration
    has no such bound.
    """
    start = np.maximum(ends[0], gaps[0])
    end = np.maximum(np.maximum(gaps[1], start - travel), ends[1])
    return float((0.5 * (start + end - travel)).min())


def leaf_value(
    work: tuple[Instants, IntervalLevers],
    k: int,
    ends: tuple[float, float],
    rates: np.ndarray,
    threshold: float,
    one_end: bool = False,
) -> float:
    """A lower bound (m) of pair k's distance between ``ends`` ``a`` and ``b`` (s), leaf pairs'.

    The distance of two bodies clear of each other is the least of the distances between
    their leaves' triangles. Each of those is at least the exact distance at an end and at
    least its leaf pair's bound there, and moves no faster than the leaf pair's own speed
    bound (``rates``: the joint-rate bounds on the interval, rad/s or m/s), which for a leaf
    near a joint's axis is far below the whole body's. With ``one_end``, only ``a`` is
    measured: at ``b`` each leaf pair's distance is at least its bound there and at least its
    value at ``a`` less its speed times the width. With a penetration at a measured end, -inf
    (the whole body's bound stands alone). The leaf pairs' speeds from their reach, then,
    while the bound lies below ``threshold`` (m), from their lever arms
    (:mod:`.interval_levers`; never faster, so the bound only rises).
    """
    (store, levers), (a, b) = work, ends
    width = abs(b - a)
    da = store.distance(a, k)
    db = -math.inf if one_end else store.distance(b, k)
    if da <= 0.0 or (db <= 0.0 and not one_end):
        return -math.inf
    gaps = (store.gaps(a, k), store.gaps(b, k))
    value = leaf_bound((da, db), gaps, (rates @ store.leaf_reach(k)) * width)
    if value < threshold:
        travel = (levers.leaves(levers.interval(min(a, b)), k) @ rates) * width
        value = max(value, leaf_bound((da, db), gaps, travel))
    return value
