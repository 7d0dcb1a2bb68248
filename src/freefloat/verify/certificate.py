"""The continuous-time clearance certificate of a path (see :mod:`freefloat.verify.clearance`).

Work goes to the (interval, pair) with the lowest lower bound first (a heap), so the smallest
measured clearance is found early and every interval whose bound lies within
:func:`tolerance` of it is settled without more queries. Before any query, the intervals the
single bounding spheres leave open are bounded again from the meshes' leaf spheres
(:mod:`.sphere_tree`): their gaps, and the least over leaf pairs of each leaf pair's own
Lipschitz bound (:mod:`.first_pass`). Each item is refined in three steps: for two meshes,
lower bounds at its two ends from a separating direction over their own vertices
(:mod:`.separation`: tens of microseconds against a mesh query's hundreds), then exact
distances there (one end first, whose distance less the pair's speed over the whole interval
may settle it without the other), then a second-order bound over it where that can settle it
(:mod:`.taylor`: the rate of change at the middle and the points' accelerations, against the
first-order bounds' largest speed times the width), then halving, the middle bounded the
same way; each new interval's bound is the larger of the whole bodies' and the leaf pairs'
(:func:`_leaf_value`).
Before it stops, the instants whose bounds lie below the least clearance measured are
measured, so that figure is the least of what the bounds leave possible
(:data:`~.settling.LAST_LOOKS` at most). A pair's speed
comes from its bodies' reach from the joints, and where that leaves an interval open from
their lever arms about the joints' axes over the first-pass interval that holds it
(:mod:`.interval_levers`: never faster).
"""

from __future__ import annotations

import heapq
import math

import numpy as np

from ..robot.collision import CollisionModel
from .clearance import (
    CHECK_TOLERANCE,
    FIRST_INSTANTS,
    MAX_BISECTIONS,
    ClearanceCertificate,
    MeshClearance,
)
from .first_pass import first_pass
from .hull_agreement import hull_agreement
from .instants import Instants
from .interval_levers import IntervalLevers
from .motion import PolynomialMotion
from .settling import EXACT, LAST_LOOKS, SEPARATED, SPHERES, TAYLOR, Item, Least, settled_above
from .taylor import IntervalTaylor

__all__ = ["certify"]


def certify(
    mesh: MeshClearance,
    motion: PolynomialMotion,
    margin: float,
    solver: CollisionModel | None = None,
    instants: int = FIRST_INSTANTS,
) -> ClearanceCertificate:
    """Certify that every checked pair stays ``margin`` apart (m) at every instant of ``motion``.

    Args:
        mesh: the original-geometry model.
        motion: the joint paths.
        margin: required clearance (m).
        solver: the solvers' hull model, to compare its figures with the mesh's.
        instants: instants of the first, uniform pass (>= 2).
    """
    if not mesh.pairs:  # no pair to keep apart: clear at every instant
        return ClearanceCertificate(
            margin, math.inf, math.inf, 0.0, "", "no pairs", False, 0, 0, certified=True
        )
    store = Instants(mesh, motion)
    times = np.linspace(0.0, motion.duration, instants)
    # the first pass's instants of even index: its intervals measure these ends first
    even = {float(t) for t in times[::2]}
    levers = IntervalLevers(store, times)
    least, lower, heap = first_pass(mesh, (store, levers), times, margin)
    bisections, exhausted = _refine(store, (least, levers), margin, heap, even)
    if heap:
        lower = min(lower, heap[0][0])
    contained = _contained_at_start(mesh, store)
    if contained is not None:
        least = Least(min(least.value, -store.distance(0.0, contained)), 0.0, contained)
        lower = min(lower, least.value)
    lower = min(lower, least.value)
    agreement = (-math.inf, "")
    if solver is not None:
        when = least.time
        agreement = hull_agreement(
            mesh,
            solver,
            when,
            motion.joints(when),
            store.at(when),
            {k for (t, k) in store.exact if t == when},
            lambda k: store.distance(when, k),
        )
    return ClearanceCertificate(
        margin=margin,
        lower_bound=lower,
        measured=least.value,
        time=least.time,
        pair=mesh.names[least.pair],
        kind=mesh.kinds[least.pair] + (", contained" if contained == least.pair else ""),
        penetration=least.value < 0.0,
        instants=len(store.placements),
        bisections=bisections,
        certified=lower >= margin - CHECK_TOLERANCE,
        exhausted=exhausted,
        hull_excess=agreement[0],
        hull_detail=agreement[1],
    )


