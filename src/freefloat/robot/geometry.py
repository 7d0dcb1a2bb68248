"""Collision geometry of a robot as its URDF states it: loading and checked pairs.

Two distance models read the same URDF through this module and nothing else in common:

- the solvers' :class:`~freefloat.robot.collision.CollisionModel`, where every mesh is replaced
  by its **true convex hull** (qhull through coal, :func:`.meshes.true_hull`); a hull contains its
  mesh, so a clearance measured on hulls is a clearance on the meshes;
- verification's :class:`~freefloat.verify.clearance.MeshClearance`, on the **original**
  geometry (meshes as bounding-volume hierarchies of their own triangles, primitives as
  themselves).

Both check the same pairs (:func:`checked_pairs`): every body on the spacecraft against every
arm body except the one mounted on it, every keep-out object against every arm body, and every
two arm bodies that are not parent and child, judged on the arm as built (a locked joint still
separates its bodies: :mod:`.designed_bodies`; a link one joint from the spacecraft that the
joint swings into it is checked against it: :mod:`.swing`); a captured payload against every
body but the one holding it and that one's fingers (the link before it included); pairs an
SRDF disables (MoveIt's ``<disable_collisions>``) are removed.

The URDF's geometry is parsed once per URDF in a process (each caller gets its own deep copy,
:func:`load_collision_geometry`; or, for the two models above, which never change a shape,
its own objects and primitives around the parsed meshes, :func:`load_shared_geometry`), a
mesh's triangles read once per file and hulls built once per mesh file and scale in a process
(:mod:`.meshes`), so a second plan of the same robot pays nothing for them.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Generic, TypeVar

import coal
import numpy as np
import pinocchio as pin

from ..errors import ModelError
from .designed_bodies import DesignedBodies, designed_bodies, finger_of
from .file_stamp import FileStamp, file_stamp
from .meshes import MeshKey, check_finite_meshes, mesh_key
from .model import Robot
from .parser_messages import parser_messages
from .payload import PAYLOAD_LINK
from .srdf import remove_srdf_pairs
from .swing import swinging_pairs

__all__ = [
    "OBSTACLE_PREFIX",
    "BuiltPerSource",
    "SharedGeometry",
    "add_obstacles",
    "bodies_without_geometry",
    "checked_pairs",
    "geometry_source",
    "load_collision_geometry",
    "load_shared_geometry",
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


def geometry_source(robot: Robot, srdf: str | Path | None) -> tuple:
    """What ``robot``'s collision models are built from, as a key (hashable).

    The URDF (text, path, package folders), the kinematic tree, and the stamps of its mesh
    files and of the SRDF (:func:`.file_stamp.file_stamp`: they change with the content).
    Fresh loads of one unchanged file, and a robot with other masses only, have the same key:
    the same geometry and pairs.
    """
    parsed = _parsed_entry(robot)
    model = robot.model
    tree = (
        tuple(model.names),
        tuple(int(j) for j in model.parents),
        tuple(j.shortname() for j in model.joints),
        b"".join(np.asarray(p.homogeneous).tobytes() for p in model.jointPlacements),
    )
    dirs = tuple(str(d) for d in robot.package_dirs)
    return (robot.urdf_text, str(robot.urdf), dirs, tree, parsed[1], _srdf_stamp(srdf, False))


Built = TypeVar("Built")


class BuiltPerSource(Generic[Built]):
    """Models built from a robot's collision geometry, an SRDF and obstacles, kept per source.

    The key is :func:`geometry_source` and the obstacles: a fresh load of an unchanged URDF
    gets the model built for an earlier load, and a changed URDF, mesh file or SRDF a new
    one. At most :data:`KEPT` are kept (the oldest goes first).

    Args:
        build: ``build(robot, srdf, obstacles)``, the model.
    """

    KEPT = 16

    def __init__(self, build: Callable[[Robot, str | Path | None, Sequence], Built]) -> None:
        self._build = build
        self._kept: dict[tuple, Built] = {}

    def get(self, robot: Robot, srdf: str | Path | None, obstacles: Sequence) -> Built:
        """The model for ``robot`` with ``srdf`` and ``obstacles``, built when not kept.

        A model is built on a copy of the robot's Pinocchio model: the caller may change its
        own robot afterwards (then it has another source) without touching a kept model.
        """
        key = (geometry_source(robot, srdf), tuple(obstacles))
        if key not in self._kept:
            if len(self._kept) >= self.KEPT:
                self._kept.pop(next(iter(self._kept)))
            own = replace(robot, model=robot.model.copy())
            self._kept[key] = self._build(own, srdf, obstacles)
        return self._kept[key]


def _srdf_stamp(srdf: str | Path | None, strict: bool = True) -> FileStamp | None:
    """The SRDF file's stamp (:func:`.file_stamp.file_stamp`), or None for none.

    Raises:
        ModelError: with ``strict``, the file does not exist (else its stamp holds -1s).
    """
    if srdf is None:
        return None
    path = Path(srdf).expanduser().resolve()
    if strict and path.exists() and not path.is_file():
        raise ModelError(
            f"SRDF {path} is not a regular file (a folder, a device or a FIFO); give an SRDF file"
        )
    if strict and not path.is_file():
        raise ModelError(f"SRDF file not found: {path}")
    return file_stamp(str(path), digest=True)  # a small text file: its content, always


def _parsed(robot: Robot) -> tuple[pin.GeometryModel, dict[int, MeshKey]]:
    """The parsed collision geometry of the URDF, kept, with each mesh object's key."""
    entry = _parsed_entry(robot)
    return entry[0], entry[2]


