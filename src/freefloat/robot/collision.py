"""Collision model of a free floater: which bodies may touch, and how far apart they are.

Built with Pinocchio's URDF geometry parser and coal (collision geometry of the URDF, meshes
resolved through the robot's package folders). Each mesh is replaced by its convex hull, so
that every distance is a signed distance (negative when two shapes overlap, by GJK/EPA) and
changes smoothly with the joints; the hull is never inside the mesh, so a clearance on hulls
is a clearance on the meshes.

Pairs checked: every body on the spacecraft (its hull, the arm's fixed first link, keep-out
objects and anything else fixed to it) against every arm body except the one mounted on it;
and every two arm bodies that are not parent and child. Pairs an SRDF disables (the MoveIt
convention, ``<disable_collisions>``) are removed.

The base is free-floating, but every collision geometry here is fixed either to the spacecraft
or to an arm link, so distances depend on the joints alone: they are computed with the
spacecraft at the identity pose, in its frame (m). Gradients with respect to the joints come
from the witness points and the joint Jacobians (``n . (J_2(p_2) - J_1(p_1))``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from ..errors import InputError, ModelError
from .model import Robot, example_robot_data_dir

__all__ = [
    "ARM_SRDFS",
    "GJK_TOLERANCE",
    "SHAPES",
    "CollisionModel",
    "Distances",
    "Obstacle",
    "collision_model",
    "known_srdf",
]

#: Keep-out shapes and the sizes each takes (m): box [x, y, z], sphere [r], capsule [r, length].
SHAPES = {"box": 3, "sphere": 1, "capsule": 2}

#: SRDF files of example-robot-data arms (below ``example-robot-data/robots``).
ARM_SRDFS = {
    "panda": "panda_description/srdf/panda.srdf",
    "ur5": "ur_description/srdf/ur5.srdf",
    "kinova": "kinova_description/srdf/kinova.srdf",
    "xarm7": "xarm_description/srdf/xarm7.srdf",
    "z1": "z1_description/srdf/z1.srdf",
}


def known_srdf(robot: Robot) -> Path | None:
    """The SRDF of a servicer composed from an example-robot-data arm (named ``ARM_servicer``).

    None for any other robot, or when example-robot-data is not installed.
    """
    arm = robot.name.removesuffix("_servicer")
    share = example_robot_data_dir()
    if arm == robot.name or arm not in ARM_SRDFS or share is None:
        return None
    path = share / "example-robot-data" / "robots" / ARM_SRDFS[arm]
    return path if path.is_file() else None


@dataclass(frozen=True)
class Obstacle:
    """A keep-out object fixed to the spacecraft.

    Attributes:
        name: its name (in messages and plots).
        shape: ``"box"``, ``"sphere"`` or ``"capsule"`` (a capsule's axis is its local z).
        size: box edge lengths [x, y, z], sphere [radius], capsule [radius, length] (m).
        xyz: position of its centre in the spacecraft frame (m).
        rpy: its orientation in the spacecraft frame, roll, pitch, yaw (rad).
    """

    name: str
    shape: str
    size: tuple[float, ...]
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise InputError(
                f"obstacle {self.name!r}: unknown shape {self.shape!r}; valid: " + ", ".join(SHAPES)
            )
        if len(self.size) != SHAPES[self.shape]:
            raise InputError(
                f"obstacle {self.name!r}: a {self.shape} takes {SHAPES[self.shape]} size(s) "
                f"[m], got {len(self.size)}"
            )
        if not all(math.isfinite(s) and s > 0.0 for s in self.size):
            raise InputError(
                f"obstacle {self.name!r}: sizes must be finite and > 0 m, got {list(self.size)}"
            )
        if not all(math.isfinite(v) for v in (*self.xyz, *self.rpy)):
            raise InputError(f"obstacle {self.name!r}: pose must be finite numbers")

    def geometry(self) -> coal.CollisionGeometry:
        """The coal shape."""
        if self.shape == "box":
            return coal.Box(*self.size)
        if self.shape == "sphere":
            return coal.Sphere(self.size[0])
        return coal.Capsule(self.size[0], self.size[1])

    def placement(self) -> pin.SE3:
        """Its pose in the spacecraft frame."""
        return pin.SE3(pin.rpy.rpyToMatrix(*self.rpy), np.array(self.xyz, dtype=float))


#: Convergence tolerance of coal's GJK and EPA distance queries (m).
GJK_TOLERANCE = 1e-9


@dataclass(frozen=True)
class Distances:
    """Signed distances of every checked pair at one configuration.

    Attributes:
        values: (P,) signed distances (m), negative when the shapes overlap.
        gradients: (P, N) derivatives with respect to the N joints (m per rad or m per m),
            when asked for.
    """

    values: np.ndarray
    gradients: np.ndarray | None = None


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
        model = robot.model
        try:
            geometry = pin.buildGeomFromUrdf(
                model,
                str(robot.urdf),
                pin.GeometryType.COLLISION,
                None,
                [str(d) for d in robot.package_dirs],
            )
        except (RuntimeError, ValueError) as exc:
            raise ModelError(
                f"cannot read its collision geometry ({exc})", str(robot.urdf)
            ) from None
        for obj in geometry.geometryObjects:
            shape = obj.geometry
            if hasattr(shape, "buildConvexRepresentation"):
                shape.buildConvexRepresentation(False)
                obj.geometry = shape.convex
        base_frame = model.frames[model.getFrameId(robot.base_link)]
        for obstacle in self.obstacles:
            geometry.addGeometryObject(
                pin.GeometryObject(
                    f"obstacle:{obstacle.name}",
                    1,  # the free-flyer joint: fixed to the spacecraft
                    model.getFrameId(robot.base_link),
                    base_frame.placement * obstacle.placement(),
                    obstacle.geometry(),
                )
            )
        parent = {j: int(model.parents[j]) for j in range(model.njoints)}
        objects = list(geometry.geometryObjects)
        for a in range(len(objects)):
            for b in range(a + 1, len(objects)):
                ja, jb = objects[a].parentJoint, objects[b].parentJoint
                if ja == jb or parent[ja] == jb or parent[jb] == ja:
                    continue  # one body, or parent and child: they touch by design
                geometry.addCollisionPair(pin.CollisionPair(a, b))
        if srdf is not None:
            path = Path(srdf).expanduser().resolve()
            if not path.is_file():
                raise ModelError(f"SRDF file not found: {path}")
            pin.removeCollisionPairs(model, geometry, str(path))
        self.geometry = geometry
        self.pairs = [(int(p.first), int(p.second)) for p in geometry.collisionPairs]
        self.names = [f"{objects[a].name} / {objects[b].name}" for a, b in self.pairs]
        self._data = robot.model.createData()
        self._geometry_data = pin.GeometryData(geometry)
        self._request = coal.DistanceRequest()
        self._request.gjk_tolerance = GJK_TOLERANCE  # coal's default 1e-6 m is too coarse
        self._request.epa_tolerance = GJK_TOLERANCE
        self._request.gjk_max_iterations = 1000
        self._request.enable_signed_distance = True
        self._results: dict[int, coal.DistanceResult] = {}
        # Bounding spheres (centre in the shape's frame, radius; m) for exact culling: a pair
        # whose spheres are farther apart than the best exact distance cannot be the closest.
        centres, radii = [], []
        for obj in geometry.geometryObjects:
            obj.geometry.computeLocalAABB()
            centres.append(np.asarray(obj.geometry.aabb_center, dtype=float))
            radii.append(float(obj.geometry.aabb_radius))
        self._centres, self._radii = np.array(centres), np.array(radii)
        self._shapes = [obj.geometry for obj in geometry.geometryObjects]
        pairs = np.array(self.pairs, dtype=int).reshape(-1, 2)
        self._first, self._second = pairs[:, 0], pairs[:, 1]
        self._columns = np.array([j.idx_v for j in robot.joints])

    @property
    def n_pairs(self) -> int:
        """Number of checked pairs."""
        return len(self.pairs)

    def distances(self, joints: np.ndarray, gradients: bool = False) -> Distances:
        """Signed distances (m) of every pair at the joint values (rad or m).

        With ``gradients``, also their derivatives with respect to the joints.
        """
        model, data, gdata = self.robot.model, self._data, self._geometry_data
        q = self.robot.configuration(np.asarray(joints, dtype=float))
        pin.forwardKinematics(model, data, q)
        pin.updateGeometryPlacements(model, data, self.geometry, gdata)
        # One fresh coal query per pair: results must not carry anything over between calls.
        objects = self.geometry.geometryObjects
        placements = [coal.Transform3s(m.rotation, m.translation) for m in gdata.oMg]
        self._results = {}
        values = np.empty(len(self.pairs))
        for k, (a, b) in enumerate(self.pairs):
            result = coal.DistanceResult()
            values[k] = coal.distance(
                objects[a].geometry,
                placements[a],
                objects[b].geometry,
                placements[b],
                self._request,
                result,
            )
            self._results[k] = result
        if not gradients:
            return Distances(values)
        pin.computeJointJacobians(model, data, q)
        grads = np.stack([self._gradient(k) for k in range(len(self.pairs))])
        return Distances(values, grads)

    def closest_value(self, joints: np.ndarray, cap: float = math.inf) -> tuple[float, int]:
        """The smallest signed distance over the pairs (m) and its pair index.

        Exact, and cheaper than :meth:`distances`: pairs are visited in the order of a lower
        bound (bounding spheres) and the search stops once that bound exceeds the best exact
        distance found. With a finite ``cap`` (m) it also stops once the bound exceeds the cap:
        the answer is then a lower bound of the distance, larger than the cap (solvers only
        need exact values near their margin).
        """
        model, data, gdata = self.robot.model, self._data, self._geometry_data
        q = self.robot.configuration(np.asarray(joints, dtype=float))
        pin.forwardKinematics(model, data, q)
        pin.updateGeometryPlacements(model, data, self.geometry, gdata)
        placements = list(gdata.oMg)
        centres = np.array([m.act(c) for m, c in zip(placements, self._centres, strict=True)])
        bound = (
            np.linalg.norm(centres[self._first] - centres[self._second], axis=1)
            - self._radii[self._first]
            - self._radii[self._second]
        )
        transforms: dict[int, coal.Transform3s] = {}

        def transform(index: int) -> coal.Transform3s:
            if index not in transforms:
                m = placements[index]
                transforms[index] = coal.Transform3s(m.rotation, m.translation)
            return transforms[index]

        best, best_k = math.inf, -1
        self._results = {}
        for index in np.argsort(bound):
            k = int(index)
            if bound[k] > best:
                break
            if bound[k] > cap:
                if bound[k] < best:
                    best, best_k = float(bound[k]), k
                break
            a, b = self.pairs[k]
            result = coal.DistanceResult()
            value = coal.distance(
                self._shapes[a], transform(a), self._shapes[b], transform(b), self._request, result
            )
            self._results[k] = result
            if value < best:
                best, best_k = float(value), k
        return best, best_k

    def closest(self, joints: np.ndarray, cap: float = math.inf) -> tuple[float, np.ndarray, int]:
        """The smallest signed distance (m), its gradient over the joints, and its pair index.

        Cheaper than :meth:`distances` with gradients: culled pairs, one gradient. Beyond a
        finite ``cap`` (see :meth:`closest_value`) the value is a lower bound and the gradient
        is zero.
        """
        value, k = self.closest_value(joints, cap)
        if k not in self._results:
            return value, np.zeros(self.robot.n), k
        pin.computeJointJacobians(self.robot.model, self._data)  # at closest_value's pose
        return value, self._gradient(k), k

    def _gradient(self, k: int) -> np.ndarray:
        """d(distance of pair k)/d(joints), after distances and joint Jacobians are computed."""
        model, data = self.robot.model, self._data
        result = self._results[k]
        normal = np.asarray(result.normal)
        objects = self.geometry.geometryObjects
        a, b = self.pairs[k]
        grad = np.zeros(self.robot.n)
        for index, point, sign in (
            (a, result.getNearestPoint1(), -1.0),
            (b, result.getNearestPoint2(), 1.0),
        ):
            joint = objects[index].parentJoint
            if joint <= 1:
                continue  # fixed to the spacecraft: does not move with the joints
            jac = pin.getJointJacobian(model, data, joint, pin.LOCAL_WORLD_ALIGNED)
            offset = np.asarray(point) - data.oMi[joint].translation
            linear = jac[:3] - pin.skew(offset) @ jac[3:]
            grad += sign * (normal @ linear[:, self._columns])
        return grad


def collision_model(
    robot: Robot, srdf: str | Path | None = None, obstacles: Sequence[Obstacle] = ()
) -> CollisionModel:
    """The collision model of ``robot`` (see :class:`CollisionModel`)."""
    return CollisionModel(robot, srdf, obstacles)