def _refine(
    store: Instants,
    work: tuple[Least, IntervalLevers],
    margin: float,
    heap: list[Item],
    even: set[float],
) -> tuple[int, bool]:
    """Settle the heap's items, lowest bound first: (intervals halved, budget spent).

    An item bounded by the spheres is bounded next from its ends' separating directions,
    then from exact distances there, then by the second-order bound over it
    (:func:`_taylor_value`), then halved. Before stopping, an instant whose bound
    lies below the least measured clearance is measured (at most :data:`LAST_LOOKS`), so the
    figure reported is the least of what the bounds leave possible, and the threshold
    follows it.
    """
    least, levers = work
    taylor = IntervalTaylor(store)
    bisections, looks = 0, 0
    while True:
        if not heap or heap[0][0] >= settled_above(least.value, margin):
            # every item left is within the accuracy of the minimum, unless it moves
            if looks < LAST_LOOKS and _look_below(store, least):
                looks += 1
                continue
            return bisections, False
        lb, t0, t1, k, level, speed = heapq.heappop(heap)
        if level == SPHERES:
            bounded = None
            if k in store.mesh.separable:  # two meshes: bounds first (Instants.lower)
                bounded = _bound_ends(store, least, margin, (t0, t1, k, speed))
            if bounded is not None:
                heapq.heappush(heap, (bounded[0], t0, t1, k, bounded[1], speed))
                continue
            level = SEPARATED
        if level == SEPARATED:
            value = _measure_ends(store, least, margin, t0 in even, (t0, t1, k, speed))
            heapq.heappush(heap, (value, t0, t1, k, EXACT, speed))
            continue
        if bisections >= MAX_BISECTIONS:
            heapq.heappush(heap, (lb, t0, t1, k, level, speed))
            return bisections, True
        if level == EXACT:  # the second-order bound over it, where it can settle it
            threshold = settled_above(least.value, margin)
            value = _taylor_value(store, (taylor, heap), threshold, (t0, t1, k, speed))
            if value > lb:
                heapq.heappush(heap, (value, t0, t1, k, TAYLOR, speed))
                continue
        bisections += 1
        for item in _halves(store, (least, levers), margin, heap, (t0, t1, k)):
            heapq.heappush(heap, item)


def _taylor_value(
    store: Instants,
    work: tuple[IntervalTaylor, list[Item]],
    threshold: float,
    item: tuple[float, float, int, float],
) -> float:
    """The second-order bound (m) over an item with exact ends, or -inf where it cannot settle.

    ``item``: its ends (s), pair and speed bound (m/s). The bound lies at or below the
    distance at both ends, and at or below the separation along its direction at the middle
    (:meth:`.Instants.separation`, at most the distance there: at most the nearer end's plus
    the speed times half the width) less its second-order term: when either ceiling is below
    ``threshold`` (m) the bound cannot settle the item and is not worked out. One evaluation
    at most per item, outside the halving budget (:data:`MAX_BISECTIONS`).
    """
    taylor, heap = work
    t0, t1, k, speed = item
    half, middle = 0.5 * (t1 - t0), 0.5 * (t0 + t1)
    nearer = min(store.distance(t0, k), store.distance(t1, k))
    if nearer < threshold:
        return -math.inf
    spread = taylor.spread(t0, t1, k)
    loss = 0.5 * spread * half * half
    if nearer + half * speed - loss < threshold:
        return -math.inf
    if middle not in store.joints:  # with the middles halving would ask for next
        store.load(_middles(store, heap, t0, t1))
    if store.separation(middle, k) - loss < threshold:
        return -math.inf
    return taylor.bound(t0, t1, k, spread)


