"""Collision geometry of a robot as its URDF states it: loading, checked pairs, true hulls.

Two distance models read the same URDF through this module and nothing else in common:

- the solvers' :class:`~freefloat.robot.collision.CollisionModel`, where every mesh is replaced
  by its **true convex hull** (qhull through coal, :func:`true_hull`); a hull contains its
  mesh, so a clearance measured on hulls is a clearance on the meshes;
- verification's :class:`~freefloat.verify.clearance.MeshClearance`, on the **original**
  geometry (meshes as bounding-volume hierarchies of their own triangles, primitives as
  themselves).

Both check the same pairs (:func:`checked_pairs`): every body on the spacecraft against every
arm body except the one mounted on it, every keep-out object against every arm body, and every
two arm bodies that are not parent and child; pairs an SRDF disables (MoveIt's
``<disable_collisions>``) are removed.

The URDF's geometry is parsed once per URDF in a process (each caller gets its own deep copy,
:func:`load_collision_geometry`; or, for the two models above, which never change a shape,
its own objects and primitives around the parsed meshes, :func:`load_shared_geometry`), a
mesh's triangles read once per file (:func:`object_triangles`), and hulls are built once per
mesh file and scale in a process (:func:`true_hull` keeps them), so a second plan of the same
robot pays nothing for them.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from ..errors import ModelError
from .model import Robot

__all__ = [
    "OBSTACLE_PREFIX",
    "HullInfo",
    "MeshKey",
    "SharedGeometry",
    "add_obstacles",
    "bodies_without_geometry",
    "checked_pairs",
    "load_collision_geometry",
    "load_shared_geometry",
    "mesh_volume",
    "object_triangles",
    "true_hull",
]


#: Name prefix of keep-out objects in a geometry model (``obstacle:<name>``).
OBSTACLE_PREFIX = "obstacle:"


def load_collision_geometry(robot: Robot) -> pin.GeometryModel:
    """A fresh geometry model of the URDF's collision elements (meshes as BVHs; m).

    The URDF and its meshes are parsed once per URDF text, file, package folders and joint
    names in a process (and again when a mesh file changes on disk); each call gets its own
    deep copy, so two callers never share shape objects.

    Raises:
        ModelError: the URDF's collision geometry cannot be read (a missing or broken mesh).
    """
    return _parsed(robot)[0].clone()


#: A mesh object's file, scale and a digest of its vertices (see _mesh_key).
MeshKey = tuple[str, tuple[float, ...], str]


@dataclass(frozen=True)
class SharedGeometry:
    """A geometry model around the parsed meshes (see :func:`load_shared_geometry`).

    Attributes:
        model: the geometry model (its objects its own; its meshes the parsed ones).
        keys: each mesh object's key, by object index, worked out when it was parsed.
    """

    model: pin.GeometryModel
    keys: dict[int, MeshKey]


def load_shared_geometry(robot: Robot) -> SharedGeometry:
    """:func:`load_collision_geometry` without copying the meshes (callers never change one).

    Its objects are copies of the parsed ones and primitives deep copies, but each mesh is
    the parsed shape, shared by every such caller in the process: it may be read (coal's
    queries, :func:`object_triangles`, :func:`true_hull`) or replaced in the model, never
    changed.

    Raises:
        ModelError: as :func:`load_collision_geometry`.
    """
    parsed, keys = _parsed(robot)
    geometry = pin.GeometryModel()
    for obj in parsed.geometryObjects:
        copy = pin.GeometryObject(obj)  # the same shape
        if not isinstance(obj.geometry, coal.BVHModelBase):
            copy.geometry = obj.geometry.clone()
        geometry.addGeometryObject(copy)
    return SharedGeometry(geometry, dict(keys))


def _parsed(robot: Robot) -> tuple[pin.GeometryModel, dict[int, MeshKey]]:
    """The parsed collision geometry of the URDF, kept (see :func:`load_collision_geometry`).

    With each mesh object's key (by index): the parsed shapes never change.
    """
    key = (
        robot.urdf_text,
        str(robot.urdf),
        tuple(str(d) for d in robot.package_dirs),
        tuple(robot.model.names),
    )
    parsed = _PARSED.get(key)
    if parsed is None or parsed[1] != _stamps(parsed[0]):
        try:
            geometry = pin.buildGeomFromUrdf(
                robot.model,
                str(robot.urdf),
                pin.GeometryType.COLLISION,
                None,
                [str(d) for d in robot.package_dirs],
            )
        except (RuntimeError, ValueError) as exc:
            raise ModelError(
                f"cannot read its collision geometry ({exc})", str(robot.urdf)
            ) from None
        if len(_PARSED) >= 16:
            _PARSED.pop(next(iter(_PARSED)))
        keys = {
            i: _mesh_key(obj)
            for i, obj in enumerate(geometry.geometryObjects)
            if isinstance(obj.geometry, coal.BVHModelBase)
        }
        parsed = _PARSED[key] = (geometry, _stamps(geometry), keys)
    return parsed[0], parsed[2]


def _stamps(geometry: pin.GeometryModel) -> tuple[tuple[str, int, int], ...]:
    """(path, modification time in ns, size in bytes) of every mesh file the model read."""
    out = []
    for obj in geometry.geometryObjects:
        if obj.meshPath:
            try:
                stat = Path(obj.meshPath).stat()
            except OSError:
                out.append((obj.meshPath, -1, -1))
                continue
            out.append((obj.meshPath, stat.st_mtime_ns, stat.st_size))
    return tuple(out)


#: Parsed collision geometry per URDF (see load_collision_geometry), with its mesh files' stamps.
_PARSED: dict[
    tuple, tuple[pin.GeometryModel, tuple[tuple[str, int, int], ...], dict[int, MeshKey]]
] = {}


def add_obstacles(robot: Robot, geometry: pin.GeometryModel, obstacles: Sequence) -> None:
    """Add keep-out objects (:class:`~freefloat.robot.collision.Obstacle`) fixed to the base."""
    model = robot.model
    frame = model.getFrameId(robot.base_link)
    for obstacle in obstacles:
        geometry.addGeometryObject(
            pin.GeometryObject(
                f"{OBSTACLE_PREFIX}{obstacle.name}",
                1,  # the free-flyer joint: fixed to the spacecraft
                frame,
                model.frames[frame].placement * obstacle.placement(),
                obstacle.geometry(),
            )
        )


def checked_pairs(
    robot: Robot, geometry: pin.GeometryModel, srdf: str | Path | None
) -> list[tuple[int, int]]:
    """The pairs of ``geometry`` whose clearance is checked, as index pairs (see module doc).

    Adds them to ``geometry`` as its collision pairs too. Worked out once per set of objects
    (names, joints, links), kinematic tree and SRDF file (path, modification time, size) in a
    process, and again when any of them changes.

    Raises:
        ModelError: the SRDF file does not exist.
    """
    model = robot.model
    path, stamp = None, None
    if srdf is not None:
        path = Path(srdf).expanduser().resolve()
        if not path.is_file():
            raise ModelError(f"SRDF file not found: {path}")
        stat = path.stat()
        stamp = (str(path), stat.st_mtime_ns, stat.st_size)
    objects = list(geometry.geometryObjects)
    key = (
        tuple((o.name, int(o.parentJoint), model.frames[o.parentFrame].name) for o in objects),
        tuple(int(j) for j in model.parents),
        stamp,
    )
    pairs = _PAIRS.get(key)
    if pairs is None:
        pairs = _PAIRS[key] = _pairs_of(model, geometry, path)
        if len(_PAIRS) > 32:
            _PAIRS.pop(next(iter(_PAIRS)))
    else:
        geometry.removeAllCollisionPairs()
        for a, b in pairs:
            geometry.addCollisionPair(pin.CollisionPair(a, b))
    return list(pairs)


def _pairs_of(
    model: pin.Model, geometry: pin.GeometryModel, srdf: Path | None
) -> list[tuple[int, int]]:
    """:func:`checked_pairs` worked out: every pair the rules keep, less the SRDF's."""
    parent = [int(j) for j in model.parents]
    objects = list(geometry.geometryObjects)
    joints = [int(obj.parentJoint) for obj in objects]
    obstacle = [obj.name.startswith(OBSTACLE_PREFIX) for obj in objects]
    geometry.removeAllCollisionPairs()
    for a in range(len(objects)):
        for b in range(a + 1, len(objects)):
            ja, jb = joints[a], joints[b]
            if ja == jb:
                continue  # one body
            kept_out = obstacle[a] or obstacle[b]
            if not kept_out and (parent[ja] == jb or parent[jb] == ja):
                continue  # parent and child touch by design (a keep-out object never does)
            geometry.addCollisionPair(pin.CollisionPair(a, b))
    if srdf is not None:
        pin.removeCollisionPairs(model, geometry, str(srdf))
    return [(int(p.first), int(p.second)) for p in geometry.collisionPairs]


