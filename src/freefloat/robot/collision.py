"""Collision model of a free floater: which bodies may touch, and how far apart they are.

This is the solvers' model. Built with Pinocchio's URDF geometry parser and coal (collision
geometry of the URDF, meshes resolved through the robot's package folders; see
:mod:`freefloat.robot.geometry`). Each mesh is replaced by its **true** convex hull (qhull), so
that every distance is a signed distance (negative when two shapes overlap, by GJK/EPA) and
changes smoothly with the joints; a hull contains its mesh, so a clearance on hulls is a
clearance on the meshes. Verification measures the original meshes with a separately built
model (:mod:`freefloat.verify.clearance`).

The queries themselves are :class:`~freefloat.robot.pair_queries.PairQueries`. Only the pairs
that can be the closest are measured when only the closest is asked for
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
from collections.abc import Sequence
from dataclasses import dataclass
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
)
from .geometry import (
    OBSTACLE_PREFIX,
    add_obstacles,
    bodies_without_geometry,
    checked_pairs,
    load_shared_geometry,
)
from .meshes import HullInfo, hull_volume, mesh_volume, object_triangles, true_hull
from .model import Robot
from .obstacle import SHAPES, Obstacle
from .pair_levers import PairLevers
from .pair_queries import PairQueries
from .srdf import known_srdf

__all__ = [
    "GJK_TOLERANCE",
    "RETRY_TOLERANCES",
    "SHAPES",
    "CheckedDistance",
    "Closest",
    "CollisionModel",
    "Distances",
    "Obstacle",
    "PairClearance",
    "checked_distance",
    "clearance_at",
    "collision_model",
    "known_srdf",
]

#: Rows from which :meth:`CollisionModel.closest_many` places a batch's spheres at once.
BATCH = 8


class CollisionModel(PairQueries):
    """The checked pairs of a robot's collision geometry and their signed distances.

    The geometry's meshes are replaced by their true hulls and the obstacles added; the pairs
    checked are :func:`~freefloat.robot.geometry.checked_pairs`. The queries are those of
    :class:`~freefloat.robot.pair_queries.PairQueries`.

    Args:
        robot: the robot.
        srdf: an SRDF whose disabled pairs are not checked (None: no pair disabled).
        obstacles: keep-out shapes fixed to the spacecraft, checked against every arm body.
    """

    def __init__(
        self,
        robot: Robot,
        srdf: str | Path | None = None,
        obstacles: Sequence[Obstacle] = (),
    ) -> None:
        self.obstacles = tuple(obstacles)
        self.srdf = None if srdf is None else Path(srdf).expanduser().resolve()
        shared = load_shared_geometry(robot)
        geometry, keys = shared.model, shared.keys  # each mesh replaced below
        #: Movable bodies with no collision geometry (their clearance cannot be checked).
        self.uncovered = bodies_without_geometry(robot, geometry)
        self._meshes: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        for index, obj in enumerate(geometry.geometryObjects):
            if isinstance(obj.geometry, coal.BVHModelBase):
                self._meshes[index] = object_triangles(obj, keys[index])
                obj.geometry = true_hull(obj, keys[index])
        add_obstacles(robot, geometry, self.obstacles)
        pairs = checked_pairs(robot, geometry, srdf)
        objects = list(geometry.geometryObjects)
        names = [f"{objects[a].name} / {objects[b].name}" for a, b in pairs]
        paired = {k for pair in pairs for k in pair}
        #: Keep-out objects in no checked pair (no moving body with collision geometry to
        #: keep clear of them), by name.
        self.unpaired_obstacles = tuple(
            obj.name.removeprefix(OBSTACLE_PREFIX)
            for k, obj in enumerate(objects)
            if obj.name.startswith(OBSTACLE_PREFIX) and k not in paired
        )
        super().__init__(robot, geometry, pairs, names)
        self._levers: PairLevers | None = None
        if self._weights is not None:
            self._levers = PairLevers(
                robot, geometry, pairs, self._centres, self._radii, self._kinematics, self._weights
            )

    @property
    def levers(self) -> PairLevers | None:
        """The spheres' lever arms about the joint axes: tighter speed bounds, or None.

        See :class:`~freefloat.robot.pair_levers.PairLevers` (None: no motion weights, with a
        prismatic joint say).
        """
        return self._levers

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

    def pair_distances(self, joints: np.ndarray, pairs: Sequence[int]) -> np.ndarray:
        """Signed distances (m) of the listed pairs (indices) at the joint values, in order.

        The same figures as :meth:`distances` gives them, the other pairs not measured.
        """
        self._place(np.asarray(joints, dtype=float))
        measured = np.asarray(pairs, dtype=int).reshape(-1)
        return self._measure(measured, self._spheres(measured))

    def pairs_moved_by(self, joints: np.ndarray) -> np.ndarray:
        """(P,) which pairs' two shapes move relative to each other when ``joints`` (N,) move.

        A pair is moved by a joint that carries one of its shapes but not the other; a pair
        none of ``joints`` moves keeps its distance whatever they do.
        """
        carried = self._carried[self._pair_array] > 0.0  # (P, 2, N)
        relative = carried[:, 0] != carried[:, 1]
        return np.asarray(relative[:, np.asarray(joints, dtype=bool)].any(axis=1))

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
        self,
        joints: np.ndarray,
        slots: Sequence[float] | np.ndarray | None = None,
        gradients: bool = False,
        among: np.ndarray | None = None,
    ) -> Closest:
        """:meth:`closest_value` (with ``gradients``: :meth:`closest`) at many joint vectors.

        The same values, pairs and gradients as those calls one after the other, in order
        (``slots``: one per row, or None). A batch of at least :data:`BATCH` rows is bounded
        at once: its bounding spheres are placed in one pass
        (:class:`~freefloat.robot.sphere_kinematics.SphereKinematics`), a box fixed to the
        spacecraft bounds its pairs by its faces too
        (:class:`~freefloat.robot.fixed_boxes.FixedBoxes`), and every row's pairs are bounded
        from the bounds kept before the call (:meth:`PairBounds.widened_many`),
        so which pairs a row measures may differ from one call per row; the smallest
        distance and its pair cannot (a pair that can be the smallest is always measured).
        Its gradients come from one array product (:func:`witness_gradients`).

        Args:
            joints: (B, N) joint values (rad or m).
            slots: a normalised instant per row (see :meth:`closest_value`), or None.
            gradients: also each smallest distance's gradient over the joints (m per rad or m).
            among: (P,) which pairs the smallest is taken over (at least one; default all).

        The result also holds each row's lower bounds of every pair's distance (``lower``).
        """
        joints = np.atleast_2d(np.asarray(joints, dtype=float))
        count = len(joints)
        at = [None] * count if slots is None else [float(s) for s in slots]
        lower = np.full((count, len(self.pairs)), math.inf)
        if not len(self.pairs) or count < BATCH:
            return self._closest_each(joints, at, gradients, lower, among)
        centres = self._kinematics.centres(joints)
        gaps = self._kinematics.gaps_at(centres, self._pair_array)
        low, high = gaps - self._reach, gaps + self._reach
        boxed = self._boxes.pairs  # the faces of boxes fixed to the spacecraft bound these too
        low[:, boxed] = np.fmax(low[:, boxed], self._boxes.lower(centres))
        unknown = np.zeros(low.shape, dtype=bool)
        if self._bounds is not None:  # the tighter of the kept bounds and the spheres
            kept_low, kept_high = self._bounds.widened_many(at, joints)
            unknown = np.isnan(kept_low)
            low, high = np.fmax(low, kept_low), np.fmin(high, kept_high)
        chosen = np.ones(len(self.pairs), dtype=bool) if among is None else among
        nearest = np.where(chosen, high, math.inf).min(axis=1, keepdims=True)
        candidates = (low <= nearest + 1e-9) & chosen
        candidates[~np.isfinite(joints).all(axis=1)] = chosen  # no bound holds: each one asked
        found = self._measure_rows(joints, candidates, low, gaps, gradients)
        measure = found.measured
        lower[:] = np.where(measure, found.values, low)
        for i, k in found.retried:  # asked again at a looser EPA tolerance
            lower[i, k] -= RETRY_TOLERANCES[-1]
        if self._bounds is not None:  # measured values, and new pairs' sphere bounds
            known = np.where(measure, found.values, 0.0)
            for i, k in found.retried:  # a retried value is no reference: forgotten
                known[i, k] = math.nan
            self._bounds.record_rows(
                at,
                measure | unknown,
                joints,
                np.where(measure, known, low),
                np.where(measure, known, high),
            )
        best = found.values.argmin(axis=1)
        values = found.values[np.arange(count), best]
        grads = None
        if found.witnesses is not None:
            grads = found.witnesses.gradients(self._carried, self._pair_array[best])
        return Closest(values, best, grads, lower)

    def hulls(self) -> list[HullInfo]:
        """Per mesh, the volume it encloses and that of its hull (m^3), for reports."""
        objects = self.geometry.geometryObjects
        return [
            HullInfo(objects[i].name, mesh_volume(*mesh), hull_volume(objects[i].geometry))
            for i, mesh in self._meshes.items()
        ]


def collision_model(
    robot: Robot, srdf: str | Path | None = None, obstacles: Sequence[Obstacle] = ()
) -> CollisionModel:
    """The collision model of ``robot`` (see :class:`CollisionModel`)."""
    return CollisionModel(robot, srdf, obstacles)


@dataclass(frozen=True)
class PairClearance:
    """The smallest clearance at one configuration.

    Attributes:
        distance: the clearance (m; negative: penetration depth).
        pair: the index of the pair that has it (``CollisionModel.pairs``).
        name: that pair's name (``CollisionModel.names``).
    """

    distance: float
    pair: int
    name: str


def clearance_at(model: CollisionModel, joints: Sequence[float] | np.ndarray) -> PairClearance:
    """Smallest clearance (m) at one configuration and the pair that has it.

    Only the pairs that can be the closest are measured (:meth:`CollisionModel.closest_value`,
    bounded from their spheres alone): the same figure and pair as with every pair measured.
    """
    with model.own_bounds():  # not from the model's earlier queries
        value, k = model.closest_value(np.asarray(joints, dtype=float))
    return PairClearance(value, k, model.names[k])