def _look_below(store: Instants, least: Least) -> bool:
    """Measure the smallest separating-direction bound's instant and pair if it is below ``least``.

    True when it did: the exact distance there may be below the least measured (m). An
    instant with no bound (-inf: its hulls touch) is not one: it was left unmeasured on
    purpose (an interval settled from its other end, :func:`_measure_ends`).
    """
    open_ = [
        (v, t, k)
        for (t, k), v in store.separated.items()
        if v > -math.inf and (t, k) not in store.exact
    ]
    if not open_:
        return False
    value, t, k = min(open_)
    if value >= least.value:
        return False
    least.note(store.distance(t, k), t, k)
    return True


def _measure_ends(
    store: Instants,
    least: Least,
    margin: float,
    start_first: bool,
    item: tuple[float, float, int, float],
) -> float:
    """A first-pass item's bound (m) from exact distances at its ends.

    ``item``: its ends (s), pair and speed bound (m/s). One end first: one already measured,
    else the start when ``start_first`` (the grid's even instants, each shared by two
    intervals). The distance there less the pair's speed over the whole interval bounds it;
    when that settles it, the other end is not measured. Otherwise the mean of both ends
    less half the speed times the width, raised by the leaf pairs' bound
    (:func:`_leaf_value`) when still below the settling threshold.
    """
    t0, t1, k, speed = item
    if (t0, k) in store.exact or ((t1, k) not in store.exact and start_first):
        first, other = t0, t1
    else:
        first, other = t1, t0
    d = store.distance(first, k)
    least.note(d, first, k)
    if (other, k) not in store.exact:
        threshold = settled_above(least.value, margin)
        one_end = d - speed * (t1 - t0)
        if one_end < threshold:  # the leaf pairs' own speeds may settle it
            rates = store.rates([t0], [t1])[0]
            one_end = max(one_end, _leaf_value(store, k, first, other, rates, one_end=True))
        if one_end >= threshold:
            return one_end
    d0, d1 = store.distance(t0, k), store.distance(t1, k)
    least.note(d0, t0, k)
    least.note(d1, t1, k)
    value = 0.5 * (d0 + d1 - speed * (t1 - t0))
    if value < settled_above(least.value, margin):  # the leaf pairs may settle it
        value = max(value, _leaf_value(store, k, t0, t1, store.rates([t0], [t1])[0]))
    return value


def _bound_ends(
    store: Instants, least: Least, margin: float, item: tuple[float, float, int, float]
) -> tuple[float, int] | None:
    """A first-pass item's bound (m) from lower bounds at its ends, and their level.

    ``item``: its ends (s), pair and speed bound (m/s). The ends' separating-direction bounds
    (or exact distances where measured), raised by the leaf pairs' bound where still below
    the settling threshold; None when an end has no such bound (touching hulls).
    """
    t0, t1, k, speed = item
    d0, d1 = store.lower(t0, k), store.lower(t1, k)
    if d0 == -math.inf or d1 == -math.inf:
        return None
    value = 0.5 * (d0 + d1 - speed * (t1 - t0))
    if value < settled_above(least.value, margin):
        value = max(value, _leaf_value(store, k, t0, t1, store.rates([t0], [t1])[0]))
    exact = (t0, k) in store.exact and (t1, k) in store.exact
    return value, EXACT if exact else SEPARATED