#: Checked pairs per set of objects, kinematic tree and SRDF file (see checked_pairs).
_PAIRS: dict[tuple, list[tuple[int, int]]] = {}


def bodies_without_geometry(robot: Robot, geometry: pin.GeometryModel) -> list[str]:
    """Links moved by a joint (Pinocchio bodies) that carry no collision geometry at all.

    A body is the link a joint moves together with every link fixed to it (fixed-joint merging
    puts their collision elements on that joint); it is named by its first link.
    """
    model = robot.model
    covered = {int(obj.parentJoint) for obj in geometry.geometryObjects}
    missing = []
    for joint in range(2, model.njoints):  # 0: the universe, 1: the spacecraft's free flyer
        if joint in covered:
            continue
        bodies = [f.name for f in model.frames if f.type == pin.FrameType.BODY]
        owners = [f.parentJoint for f in model.frames if f.type == pin.FrameType.BODY]
        body = bodies[owners.index(joint)] if joint in owners else model.names[joint]
        missing.append(body)
    return missing


@dataclass(frozen=True)
class HullInfo:
    """How much a link's convex hull adds to its mesh.

    Attributes:
        name: the geometry object's name.
        mesh_volume: volume the mesh encloses (m^3); NaN when the mesh is not closed.
        hull_volume: volume of its convex hull (m^3).
    """

    name: str
    mesh_volume: float
    hull_volume: float

    @property
    def extra_fraction(self) -> float:
        """The hull's extra volume as a fraction of the mesh's (1), NaN when unknown."""
        if not (math.isfinite(self.mesh_volume) and self.mesh_volume > 0.0):
            return math.nan
        return self.hull_volume / self.mesh_volume - 1.0


