"""Collision model of a free floater: which bodies may touch, and how far apart they are.

This is the solvers' model. Built with Pinocchio's URDF geometry parser and coal (collision
geometry of the URDF, meshes resolved through the robot's package folders; see
:mod:`freefloat.robot.geometry`). Each mesh is replaced by its **true** convex hull (qhull), so
that every distance is a signed distance (negative when two shapes overlap, by GJK/EPA) and
changes smoothly with the joints; a hull contains its mesh, so a clearance on hulls is a
clearance on the meshes. Verification measures the original meshes with a separately built
model (:mod:`freefloat.verify.clearance`).

Only the pairs that can be the closest are measured when only the closest is asked for
(:mod:`freefloat.robot.motion_bound` bounds the others from their last measurement). Every
query is checked (:mod:`freefloat.robot.distance_query`): a non-finite or impossible distance
(coal's EPA can return -DBL_MAX for some penetrating pairs at tight tolerances) is asked again
at looser tolerances (:data:`RETRY_TOLERANCES`) and counted in
:attr:`CollisionModel.retries`; a value still impossible raises
:class:`~freefloat.errors.ModelError`, never reaching a solver.

The base is free-floating, but every collision geometry here is fixed either to the spacecraft
or to an arm link, so distances depend on the joints alone: they are computed with the
spacecraft at the identity pose, in its frame (m); their gradients come from the witness
points (:mod:`freefloat.robot.witness_gradient`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from .distance_query import (
    GJK_TOLERANCE,
    RETRY_TOLERANCES,
    CheckedDistance,
    Closest,
    Distances,
    checked_distance,
    configure,
)
from .geometry import (
    HullInfo,
    add_obstacles,
    bodies_without_geometry,
    checked_pairs,
    hull_volume,
    load_collision_geometry,
    mesh_volume,
    object_triangles,
    true_hull,
)
from .model import Robot
from .motion_bound import PairBounds, motion_weights
from .obstacle import SHAPES, Obstacle
from .sphere_kinematics import SphereKinematics
from .srdf import known_srdf
from .witness_gradient import carriers, witness_gradient

__all__ = [
    "GJK_TOLERANCE",
    "RETRY_TOLERANCES",
    "SHAPES",
    "CheckedDistance",
    "Closest",
    "CollisionModel",
    "Distances",
    "Obstacle",
    "checked_distance",
    "clearance_at",
    "collision_model",
    "known_srdf",
]

#: Rows from which :meth:`CollisionModel.closest_many` places a batch's spheres at once.
BATCH = 8


class CollisionModel:
    """The checked pairs of a robot's collision geometry and their signed distances.

    Attributes:
        robot: the robot.
        geometry: Pinocchio geometry model (convex hulls; body = parent joint).
        pairs: the checked pairs, as indices into ``geometry.geometryObjects``.
        names: ``"a / b"`` per pair, for messages.
    """

    def __init__(
        self,
        robot: Robot,
        srdf: str | Path | None = None,
        obstacles: Sequence[Obstacle] = (),
    ) -> None:
        self.robot = robot
        self.obstacles = tuple(obstacles)
        self.srdf = None if srdf is None else Path(srdf).expanduser().resolve()
        geometry = load_collision_geometry(robot)
        #: Movable bodies with no collision geometry (their clearance cannot be checked).
        self.uncovered = bodies_without_geometry(robot, geometry)
        self._meshes: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        for index, obj in enumerate(geometry.geometryObjects):
            if isinstance(obj.geometry, coal.BVHModelBase):
                self._meshes[index] = object_triangles(obj)
                obj.geometry = true_hull(obj)
        add_obstacles(robot, geometry, self.obstacles)
        self.pairs = checked_pairs(robot, geometry, srdf)
        objects = list(geometry.geometryObjects)
        self.geometry = geometry
        self.names = [f"{objects[a].name} / {objects[b].name}" for a, b in self.pairs]
        self._data = robot.model.createData()
        self._geometry_data = pin.GeometryData(geometry)
        requests = self._geometry_data.distanceRequests
        for k in range(len(requests)):  # coal's own requests: no guess kept from the last query
            requests[k] = configure(coal.DistanceRequest(), GJK_TOLERANCE)
        #: Queries asked again at a looser EPA tolerance since the model was built.
        self.retries = 0
        # Views of Pinocchio's per-pair results (valid: the vector never resizes), and the
        # results of pairs asked again alone in the last call.
        self._pair_results = list(self._geometry_data.distanceResults)
        self._retried: dict[int, coal.DistanceResult] = {}
        # Bounding spheres (centre in the shape's frame, radius; m): a distance outside what
        # they allow is impossible (see checked_distance).
        centres, radii = [], []
        for obj in geometry.geometryObjects:
            obj.geometry.computeLocalAABB()
            centres.append(np.asarray(obj.geometry.aabb_center, dtype=float))
            radii.append(float(obj.geometry.aabb_radius))
        self._centres, self._radii = np.array(centres), np.array(radii)
        self._shapes = [obj.geometry for obj in geometry.geometryObjects]
        # Per shape, which of the robot's joints carry it (1.0 or 0.0 per joint), or None
        # for a shape fixed to the spacecraft.
        self._carried = [carriers(robot, int(obj.parentJoint)) for obj in geometry.geometryObjects]
        self._pair_array = np.array(self.pairs, dtype=int).reshape(-1, 2)
        self._reach = self._radii[self._pair_array[:, 0]] + self._radii[self._pair_array[:, 1]]
        self._kinematics = SphereKinematics(robot, geometry, self._centres)
        self._neutral = pin.neutral(robot.model)  # joint values go into a copy (no continuous)
        plain = all(j.kind != "continuous" for j in robot.joints)
        self._slots = np.array([j.idx_q for j in robot.joints]) if plain else None
        self._columns = np.array([j.idx_v for j in robot.joints])
        # Each pair's last bounds of its distance per slot: see _may_be_closest.
        self._weights = motion_weights(robot, geometry, self.pairs, self._centres, self._radii)
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

    def distances(self, joints: np.ndarray, gradients: bool = False) -> Distances:
        """Signed distances (m) of every pair at the joint values (rad or m).

        With ``gradients``, also their derivatives with respect to the joints.
        """
        values = self._bulk(joints)
        if not gradients:
            return Distances(values)
        pin.computeJointJacobians(self.robot.model, self._data)  # at _bulk's configuration
        grads = np.stack([self._gradient(k) for k in range(len(self.pairs))])
        return Distances(values, grads)

    def closest_value(self, joints: np.ndarray, slot: float | None = None) -> tuple[float, int]:
        """The smallest signed distance over the pairs (m) and its pair index.

        Exact: only the pairs that can be the closest are measured (:meth:`_may_be_closest`),
        bounded from their last measurement at ``slot`` (a normalised instant of a path, say:
        queries that come back to a slot with nearby joints measure few pairs).
        """
        values = self._bulk(joints, nearest=True, slot=slot)
        k = int(np.argmin(values)) if len(values) else -1
        return (float(values[k]) if k >= 0 else math.inf), k

    def closest(
        self, joints: np.ndarray, slot: float | None = None
    ) -> tuple[float, np.ndarray, int]:
        """The smallest signed distance (m), its gradient over the joints, and its pair index.

        ``slot`` as for :meth:`closest_value`.
        """
        value, k = self.closest_value(joints, slot)
        if k < 0:
            return value, np.zeros(self.robot.n), k
        pin.computeJointJacobians(self.robot.model, self._data)  # at closest_value's pose
        return value, self._gradient(k), k

    def closest_many(
        self, joints: np.ndarray, slots: Sequence[float] | None = None, gradients: bool = False
    ) -> Closest:
        """:meth:`closest_value` (with ``gradients``: :meth:`closest`) at many joint vectors.

        The same values, pairs and gradients as those calls one after the other, in order
        (``slots``: one per row, or None); the bounding spheres of the whole batch are placed
        at once (:class:`~freefloat.robot.sphere_kinematics.SphereKinematics`) when it is
        large enough for that to pay.

        Args:
            joints: (B, N) joint values (rad or m).
            slots: a normalised instant per row (see :meth:`closest_value`), or None.
            gradients: also each smallest distance's gradient over the joints (m per rad or m).

        The result also holds each row's lower bounds of every pair's distance (``lower``).
        """
        joints = np.atleast_2d(np.asarray(joints, dtype=float))
        count = len(joints)
        at = [None] * count if slots is None else [float(s) for s in slots]
        values, pairs = np.full(count, math.inf), np.full(count, -1)
        grads = np.zeros((count, self.robot.n)) if gradients else None
        lower = np.full((count, len(self.pairs)), math.inf)
        if not len(self.pairs):
            return Closest(values, pairs, grads, lower)
        gaps = self._kinematics.gaps(joints, self._pair_array) if count >= BATCH else None
        for i in range(count):
            found = self._bulk(joints[i], True, at[i], None if gaps is None else gaps[i], lower[i])
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
        gaps: np.ndarray | None = None,
        lower: np.ndarray | None = None,
    ) -> np.ndarray:
        """Signed distances (m) of the pairs, each by Pinocchio's ``computeDistance``.

        With ``nearest``, only the pairs that can be the closest are measured (the others are
        ``inf``; see :meth:`_may_be_closest`). Each value is checked against its bounding
        spheres as :func:`checked_distance` does, and an impossible one is asked again alone at
        looser tolerances (counted in :attr:`retries`). Every query starts from coal's default
        guesses (the requests keep none from the last query), so a distance does not depend,
        to the last bit, on what was asked before. ``gaps``: the (P,) distances between the
        pairs' sphere centres at ``joints`` (m), when already known. ``lower``: a (P,) array
        that receives a lower bound of every pair's distance (m): the measured value, or for a
        pair not measured, its bound.
        """
        model, data, gdata = self.robot.model, self._data, self._geometry_data
        joints = np.asarray(joints, dtype=float)
        pin.forwardKinematics(model, data, self._configuration(joints))
        pin.updateGeometryPlacements(model, data, self.geometry, gdata)
        if nearest and len(self.pairs):
            measured = self._may_be_closest(joints, slot, gaps, lower)
        else:
            measured = np.arange(len(self.pairs))
        gap = self._spheres(measured) if gaps is None else gaps[measured]
        reach = self._reach[measured]
        compute, geometry = pin.computeDistance, self.geometry
        found = np.array([compute(geometry, gdata, k).min_distance for k in measured.tolist()])
        with np.errstate(invalid="ignore"):
            possible = (found >= gap - reach - 1e-9) & (found <= gap + reach + 1e-9)
        self._retried = {}
        if not possible.all():
            for i in np.flatnonzero(~(np.isfinite(found) & possible)).tolist():
                found[i] = self._retry(int(measured[i]), float(gap[i]), float(reach[i]))
        if self._bounds is not None:  # a retried value is no reference: forgotten
            known = found
            if self._retried:
                known = np.where(np.isin(measured, list(self._retried)), math.nan, found)
            self._bounds.record(slot, measured, joints, known, known)
        values = np.full(len(self.pairs), math.inf)
        values[measured] = found
        if lower is not None:
            lower[measured] = found
            if self._retried:  # asked again at a looser EPA tolerance: a bound that allows it
                lower[list(self._retried)] -= RETRY_TOLERANCES[-1]
        return values

    def _retry(self, k: int, gap: float, reach: float) -> float:
        """Pair ``k``'s distance (m) asked again alone at looser tolerances.

        For a value impossible by its bounding spheres (``gap +- reach``, m):
        :func:`checked_distance`, counted in :attr:`retries`.
        """
        a, b = self.pairs[k]
        placements = self._geometry_data.oMg
        shapes = (self._shapes[a], _transform(placements[a]), self._shapes[b])
        spheres = (gap - reach, gap + reach)
        answer = checked_distance(*shapes, _transform(placements[b]), spheres, self.names[k])
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
        gaps: np.ndarray | None = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Indices of the pairs that may have the smallest distance at ``joints``.

        Each pair is bounded from its last bounds at ``slot`` (:class:`PairBounds`: its
        measured distance; or, for a pair never measured there, its bounding spheres, which are
        then kept); with no motion bound (a prismatic joint), by its bounding spheres
        (``gaps``: their centres' distances when already known, m). A pair that cannot be the
        closest is not measured, so the smallest distance and its pair are the same bits as
        with every pair measured. ``out`` receives every pair's lower bound (m).
        """
        if self._bounds is None:
            gap = self._spheres(np.arange(len(self.pairs))) if gaps is None else gaps
            lower, upper = gap - self._reach, gap + self._reach
        else:
            unknown = self._bounds.unknown(slot)
            if len(unknown):
                gap = self._spheres(unknown) if gaps is None else gaps[unknown]
                reach = self._reach[unknown]
                self._bounds.record(slot, unknown, joints, gap - reach, gap + reach)
            lower, upper = self._bounds.widened(slot, joints)
            if gaps is not None:  # the spheres bound every pair too: the tighter of both
                lower = np.maximum(lower, gaps - self._reach)
                upper = np.minimum(upper, gaps + self._reach)
        if out is not None:
            out[:] = lower
        return np.flatnonzero(lower <= float(upper.min()) + 1e-9)

    def hulls(self) -> list[HullInfo]:
        """Per mesh, the volume it encloses and that of its hull (m^3), for reports."""
        objects = self.geometry.geometryObjects
        return [
            HullInfo(objects[i].name, mesh_volume(*mesh), hull_volume(objects[i].geometry))
            for i, mesh in self._meshes.items()
        ]

    def _gradient(self, k: int) -> np.ndarray:
        """d(distance of pair k)/d(joints), after distances and joint Jacobians are computed."""
        result = self._retried.get(k, self._pair_results[k])
        a, b = self.pairs[k]
        carried = (self._carried[a], self._carried[b])
        return witness_gradient(result, carried, self._data.J[:, self._columns], self.robot.n)


def _transform(placement: pin.SE3) -> coal.Transform3s:
    """The coal transform of a Pinocchio placement."""
    return coal.Transform3s(placement.rotation, placement.translation)


def collision_model(
    robot: Robot, srdf: str | Path | None = None, obstacles: Sequence[Obstacle] = ()
) -> CollisionModel:
    """The collision model of ``robot`` (see :class:`CollisionModel`)."""
    return CollisionModel(robot, srdf, obstacles)


def clearance_at(model: CollisionModel, joints: Sequence[float] | np.ndarray) -> tuple[float, str]:
    """Smallest clearance (m) at one configuration and the pair that has it."""
    values = model.distances(np.asarray(joints, dtype=float)).values
    k = int(np.argmin(values))
    return float(values[k]), model.names[k]
