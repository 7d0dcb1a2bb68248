"""How far a pair's signed distance can move when the joints move: a bound that spares queries.

The solvers ask for the smallest distance over every checked pair at many configurations
along a path. A pair measured at one configuration bounds its distance at any other: the
shapes are rigid, so their signed distance changes no more than their points move relative
to each other, and :func:`motion_weights` bounds that per joint (m per rad). A pair whose
lower bound exceeds another pair's upper bound cannot be the closest, and need not be measured
(:class:`~freefloat.robot.collision.CollisionModel`).
"""

from __future__ import annotations

import bisect
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from .model import Robot

__all__ = ["BOUND_SLACK", "PairBounds", "alone", "motion_weights", "sphere_reach"]

#: Allowance (m) for the error of a measured distance, in the bound of a pair not measured
#: (a thousand times coal's GJK and EPA tolerance).
BOUND_SLACK = 1e-6


def sphere_reach(
    robot: Robot, geometry: pin.GeometryModel, centres: np.ndarray, radii: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """How far each object's bounding sphere reaches from each joint (G x N, m per rad).

    ``reach[g, k]``: the distance from joint k's origin (on its axis) to the farthest point of
    object g's bounding sphere (``centres`` in the objects' frames, ``radii``; m), at most the
    lengths of the joint offsets down the chain plus the sphere's centre offset and radius
    (rotations keep lengths); ``carried[g, k]``: whether joint k moves object g (reach 0 when
    it does not). None with a prismatic joint (the lengths change with it).
    """
    if any(not joint.angular for joint in robot.joints):
        return None
    model = robot.model
    column = {joint.index: k for k, joint in enumerate(robot.joints)}
    objects = list(geometry.geometryObjects)
    parents = [int(j) for j in model.parents]
    offsets = {j: float(np.linalg.norm(model.jointPlacements[j].translation)) for j in column}
    reach = np.zeros((len(objects), robot.n))
    carried = np.zeros((len(objects), robot.n), dtype=bool)
    for g, obj in enumerate(objects):
        length = float(np.linalg.norm(obj.placement.act(centres[g]))) + float(radii[g])
        joint = int(obj.parentJoint)
        while joint in column:  # arm joints; the spacecraft (free flyer) and the world end it
            reach[g, column[joint]], carried[g, column[joint]] = length, True
            length += offsets[joint]
            joint = parents[joint]
    return reach, carried


def motion_weights(
    robot: Robot,
    geometry: pin.GeometryModel,
    pairs: Sequence[tuple[int, int]],
    centres: np.ndarray,
    radii: np.ndarray,
) -> np.ndarray | None:
    """How fast each pair's signed distance can change with each joint (P x N, m per rad).

    A joint that moves both bodies of a pair (an ancestor of both) moves them as one rigid
    body and leaves their distance unchanged; a revolute joint that moves one of them moves
    each of its points at most ``rho`` per rad, ``rho`` the distance from the joint's origin
    (on its axis) to the farthest point of the body's bounding sphere (:func:`sphere_reach`).
    A signed distance changes no more than its two shapes' points move, so
    ``|d(q) - d(q')| <= weights[p] @ |q - q'|`` along the straight line between any two
    joint vectors. With a prismatic joint the lengths change with it: None (no bound).
    """
    found = sphere_reach(robot, geometry, centres, radii)
    if found is None:
        return None
    reach, carried = found
    first, second = alone(carried, pairs)
    pair_array = np.array(pairs, dtype=int).reshape(-1, 2)
    return np.where(first, reach[pair_array[:, 0]], 0.0) + np.where(
        second, reach[pair_array[:, 1]], 0.0
    )


def alone(
    carried: np.ndarray, pairs: Sequence[tuple[int, int]] | np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(P, N) each pair's joints that move its first object alone, and its second alone.

    ``carried``: (G, N) which joints move each object (:func:`sphere_reach`). A joint that
    moves both moves them as one rigid body: their distance does not change with it.
    """
    pair_array = np.array(pairs, dtype=int).reshape(-1, 2)
    a, b = carried[pair_array[:, 0]], carried[pair_array[:, 1]]
    return a & ~b, b & ~a


class PairBounds:
    """Each pair's last bounds of its distance (m) and the joints then, per slot.

    A slot names a place where queries come back (a normalised instant of a path, say): a
    pair's bound from its last measurement *at that slot* is tight when the joints there
    moved little since (a solver's iterates), where the last query elsewhere on the path may
    be far. A new slot starts from the bounds of the nearest slot kept (the last used, for
    ``None``). Bounds are valid whatever their slot, so the slot changes which pairs are
    measured, never a distance. At most :data:`SLOTS` slots are kept.

    Args:
        weights: (P, N) :func:`motion_weights` of the pairs (m per rad).
    """

    #: Slots kept before all are forgotten.
    SLOTS = 4096
    #: Rows the arrays start with (twice as many each time they fill up).
    ROWS = 16

    def __init__(self, weights: np.ndarray) -> None:
        self.weights = weights
        pairs, joints = weights.shape
        # Row r of the arrays holds a slot's (joints, lower, upper); rows are used in order.
        self._rows: dict[float | None, int] = {}
        self._joints = np.zeros((self.ROWS, pairs, joints))
        self._lower = np.full((self.ROWS, pairs), np.nan)
        self._upper = np.full((self.ROWS, pairs), np.nan)
        self._recent: float | None = None
        self._keys: list[float] = []  # the numeric slots, sorted

    def _row(self, slot: float | None) -> int:
        """The slot's row of the arrays, a new one (NaN bounds, or the nearest slot's) if new."""
        found = self._rows.get(slot)
        if found is None:
            if len(self._rows) >= self.SLOTS:
                self._rows.clear()
                self._keys.clear()
            near = self._rows.get(self._nearest(slot))
            found = len(self._rows)
            self._room(found + 1)
            if near is not None:  # a new slot starts from the nearest one, or the last used
                self._joints[found] = self._joints[near]
                self._lower[found], self._upper[found] = self._lower[near], self._upper[near]
            else:
                self._lower[found], self._upper[found] = np.nan, np.nan
            self._rows[slot] = found
            if slot is not None:
                bisect.insort(self._keys, slot)
        self._recent = slot
        return found

    def _room(self, rows: int) -> None:
        """Room for ``rows`` rows in the arrays (twice the rows while full)."""
        size = len(self._lower)
        if rows <= size:
            return
        while size < rows:
            size *= 2
        used = len(self._rows)
        joints = np.zeros((size, *self._joints.shape[1:]))
        joints[:used] = self._joints[:used]
        lower = np.full((size, self._lower.shape[1]), np.nan)
        upper = lower.copy()
        lower[:used], upper[:used] = self._lower[:used], self._upper[:used]
        self._joints, self._lower, self._upper = joints, lower, upper

    def _rows_of(self, slots: Sequence[float | None]) -> list[int]:
        """:meth:`_row` of each slot in turn (one lookup each when every slot is kept).

        New slots are made in one pass where that gives what one at a time gives
        (:meth:`_made_at_once`).
        """
        known = list(map(self._rows.get, slots))
        if None in known and not self._made_at_once(slots, known):
            return [self._row(slot) for slot in slots]  # one after the other, as asked
        if slots:
            self._recent = slots[-1]
        return list(map(self._rows.__getitem__, slots))

    def _made_at_once(self, slots: Sequence[float | None], known: list[int | None]) -> bool:
        """Make the new slots of ``slots`` at once, when that gives what :meth:`_row` would.

        Made one after the other, a new slot starts from the nearest slot kept, which may be
        one made just before it in the same call. When no slot is kept (every new slot starts
        without bounds), or when each new numeric slot lies strictly nearer a slot kept before
        the call than any other new slot, each starts from that slot either way: they are
        made in one pass. False (nothing made) otherwise.
        """
        made = list(dict.fromkeys(s for s, row in zip(slots, known, strict=True) if row is None))
        if None in made or len(self._rows) + len(made) >= self.SLOTS:
            return False
        new = [float(s) for s in made if s is not None]
        if self._rows and not self._keys:  # only the slot None kept: each from the last used
            return False
        at = np.array(new, dtype=float)
        near = np.full(len(new), -1)
        if self._rows:
            keys = np.array(self._keys)
            k = np.searchsorted(keys, at)  # bisect_left, as _nearest
            below, above = keys[np.maximum(k - 1, 0)], keys[np.minimum(k, len(keys) - 1)]
            gap_below, gap_above = np.abs(at - below), np.abs(above - at)
            chosen = np.where(gap_below <= gap_above, below, above)  # a tie: the lower
            gap = np.minimum(gap_below, gap_above)
            if len(new) > 1:
                ordered = np.sort(at)
                spacing = np.diff(ordered)
                apart = np.minimum(np.append(spacing, np.inf), np.insert(spacing, 0, np.inf))
                if np.any(apart[np.searchsorted(ordered, at)] <= gap):
                    return False
            near = np.array([self._rows[key] for key in chosen.tolist()])
        first = len(self._rows)
        self._room(first + len(new))
        rows = np.arange(first, first + len(new))
        copied = near >= 0
        self._joints[rows[copied]] = self._joints[near[copied]]
        self._lower[rows], self._upper[rows] = np.nan, np.nan
        self._lower[rows[copied]] = self._lower[near[copied]]
        self._upper[rows[copied]] = self._upper[near[copied]]
        self._rows.update(zip(new, rows.tolist(), strict=True))
        self._keys = sorted(self._keys + new)
        return True

    def _nearest(self, slot: float | None) -> float | None:
        """The kept slot nearest ``slot`` (the last used for None, or when none is kept)."""
        if slot is None or not self._keys:
            return self._recent
        k = bisect.bisect_left(self._keys, slot)
        around = self._keys[max(k - 1, 0) : k + 1]
        return min(around, key=lambda key: abs(key - slot))

    def unknown(self, slot: float | None) -> np.ndarray:
        """Indices of the pairs with no bounds at the slot."""
        row = self._row(slot)  # first: a new row may grow the arrays
        return np.flatnonzero(np.isnan(self._lower[row]))

    def record(
        self,
        slot: float | None,
        pairs: np.ndarray,
        joints: np.ndarray,
        lower: np.ndarray,
        upper: np.ndarray,
    ) -> None:
        """Bounds (m) of ``pairs`` at ``joints`` (rad or m); NaN to forget them."""
        row = self._row(slot)
        self._joints[row, pairs] = joints
        self._lower[row, pairs], self._upper[row, pairs] = lower, upper

    def widened(self, slot: float | None, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds (m) of every pair's distance at ``joints``.

        Every pair must have bounds at the slot. Each is widened by how far its two bodies can
        have moved relative to each other since (weights times the joint change, m) and
        :data:`BOUND_SLACK`.
        """
        row = self._row(slot)
        moved = np.einsum("pn,pn->p", self.weights, np.abs(joints - self._joints[row]))
        moved += BOUND_SLACK
        return self._lower[row] - moved, self._upper[row] + moved

    def widened_many(
        self, slots: Sequence[float | None], joints: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`widened` at many slots at once: (B, P) lower and upper bounds (m).

        ``joints``: (B, N), one row per slot (rad or m). A pair with no bounds at its slot
        gets NaN (the caller bounds it otherwise). Rows share no bounds with each other: each
        is widened from its slot as it stood before the call (a new slot from the nearest
        one kept then, or created by an earlier row of the call).
        """
        rows = np.array(self._rows_of(slots), dtype=int)
        change = self._joints[rows]  # (B, P, N): each pair's joints when last bounded
        np.subtract(joints[:, None, :], change, out=change)
        np.abs(change, out=change)
        # per pair, its weights times the joints' change: one product per pair, all rows
        moved = np.matmul(change.transpose(1, 0, 2), self.weights[:, :, None])[..., 0].T
        moved += BOUND_SLACK
        return self._lower[rows] - moved, self._upper[rows] + moved

    def record_rows(
        self,
        slots: Sequence[float | None],
        pairs: np.ndarray,
        joints: np.ndarray,
        lower: np.ndarray,
        upper: np.ndarray,
    ) -> None:
        """:meth:`record` at many slots, in order: (B, P) ``pairs`` mask, bounds (m).

        ``joints``: (B, N), one row per slot (rad or m); NaN bounds forget a pair.
        """
        rows = self._rows_of(slots)
        if len(set(rows)) < len(rows):  # a slot twice: one after the other, as asked
            for i, row in enumerate(rows):
                chosen = pairs[i]
                self._joints[row, chosen] = joints[i]
                self._lower[row, chosen] = lower[i, chosen]
                self._upper[row, chosen] = upper[i, chosen]
            return
        at, chosen = np.nonzero(pairs)  # each slot once: written in place, whatever the order
        kept = np.array(rows, dtype=int)[at]
        self._joints[kept, chosen] = joints[at]
        self._lower[kept, chosen] = lower[at, chosen]
        self._upper[kept, chosen] = upper[at, chosen]