def _parsed_entry(
    robot: Robot,
) -> tuple[pin.GeometryModel, tuple[FileStamp, ...], dict[int, MeshKey]]:
    """The parsed collision geometry of the URDF, kept (see :func:`load_collision_geometry`).

    With its mesh files' stamps and each mesh object's key (by index): the parsed shapes
    never change.
    """
    key = (
        robot.urdf_text,
        str(robot.urdf),
        tuple(str(d) for d in robot.package_dirs),
        tuple(robot.model.names),
    )
    parsed = _PARSED.get(key)
    if parsed is None or parsed[1] != _stamps(parsed[0], parsed[1]):
        dirs = [str(d) for d in robot.package_dirs]
        try:  # C++ prints of a bad mesh (coal's "eigen: too many iterations") collected
            # from the text the robot was loaded from, the one the models are kept under (the
            # file may have changed on disk since); the file for a robot without one
            with parser_messages():
                geometry = (
                    pin.buildGeomFromUrdfString(
                        robot.model, robot.urdf_text, pin.GeometryType.COLLISION, None, dirs
                    )
                    if robot.urdf_text
                    else pin.buildGeomFromUrdf(
                        robot.model, str(robot.urdf), pin.GeometryType.COLLISION, None, dirs
                    )
                )
            check_finite_meshes(geometry)
        except (RuntimeError, ValueError) as exc:
            raise ModelError(
                f"cannot read its collision geometry ({exc}); put the mesh files where the "
                "URDF names them, or plan without clearance: [safety] check = false",
                str(robot.urdf),
            ) from None
        if len(_PARSED) >= 16:
            _PARSED.pop(next(iter(_PARSED)))
        keys = {
            i: mesh_key(obj)
            for i, obj in enumerate(geometry.geometryObjects)
            if isinstance(obj.geometry, coal.BVHModelBase)
        }
        parsed = _PARSED[key] = (geometry, _stamps(geometry), keys)
    return parsed


def _stamps(geometry: pin.GeometryModel, like: tuple[FileStamp, ...] = ()) -> tuple[FileStamp, ...]:
    """The stamp (:func:`.file_stamp.file_stamp`) of every mesh file the model read.

    ``like``: the stamps to compare with (a digest where they hold one).
    """
    paths = [obj.meshPath for obj in geometry.geometryObjects if obj.meshPath]
    earlier = list(like) if len(like) == len(paths) else [None] * len(paths)
    return tuple(file_stamp(p, e) for p, e in zip(paths, earlier, strict=True))


