"""Exact distance queries of a collision model's checked pairs, one configuration at a time.

The machinery under :class:`~freefloat.robot.collision.CollisionModel`: place the shapes at a
joint vector (Pinocchio), measure the pairs that can matter (coal, through Pinocchio's
``computeDistance``), check every value against the pair's bounding spheres and ask an
impossible one again at looser tolerances (:func:`checked_distance`), keep each pair's last
bounds per slot (:class:`~freefloat.robot.motion_bound.PairBounds`) and read gradients from the
witness points (:mod:`freefloat.robot.witness_gradient`). Distances are in the spacecraft's
frame with the spacecraft at the identity (m).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from .distance_query import (
    GJK_TOLERANCE,
    RETRY_TOLERANCES,
    Closest,
    checked_distance,
    coal_placement,
    configure,
    possible_distances,
)
from .fixed_boxes import FixedBoxes
from .model import Robot
from .motion_bound import PairBounds, motion_weights
from .sphere_distance import SphereWitness, closed_form_first, sphere_distance
from .sphere_kinematics import SphereKinematics
from .witness_gradient import WitnessBatch, carriers

__all__ = ["PairQueries"]


@dataclass(frozen=True)
class _Measured:
    """What :meth:`CollisionModel.closest_many` measured in one batch.

    Attributes:
        values: (B, P) distances (m; inf where not measured).
        measured: (B, P) which pairs were measured.
        retried: the (row, pair) values asked again at looser tolerances.
        witnesses: each row's smallest pair's witnesses (None without gradients).
    """

    values: np.ndarray
    measured: np.ndarray
    retried: list[tuple[int, int]]
    witnesses: WitnessBatch | None


class PairQueries:
    """Exact, checked distance queries of the checked pairs of a geometry model.

    Args:
        robot: the robot.
        geometry: Pinocchio geometry model (convex shapes; body = parent joint).
        pairs: the checked pairs, as indices into ``geometry.geometryObjects``.
        names: ``"a / b"`` per pair, for messages.
    """

    def __init__(
        self,
        robot: Robot,
        geometry: pin.GeometryModel,
        pairs: list[tuple[int, int]],
        names: list[str],
    ) -> None:
        self.robot, self.geometry, self.pairs, self.names = robot, geometry, pairs, names
        self._data = robot.model.createData()
        self._geometry_data = pin.GeometryData(geometry)
        requests = self._geometry_data.distanceRequests
        request = configure(coal.DistanceRequest(), GJK_TOLERANCE)
        for k in range(len(requests)):  # coal's own requests: no guess kept from the last query
            requests[k] = request  # (a copy each)
        #: Queries asked again at a looser EPA tolerance since the model was built.
        self.retries = 0
        # Views of Pinocchio's per-pair results (valid: the vector never resizes), and the
        # results of pairs asked again alone in the last call.
        self._pair_results = list(self._geometry_data.distanceResults)
        self._retried: dict[int, coal.DistanceResult | SphereWitness] = {}
        # Bounding spheres (centre in the shape's frame, radius; m): a distance outside what
        # they allow is impossible (see checked_distance).
        centres, radii = [], []
        for obj in geometry.geometryObjects:
            obj.geometry.computeLocalAABB()
            centres.append(np.asarray(obj.geometry.aabb_center, dtype=float))
            radii.append(float(obj.geometry.aabb_radius))
        self._centres, self._radii = np.array(centres), np.array(radii)
        self._shapes = [obj.geometry for obj in geometry.geometryObjects]
        # Pairs measured in closed form (a sphere and a cylinder), their last query's results.
        shapes = self._shapes
        self._closed = {
            k for k, (a, b) in enumerate(pairs) if closed_form_first(shapes[a], shapes[b])
        }
        self._closed_results: dict[int, SphereWitness] = {}
        # (G, N) per shape, which of the robot's joints carry it (1.0 or 0.0 per joint; all
        # zeros for a shape fixed to the spacecraft).
        self._carried = np.array(
            [carriers(robot, int(obj.parentJoint)) for obj in geometry.geometryObjects]
        ).reshape(-1, robot.n)
        self._pair_array = np.array(pairs, dtype=int).reshape(-1, 2)
        self._reach = self._radii[self._pair_array[:, 0]] + self._radii[self._pair_array[:, 1]]
        self._kinematics = SphereKinematics(robot, geometry, self._centres)
        self._boxes = FixedBoxes(robot, geometry, self._pair_array, self._radii)
        self._neutral = pin.neutral(robot.model)  # joint values go into a copy (no continuous)
        plain = all(j.kind != "continuous" for j in robot.joints)
        self._slots = np.array([j.idx_q for j in robot.joints]) if plain else None
        self._columns = np.array([j.idx_v for j in robot.joints])
        # Each pair's last bounds of its distance per slot: see _may_be_closest.
        self._weights = motion_weights(robot, geometry, pairs, self._centres, self._radii)
        self._bounds = None if self._weights is None else PairBounds(self._weights)

    @contextmanager
    def own_bounds(self) -> Iterator[None]:
        """Queries within bound pairs from each other only, not from earlier queries.

        Which pairs a query measures, and the bounds it reports for the others
        (:attr:`Closest.lower`), then depend on the queries within alone: a check built on
        those bounds gives the same answer whatever was asked before.
        """
        kept = self._bounds
        self._bounds = None if self._weights is None else PairBounds(self._weights)
        try:
            yield
        finally:
            self._bounds = kept

    @property
    def weights(self) -> np.ndarray | None:
        """(P, N) how fast each pair's distance can change per joint (m per rad), or None.

        See :func:`~freefloat.robot.motion_bound.motion_weights` (None: no bound).
        """
        return self._weights

    @property
    def n_pairs(self) -> int:
        """Number of checked pairs."""
        return len(self.pairs)

    def _measure_rows(
        self,
        joints: np.ndarray,
        candidates: np.ndarray,
        low: np.ndarray,
        gaps: np.ndarray,
        gradients: bool,
    ) -> _Measured:
        """Each row's smallest distance, measuring its ``candidates`` (B, P) as needed.

        A row's candidates are measured in the order of their lower bounds (``low``, m), until
        the next bound exceeds the smallest distance measured so far: the pairs left cannot be
        the smallest, nor tie with it. Each value is checked against its bounding spheres
        (``gaps``, m) as :meth:`_measure` checks it; a row with an impossible value is placed
        again and all its candidates asked again, the impossible ones alone. With
        ``gradients``, each row's smallest pair's witnesses are kept.
        """
        count = len(joints)
        compute, geometry, gdata = pin.computeDistance, self.geometry, self._geometry_data
        values = np.full(candidates.shape, math.inf)
        measured = np.zeros(candidates.shape, dtype=bool)
        rows, columns = np.nonzero(candidates)
        order = np.lexsort((low[rows, columns], rows))  # by row, then by lower bound
        rows, columns = rows[order], columns[order]
        starts = np.searchsorted(rows, np.arange(count + 1)).tolist()
        bounds = low[rows, columns].tolist()
        columns_list = columns.tolist()
        witnesses = WitnessBatch(count, self.robot.n) if gradients else None
        jacobian, closed, exact = self._data.J, self._closed, self._closed_form
        for i in range(count):
            self._place(joints[i], jacobians=gradients)
            best, best_k = math.inf, -1
            for j in range(starts[i], starts[i + 1]):
                k = columns_list[j]
                if bounds[j] > best + 1e-9:
                    break
                value = exact(k) if k in closed else compute(geometry, gdata, k).min_distance
                values[i, k], measured[i, k] = value, True
                if value < best or (value == best and k < best_k):
                    best, best_k = value, k
            if witnesses is not None and best_k >= 0:
                results = self._closed_results if best_k in closed else self._pair_results
                witnesses.take(i, results[best_k], jacobian[:, self._columns])
        sane = possible_distances(values, gaps, self._reach)
        retried: list[tuple[int, int]] = []
        for i in np.flatnonzero(np.any(measured & ~sane, axis=1)).tolist():
            pairs = np.flatnonzero(candidates[i])
            self._place(joints[i], jacobians=gradients)
            values[i, pairs] = self._measure(pairs, gaps[i, pairs])
            measured[i, pairs] = True
            retried += [(i, k) for k in self._retried]
            if witnesses is not None:
                best = int(pairs[np.argmin(values[i, pairs])])
                witnesses.take(i, self._result(best), jacobian[:, self._columns])
        return _Measured(values, measured, retried, witnesses)

    def _closest_each(
        self,
        joints: np.ndarray,
        at: Sequence[float | None],
        gradients: bool,
        lower: np.ndarray,
        among: np.ndarray | None,
    ) -> Closest:
        """:meth:`closest_many` one row at a time (a small batch: spheres placed per row)."""
        count = len(joints)
        values, pairs = np.full(count, math.inf), np.full(count, -1)
        grads = np.zeros((count, self.robot.n)) if gradients else None
        if not len(self.pairs):
            return Closest(values, pairs, grads, lower)
        for i in range(count):
            found = self._bulk(joints[i], True, at[i], lower[i], among)
            k = int(np.argmin(found))
            values[i], pairs[i] = found[k], k
            if grads is not None:
                pin.computeJointJacobians(self.robot.model, self._data)  # at _bulk's pose
                grads[i] = self._gradient(k)
        return Closest(values, pairs, grads, lower)

    def _bulk(
        self,
        joints: np.ndarray,
        nearest: bool = False,
        slot: float | None = None,
        lower: np.ndarray | None = None,
        among: np.ndarray | None = None,
    ) -> np.ndarray:
        """Signed distances (m) of the pairs, each by Pinocchio's ``computeDistance``.

        With ``nearest``, only the pairs (``among`` them) that can be the closest are measured
        (the others are ``inf``; see :meth:`_may_be_closest`), each checked by
        :meth:`_measure`. ``lower``: a (P,) array that receives a lower bound of every pair's
        distance (m): the measured value, or for a pair not measured, its bound.
        """
        joints = np.asarray(joints, dtype=float)
        self._place(joints)
        if nearest and len(self.pairs):
            measured = self._may_be_closest(joints, slot, lower, among)
        else:
            measured = np.arange(len(self.pairs))
        found = self._measure(measured, self._spheres(measured))
        self._remember(slot, joints, measured, found, lower)
        values = np.full(len(self.pairs), math.inf)
        values[measured] = found
        return values

    def _place(self, joints: np.ndarray, jacobians: bool = False) -> None:
        """Place the shapes at the joint values (and with ``jacobians``, the joint Jacobians)."""
        model, data, q = self.robot.model, self._data, self._configuration(joints)
        if jacobians:  # forward kinematics too
            pin.computeJointJacobians(model, data, q)
        else:
            pin.forwardKinematics(model, data, q)
        pin.updateGeometryPlacements(model, data, self.geometry, self._geometry_data)

    def _measure(self, measured: np.ndarray, gap: np.ndarray) -> np.ndarray:
        """Distances (m) of the ``measured`` pairs at the placed shapes, each one checked.

        Each value is checked against its bounding spheres (``gap``: their centres' distances,
        m) as :func:`checked_distance` does, and an impossible one is asked again alone at
        looser tolerances (counted in :attr:`retries`). Every query starts from coal's default
        guesses (the requests keep none from the last query), so a distance does not depend,
        to the last bit, on what was asked before.
        """
        compute, geometry, gdata = pin.computeDistance, self.geometry, self._geometry_data
        reach, closed, exact = self._reach[measured], self._closed, self._closed_form
        listed = measured.tolist()
        found = np.array(
            [exact(k) if k in closed else compute(geometry, gdata, k).min_distance for k in listed]
        )
        possible = possible_distances(found, gap, reach)
        self._retried = {}
        if not possible.all():
            for i in np.flatnonzero(~possible).tolist():
                found[i] = self._retry(int(measured[i]), float(gap[i]), float(reach[i]))
        return found

    def _remember(
        self,
        slot: float | None,
        joints: np.ndarray,
        measured: np.ndarray,
        found: np.ndarray,
        lower: np.ndarray | None,
    ) -> None:
        """Keep measured distances (m) as bounds at ``slot``; put them in ``lower``.

        A retried value is no reference (forgotten); in ``lower`` it allows for its looser
        tolerance.
        """
        if self._bounds is not None:
            known = found
            if self._retried:
                known = np.where(np.isin(measured, list(self._retried)), math.nan, found)
            self._bounds.record(slot, measured, joints, known, known)
        if lower is not None:
            lower[measured] = found
            if self._retried:  # asked again at a looser EPA tolerance: a bound that allows it
                lower[list(self._retried)] -= RETRY_TOLERANCES[-1]

    def _result(self, k: int) -> coal.DistanceResult | SphereWitness:
        """Pair ``k``'s result of the last query (the retried one when it was asked again)."""
        if k in self._closed:
            return self._closed_results[k]
        return self._retried.get(k, self._pair_results[k])

    def _closed_form(self, k: int) -> float:
        """Pair ``k``'s distance (m) in closed form at the placed shapes, its result kept."""
        a, b = self.pairs[k]
        placements = self._geometry_data.oMg
        found = sphere_distance(self._shapes[a], placements[a], self._shapes[b], placements[b])
        assert found is not None  # a pair of closed_form_first
        self._closed_results[k] = found
        return found.min_distance

    def _retry(self, k: int, gap: float, reach: float) -> float:
        """Pair ``k``'s distance (m) asked again alone at looser tolerances.

        For a value impossible by its bounding spheres (``gap +- reach``, m):
        :func:`checked_distance`, counted in :attr:`retries`.
        """
        a, b = self.pairs[k]
        placements = self._geometry_data.oMg
        shapes = (self._shapes[a], coal_placement(placements[a]), self._shapes[b])
        spheres = (gap - reach, gap + reach)
        answer = checked_distance(*shapes, coal_placement(placements[b]), spheres, self.names[k])
        self.retries += max(1, answer.retries)
        self._retried[k] = answer.result
        return answer.value

    def _configuration(self, joints: np.ndarray) -> np.ndarray:
        """Pinocchio's configuration at the joint values, spacecraft at the identity."""
        if self._slots is None:
            return self.robot.configuration(joints)
        q = self._neutral.copy()
        q[self._slots] = joints
        return q

    def _spheres(self, pairs: np.ndarray) -> np.ndarray:
        """Per pair (indices), the distance of its bounding spheres' centres (m).

        At the placements of the last ``updateGeometryPlacements``; the distance of the
        shapes is within this +- the pairs' :attr:`_reach`.
        """
        placements = self._geometry_data.oMg
        involved = np.unique(self._pair_array[pairs])
        centres = np.zeros((len(self._centres), 3))
        for g in involved.tolist():
            centres[g] = placements[g].act(self._centres[g])
        first, second = self._pair_array[pairs, 0], self._pair_array[pairs, 1]
        return np.linalg.norm(centres[first] - centres[second], axis=1)

    def _may_be_closest(
        self,
        joints: np.ndarray,
        slot: float | None,
        out: np.ndarray | None = None,
        among: np.ndarray | None = None,
    ) -> np.ndarray:
        """Indices of the pairs that may have the smallest distance at ``joints``.

        Each pair is bounded from its last bounds at ``slot`` (:class:`PairBounds`: its
        measured distance; or, for a pair never measured there, its bounding spheres, which are
        then kept); with no motion bound (a prismatic joint), by its bounding spheres. A pair
        that cannot be the closest is not measured, so the smallest distance and its pair are
        the same bits as with every pair measured. ``out`` receives every pair's lower bound (m).
        ``among``: the pairs the smallest is taken over (default all).
        """
        if self._bounds is None:
            gap = self._spheres(np.arange(len(self.pairs)))
            lower, upper = gap - self._reach, gap + self._reach
        else:
            unknown = self._bounds.unknown(slot)
            if len(unknown):
                gap, reach = self._spheres(unknown), self._reach[unknown]
                self._bounds.record(slot, unknown, joints, gap - reach, gap + reach)
            lower, upper = self._bounds.widened(slot, joints)
        if out is not None:
            out[:] = lower
        chosen = np.ones(len(self.pairs), dtype=bool) if among is None else among
        if not np.isfinite(joints).all():  # no bound holds: every pair is asked (and refused)
            return np.flatnonzero(chosen)
        return np.flatnonzero((lower <= float(upper[chosen].min()) + 1e-9) & chosen)

    def _gradient(self, k: int) -> np.ndarray:
        """d(distance of pair k)/d(joints), after distances and joint Jacobians are computed."""
        batch = WitnessBatch(1, self.robot.n)
        batch.take(0, self._result(k), self._data.J[:, self._columns])
        return batch.gradients(self._carried, self._pair_array[k : k + 1])[0]
