"""The continuous-time clearance certificate of a path (see :mod:`freefloat.verify.clearance`).

Work goes to the (interval, pair) with the lowest lower bound first (a heap), so the smallest
measured clearance is found early and every interval whose bound lies within
:func:`_tolerance` of it is settled without more queries. Before any query, the intervals the
single bounding spheres leave open are bounded again from the meshes' leaf spheres
(:mod:`.sphere_tree`): their gaps, and the least over leaf pairs of each leaf pair's own
Lipschitz bound. Each item is refined in two steps: exact distances at its two ends (in place
of the sphere bounds it starts from; one end first, whose distance less the pair's speed over
the whole interval may settle it without the other), then halving; each new interval's bound
is the larger of the whole bodies' and the leaf pairs' (:func:`_leaf_value`). A pair's speed
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
    ACCURACY,
    CHECK_TOLERANCE,
    FIRST_INSTANTS,
    MAX_BISECTIONS,
    SLACK_FRACTION,
    ClearanceCertificate,
    MeshClearance,
)
from .hull_agreement import hull_agreement
from .instants import Instants
from .interval_levers import IntervalLevers
from .motion import PolynomialMotion

__all__ = ["certify"]


def _tolerance(measured: float, margin: float) -> float:
    """How far below the smallest measured clearance a settled bound may lie (m).

    :data:`ACCURACY` near the margin, a fraction :data:`SLACK_FRACTION` of the slack above it:
    a bound that close to a minimum well clear of the margin still clears it.
    """
    return max(ACCURACY, SLACK_FRACTION * (measured - margin))


def _threshold(measured: float, margin: float) -> float:
    """The bound (m) at or above which an interval is settled, ``measured`` the least yet.

    Within :func:`_tolerance` of ``measured``; but not below what the ``clearance`` check
    needs while ``measured`` leaves room for it: a path 20 um clear of the margin must not
    fail because its bound was settled 100 um below its minimum. While ``measured`` clears
    the margin by :data:`CHECK_TOLERANCE`, the margin itself; while it clears the margin less
    half of that, the margin less :data:`CHECK_TOLERANCE` (what the check allows). A bound
    is never asked to come closer to ``measured`` than half that tolerance: nearer, the
    halvings needed grow without end (a wall 20 nm clear spent the 20,000 halvings).
    """
    loose = measured - _tolerance(measured, margin)
    for need, room in ((margin, CHECK_TOLERANCE), (margin - CHECK_TOLERANCE, CHECK_TOLERANCE / 2)):
        if measured >= need + room:
            return max(loose, need)
    return loose


class _Least:
    """The smallest clearance measured so far (m), its instant (s) and pair."""

    def __init__(self, value: float, time: float, pair: int) -> None:
        self.value, self.time, self.pair = value, time, pair

    def note(self, value: float, time: float, pair: int) -> None:
        """Keep a clearance ``value`` (m) at ``time`` (s) of ``pair`` if it is the least yet."""
        if value < self.value:
            self.value, self.time, self.pair = value, time, pair


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
    store = Instants(mesh, motion)
    times = np.linspace(0.0, motion.duration, instants)
    # the first pass's instants of even index: its intervals measure these ends first
    even = {float(t) for t in times[::2]}
    levers = IntervalLevers(store, times)
    least, lower, heap = _first_pass(mesh, (store, levers), times, margin)
    bisections = 0
    exhausted = False
    while heap:
        lb, t0, t1, k, exact, speed = heap[0]
        if lb >= _threshold(least.value, margin):
            break  # this and every later item is within the accuracy of the minimum
        heapq.heappop(heap)
        if not exact:
            value = _measure_ends(store, least, margin, t0 in even, (t0, t1, k, speed))
            heapq.heappush(heap, (value, t0, t1, k, True, speed))
            continue
        if bisections >= MAX_BISECTIONS:
            exhausted = True
            heapq.heappush(heap, (lb, t0, t1, k, exact, speed))
            break
        bisections += 1
        mid = 0.5 * (t0 + t1)
        if mid not in store.joints:  # with the middles of its halves and of other intervals
            store.load(_middles(store, heap, t0, t1))
        least.note(store.distance(mid, k), mid, k)
        rates = store.rates([t0, mid], [mid, t1])
        threshold = _threshold(least.value, margin)
        for (a, b), rate in zip(((t0, mid), (mid, t1)), rates, strict=True):
            speed = float(rate @ mesh.pair_reach[:, k])
            value = 0.5 * (store.distance(a, k) + store.distance(b, k) - speed * (b - a))
            if value < threshold:  # the lever arms' speed (never above the reach's)
                speed = float(rate @ levers.pair(levers.interval(a), k))
                value = 0.5 * (store.distance(a, k) + store.distance(b, k) - speed * (b - a))
            if value < threshold:
                value = max(value, _leaf_value(store, k, a, b, rate))
            heapq.heappush(heap, (value, a, b, k, True, speed))
    if heap:
        lower = min(lower, heap[0][0])
    contained = _contained_at_start(mesh, store)
    if contained is not None:
        least = _Least(min(least.value, -store.distance(0.0, contained)), 0.0, contained)
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


def _measure_ends(
    store: Instants,
    least: _Least,
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
        threshold = _threshold(least.value, margin)
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
    if value < _threshold(least.value, margin):  # the leaf pairs may settle it
        value = max(value, _leaf_value(store, k, t0, t1, store.rates([t0], [t1])[0]))
    return value


#: A heap item: lower bound (m), interval ends (s), pair, whether its ends are exact, speed (m/s).
_Item = tuple[float, float, float, int, bool, float]


def _middles(store: Instants, heap: list[_Item], t0: float, t1: float) -> np.ndarray:
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


def _first_pass(
    mesh: MeshClearance,
    work: tuple[Instants, IntervalLevers],
    times: np.ndarray,
    margin: float,
) -> tuple[_Least, float, list[_Item]]:
    """The uniform first pass at ``times`` (s): sphere bounds, then leaf bounds where open.

    One exact query where the sphere bounds are least. The pairs' speeds from their reach,
    then from their lever arms where the former leave an interval open. Returns the smallest
    measured clearance (m) with its time (s) and pair, the least bound of the intervals
    settled (m; inf if none), and the heap of the others.
    """
    store, levers = work
    store.load(times)
    placements = np.array([store.at(t) for t in times.tolist()])
    bounds = mesh.sphere_bounds(placements)
    k0, p0 = np.unravel_index(int(np.argmin(bounds)), bounds.shape)
    measured, when, pair = store.distance(float(times[k0]), int(p0)), float(times[k0]), int(p0)
    rates = store.rates(times[:-1].tolist(), times[1:].tolist())
    lipschitz = rates @ mesh.pair_reach
    lbs = 0.5 * (bounds[:-1] + bounds[1:] - lipschitz * np.diff(times)[:, None])
    settled = lbs >= _threshold(measured, margin)
    rows, pairs = np.nonzero(~settled)  # the lever arms' speeds (never above the reach's)
    lipschitz[rows, pairs] = levers.first_pass(rates, (rows, pairs), placements)
    lbs = 0.5 * (bounds[:-1] + bounds[1:] - lipschitz * np.diff(times)[:, None])
    settled = lbs >= _threshold(measured, margin)
    _tighten(
        store,
        placements,
        times,
        (bounds, rates, lipschitz),
        lbs,
        settled,
        _threshold(measured, margin),
    )
    settled = lbs >= _threshold(measured, margin)
    lower = float(lbs[settled].min()) if settled.any() else math.inf
    rows, pairs = np.nonzero(~settled)
    heap: list[_Item] = [
        (value, t0, t1, k, False, speed)
        for value, t0, t1, k, speed in zip(
            lbs[rows, pairs].tolist(),
            times[rows].tolist(),
            times[rows + 1].tolist(),
            pairs.tolist(),
            lipschitz[rows, pairs].tolist(),
            strict=True,
        )
    ]
    heapq.heapify(heap)
    return _Least(measured, when, pair), lower, heap


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
    da = store.distance(a, k)
    db = -math.inf if one_end else store.distance(b, k)
    if da <= 0.0 or (db <= 0.0 and not one_end):
        return -math.inf
    travel = (rates @ store.leaf_reach(k)) * width
    start = np.maximum(da, store.gaps(a, k))
    end = np.maximum(store.gaps(b, k), start - travel)
    if not one_end:
        end = np.maximum(end, db)
    return float(np.min(0.5 * (start + end - travel)))


def _tighten(
    store: Instants,
    placements: np.ndarray,
    times: np.ndarray,
    spheres: tuple[np.ndarray, np.ndarray, np.ndarray],
    lbs: np.ndarray,
    settled: np.ndarray,
    threshold: float,
) -> None:
    """Raise the bounds of the intervals not settled by the single spheres, in place.

    For every such (interval, pair), the larger of two lower bounds: the pair's leaf-sphere
    bound (:mod:`.sphere_tree`) at both ends where it beats the single spheres', with the
    whole bodies' speed bound; and the least over the pair's leaf pairs of their own bounds at
    both ends with their own speed bounds, the latter only for the items the former leaves
    below ``threshold`` (m). Both hold for the distance, so the interval bound stays one.
    ``placements``: (K, G, 4, 4) the body poses at ``times``; ``spheres``: the single spheres'
    bounds (K, P) (m), the joint-rate bounds per interval (K - 1, N) (rad/s or m/s) and the
    pairs' speed bounds per interval (K - 1, P) (m/s).
    """
    mesh, (bounds, rates, lipschitz) = store.mesh, spheres
    rows, pairs = np.nonzero(~settled)
    if len(rows) == 0:
        return
    leaves, count = mesh.leaves, len(mesh.pairs)
    # the (instant, pair) cells at the items' ends, each with its leaf pairs' gaps, once
    codes = np.unique(np.concatenate([rows * count + pairs, (rows + 1) * count + pairs]))
    cells, cell_pairs = np.divmod(codes, count)
    runs = leaves.count[cell_pairs]
    starts = np.cumsum(runs) - runs
    offsets = np.arange(int(runs.sum())) - np.repeat(starts, runs)
    gaps = leaves.gaps_at(
        leaves.centres_at(placements),
        placements,
        np.repeat(cells, runs),
        np.repeat(leaves.start[cell_pairs], runs) + offsets,
    )
    store.keep_gaps(times, codes, starts, gaps)
    tight = bounds.copy()
    tight[cells, cell_pairs] = np.maximum(
        bounds[cells, cell_pairs], np.minimum.reduceat(gaps, starts)
    )
    widths = times[rows + 1] - times[rows]
    whole = 0.5 * (tight[rows, pairs] + tight[rows + 1, pairs] - lipschitz[rows, pairs] * widths)
    lbs[rows, pairs] = whole
    # the leaf pairs' own bounds, for the items still open: one run of leaf pairs per item
    still = whole < threshold
    rows, pairs, widths, whole = rows[still], pairs[still], widths[still], whole[still]
    if len(rows) == 0:
        return
    first = starts[np.searchsorted(codes, rows * count + pairs)]
    second = starts[np.searchsorted(codes, (rows + 1) * count + pairs)]
    runs = leaves.count[pairs]
    item = np.repeat(np.arange(len(rows)), runs)
    offsets = np.arange(int(runs.sum())) - np.repeat(np.cumsum(runs) - runs, runs)
    ends = gaps[first[item] + offsets] + gaps[second[item] + offsets]
    leaf_rows = leaves.start[pairs][item] + offsets
    speed = np.einsum(
        "rn,rn->r",
        np.take(rates, rows[item], axis=0),
        np.take(leaves.row_reach_t, leaf_rows, axis=0),
    )
    own = np.minimum.reduceat(0.5 * (ends - speed * widths[item]), np.cumsum(runs) - runs)
    lbs[rows, pairs] = np.maximum(whole, own)


def _contained_at_start(mesh: MeshClearance, store: Instants) -> int | None:
    """A pair one of whose bodies starts inside the other's closed mesh, if any.

    Inside by the winding number, and clear of the mesh's surface (positive distance: coal
    measures a mesh's triangles, not its inside). The winding number first: the exact query
    only for a pair found inside.
    """
    placements = store.at(0.0)
    near = np.flatnonzero(mesh.sphere_bounds(placements) < 0.0)
    for k in near:
        if mesh.contained(placements, int(k)) and store.distance(0.0, int(k)) > 0.0:
            return int(k)
    return None