#: Parsed collision geometry per URDF (see load_collision_geometry), with its mesh files' stamps.
_PARSED: dict[tuple, tuple[pin.GeometryModel, tuple[FileStamp, ...], dict[int, MeshKey]]] = {}


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
    (names, joints, links), kinematic tree, joint names and SRDF file (its stamp,
    :func:`.file_stamp.file_stamp`) in a process, and again when any of them changes.

    Raises:
        ModelError: the SRDF file does not exist.
    """
    model = robot.model
    stamp = _srdf_stamp(srdf)
    path = None if stamp is None else Path(stamp[0])
    objects = list(geometry.geometryObjects)
    designed = designed_bodies(robot.urdf_text) if robot.urdf_text else None
    links = [model.frames[o.parentFrame].name for o in objects]
    key = (
        tuple((o.name, int(o.parentJoint), link) for o, link in zip(objects, links, strict=True)),
        tuple(int(j) for j in model.parents),
        tuple(model.names),  # the payload's fingers are known by their joints' names
        stamp,
        None if designed is None else tuple(designed.placed(link) for link in links),
        # the swing sweep reads the joints' origins, axes and limits and the shapes: all the
        # URDF's (mesh files by name; a mesh changed on disk under the same URDF is not seen)
        hashlib.sha256(robot.urdf_text.encode("utf-8")).hexdigest(),
    )
    pairs = _PAIRS.get(key)
    if pairs is None:
        pairs = _PAIRS[key] = _pairs_of(model, geometry, path, designed)
        if len(_PAIRS) > 32:
            _PAIRS.pop(next(iter(_PAIRS)))
    else:
        geometry.removeAllCollisionPairs()
        for a, b in pairs:
            geometry.addCollisionPair(pin.CollisionPair(a, b))
    return list(pairs)


def _pairs_of(
    model: pin.Model,
    geometry: pin.GeometryModel,
    srdf: Path | None,
    designed: DesignedBodies | None = None,
) -> list[tuple[int, int]]:
    """:func:`checked_pairs` worked out: every pair the rules keep, less the SRDF's.

    Parent and child are judged on the arm as designed (``designed``: a locked joint still
    separates its bodies, :mod:`.designed_bodies`), or without it on Pinocchio's bodies.
    """
    parent = [int(j) for j in model.parents]
    objects = list(geometry.geometryObjects)
    links = [model.frames[obj.parentFrame].name for obj in objects]
    joints = [int(obj.parentJoint) for obj in objects]
    obstacle = [obj.name.startswith(OBSTACLE_PREFIX) for obj in objects]
    # a captured payload is carried by its end effector's body but is no part of it: it
    # touches that body (and its fingers) by design, never the link before nor the arm beyond
    payload = [model.frames[obj.parentFrame].name == PAYLOAD_LINK for obj in objects]
    geometry.removeAllCollisionPairs()
    spared: list[tuple[int, int]] = []
    for a in range(len(objects)):
        for b in range(a + 1, len(objects)):
            ja, jb = joints[a], joints[b]
            if ja == jb and not (designed and designed.held_apart(links[a], links[b])):
                if designed and designed.adjacent(links[a], links[b]):
                    spared.append((a, b))  # a lock holds them: unless it holds one in the other
                continue  # one body (unless locks made it: then its start keeps the margin)
            if obstacle[a] or obstacle[b]:  # a keep-out object touches nothing by design
                geometry.addCollisionPair(pin.CollisionPair(a, b))
                continue
            if designed is not None:
                touching = designed.adjacent(links[a], links[b])
            else:
                touching = parent[ja] == jb or parent[jb] == ja
            if not (payload[a] or payload[b]) and touching:
                spared.append((a, b))  # parent and child touch by design (a payload is neither)
                continue
            if (payload[a] and finger_of(model, ja, jb)) or (
                payload[b] and finger_of(model, jb, ja)
            ):
                continue  # a grasped payload touches its holder's fingers
            geometry.addCollisionPair(pin.CollisionPair(a, b))
    swinging = set() if designed is None else swinging_pairs(model, geometry, designed, spared)
    if swinging:  # unless the joint swings one into the spacecraft (.swing), in one order
        every = sorted({(int(p.first), int(p.second)) for p in geometry.collisionPairs} | swinging)
        geometry.removeAllCollisionPairs()
        for a, b in every:
            geometry.addCollisionPair(pin.CollisionPair(a, b))
    if srdf is not None:  # never a keep-out object's pairs: they belong to no link's design
        kept = [  # as numbers: the vector's elements change under removal
            (int(p.first), int(p.second))
            for p in geometry.collisionPairs
            if obstacle[p.first] or obstacle[p.second]
        ]
        remove_srdf_pairs(model, geometry, srdf)
        pairs = {(int(p.first), int(p.second)) for p in geometry.collisionPairs} | set(kept)
        geometry.removeAllCollisionPairs()  # in one order, the queries index them by it
        for first, second in sorted(pairs):
            geometry.addCollisionPair(pin.CollisionPair(first, second))
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