#: True hulls by mesh file, scale and vertices, built once in a process.
_HULLS: dict[MeshKey, coal.ConvexBase] = {}


def _mesh_key(obj: pin.GeometryObject) -> MeshKey:
    """A mesh object's file, scale and a digest of the vertices it was read with.

    A mesh file changed on disk (between two plans, or while one is made) never meets the
    cached hull or triangles of its former content.
    """
    vertices = np.ascontiguousarray(np.array(obj.geometry.vertices(), dtype=float))
    digest = hashlib.sha256(vertices.tobytes()).hexdigest()
    return str(obj.meshPath), tuple(float(s) for s in obj.meshScale), digest


def true_hull(obj: pin.GeometryObject, key: MeshKey | None = None) -> coal.ConvexBase:
    """The real convex hull (qhull, coal ``buildConvexHull(True, "Qt")``) of a mesh object.

    Remembered per mesh file, scale and vertices (``key``: the object's, if known, as
    :func:`load_shared_geometry` gives it). Never ``buildConvexRepresentation``: for a
    non-convex mesh that keeps the mesh's own faces, and GJK's support search on it stops at
    local maxima.
    """
    key = _mesh_key(obj) if key is None else key
    if key not in _HULLS:
        shape = obj.geometry.clone()  # the object's own shape is left as it is
        shape.buildConvexHull(True, "Qt")
        _HULLS[key] = shape.convex
    return _HULLS[key]


def mesh_triangles(shape: coal.BVHModelBase) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) (m) and triangles (F, 3) (vertex indices) of a coal mesh."""
    vertices = np.array(shape.vertices(), dtype=float).reshape(-1, 3)
    triangles = np.array(
        [[t[0], t[1], t[2]] for t in (shape.tri_indices(i) for i in range(shape.num_tris))],
        dtype=int,
    ).reshape(-1, 3)
    return vertices, triangles


def object_triangles(
    obj: pin.GeometryObject, key: MeshKey | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`mesh_triangles` of a mesh object, read once per mesh file, scale and vertices.

    ``key``: as for :func:`true_hull`. The arrays are shared between callers, so they are
    read-only.
    """
    key = _mesh_key(obj) if key is None else key
    if key not in _TRIANGLES:
        vertices, triangles = mesh_triangles(obj.geometry)
        vertices.setflags(write=False)
        triangles.setflags(write=False)
        _TRIANGLES[key] = (vertices, triangles)
    return _TRIANGLES[key]


#: Triangles per mesh file, scale and vertices (see object_triangles).
_TRIANGLES: dict[MeshKey, tuple[np.ndarray, np.ndarray]] = {}


def mesh_volume(vertices: np.ndarray, triangles: np.ndarray) -> float:
    """Volume (m^3) a closed triangle mesh encloses (divergence theorem); NaN if not closed.

    A mesh is closed when every edge is shared by exactly two triangles.
    """
    pairs = (triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]])
    edges = np.sort(np.concatenate(pairs), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    if len(counts) == 0 or not np.all(counts == 2):
        return math.nan
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    return abs(float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6.0)


def hull_volume(hull: coal.ConvexBase) -> float:
    """Volume of a coal convex hull (m^3), from its points (qhull through scipy)."""
    from scipy.spatial import ConvexHull  # when needed: it costs start-up time

    points = np.array(hull.points(), dtype=float).reshape(-1, 3)
    return float(ConvexHull(points).volume)
