"""The clearance certificate's first, uniform pass (:mod:`freefloat.verify.certificate`).

Bounds of every pair on every interval of a uniform grid from the bounding spheres and the
pairs' speed bounds, tightened where they leave an interval open by the leaf spheres' gaps
and the leaf pairs' own speeds, before any exact query but one.
"""

from __future__ import annotations

import heapq
import math

import numpy as np

from .clearance import MeshClearance
from .instants import Instants
from .interval_levers import IntervalLevers
from .settling import SPHERES, Item, Least, settled_above

__all__ = ["first_pass"]


def first_pass(
    mesh: MeshClearance,
    work: tuple[Instants, IntervalLevers],
    times: np.ndarray,
    margin: float,
) -> tuple[Least, float, list[Item]]:
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
    settled = lbs >= settled_above(measured, margin)
    rows, pairs = np.nonzero(~settled)  # the lever arms' speeds (never above the reach's)
    lipschitz[rows, pairs] = levers.first_pass(rates, (rows, pairs), placements)
    lbs = 0.5 * (bounds[:-1] + bounds[1:] - lipschitz * np.diff(times)[:, None])
    settled = lbs >= settled_above(measured, margin)
    _tighten(
        store,
        placements,
        times,
        (bounds, rates, lipschitz),
        lbs,
        settled,
        settled_above(measured, margin),
    )
    settled = lbs >= settled_above(measured, margin)
    lower = float(lbs[settled].min()) if settled.any() else math.inf
    rows, pairs = np.nonzero(~settled)
    heap: list[Item] = [
        (value, t0, t1, k, SPHERES, speed)
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
    return Least(measured, when, pair), lower, heap


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