def _halves(
    store: Instants,
    work: tuple[Least, IntervalLevers],
    margin: float,
    heap: list[Item],
    interval: tuple[float, float, int],
) -> list[Item]:
    """The two halves of pair k's interval ``[t0, t1]`` (s, its ends exact), as heap items.

    The middle's separating-direction bound where it gives one, else its exact distance
    (noted in ``least``). Each half's bound uses the pair's speed from its bodies' reach,
    then from their lever arms and from the leaf pairs where those leave it open.
    """
    least, levers = work
    t0, t1, k = interval
    mesh = store.mesh
    mid = 0.5 * (t0 + t1)
    if mid not in store.joints:  # with the middles of its halves and of other intervals
        store.load(_middles(store, heap, t0, t1))
    if store.lower(mid, k) == -math.inf:
        least.note(store.distance(mid, k), mid, k)
    rates = store.rates([t0, mid], [mid, t1])
    threshold = settled_above(least.value, margin)
    items: list[Item] = []
    for (a, b), rate in zip(((t0, mid), (mid, t1)), rates, strict=True):
        ends = store.lower(a, k) + store.lower(b, k)
        speed = float(rate @ mesh.pair_reach[:, k])
        value = 0.5 * (ends - speed * (b - a))
        if value < threshold:  # the lever arms' speed (never above the reach's)
            speed = float(rate @ levers.pair(levers.interval(a), k))
            value = 0.5 * (ends - speed * (b - a))
        if value < threshold:
            value = max(value, _leaf_value(store, k, a, b, rate))
        exact = (a, k) in store.exact and (b, k) in store.exact
        items.append((value, a, b, k, EXACT if exact else SEPARATED, speed))
    return items


def _middles(store: Instants, heap: list[Item], t0: float, t1: float) -> np.ndarray:
    """Instants (s) likely needed next: ``[t0, t1]``'s middle and those of its halves.

    And the same for every interval in ``heap`` whose middle is not loaded yet: all loaded
    in one evaluation of the paths, whose cost is mostly per call.
    """
    out: list[float] = []
    seen: set[float] = set()
    for a, b in ((t0, t1), *((item[1], item[2]) for item in heap)):
        mid = 0.5 * (a + b)
        if mid not in seen and mid not in store.joints:
            seen.add(mid)
            out += [mid, 0.5 * (a + mid), 0.5 * (mid + b)]
    return np.array(out)


def _leaf_value(
    store: Instants, k: int, a: float, b: float, rates: np.ndarray, one_end: bool = False
) -> float:
    """A lower bound (m) of pair k's distance between ``a`` and ``b`` (s) from its leaf pairs.

    The distance of two bodies clear of each other is the least of the distances between
    their leaves' triangles. Each of those is at least the exact distance at an end and at
    least its leaf pair's bound there, and moves no faster than the leaf pair's own speed
    bound (``rates``: the joint-rate bounds on the interval, rad/s or m/s), which for a leaf
    near a joint's axis is far below the whole body's. With ``one_end``, only ``a`` is
    measured: at ``b`` each leaf pair's distance is at least its bound there and at least its
    value at ``a`` less its speed times the width. With a penetration at a measured end, -inf
    (the whole body's bound stands alone).
    """
    width = abs(b - a)
    da = store.lower(a, k)
    db = -math.inf if one_end else store.lower(b, k)
    if da <= 0.0 or (db <= 0.0 and not one_end):
        return -math.inf
    travel = (rates @ store.leaf_reach(k)) * width
    start = np.maximum(da, store.gaps(a, k))
    end = np.maximum(store.gaps(b, k), start - travel)
    if not one_end:
        end = np.maximum(end, db)
    return float(np.min(0.5 * (start + end - travel)))


def _contained_at_start(mesh: MeshClearance, store: Instants) -> int | None:
    """A pair one of whose bodies starts inside the other's closed mesh, if any.

    Inside by the winding number, and clear of the mesh's surface (positive distance: coal
    measures a mesh's triangles, not its inside). A pair a plane separates is neither
    (:meth:`.Instants.separation`, tens of microseconds); then the winding number, and the
    exact query only for a pair found inside.
    """
    placements = store.at(0.0)
    near = np.flatnonzero(mesh.sphere_bounds(placements) < 0.0)
    for k in near:
        if store.separation(0.0, int(k)) > 0.0:
            continue
        if mesh.contained(placements, int(k)) and store.distance(0.0, int(k)) > 0.0:
            return int(k)
    return None
