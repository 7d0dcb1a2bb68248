"""The arms of a servicer: where each comes from, how it is mounted, renamed and locked.

An arm is an ``example-robot-data`` arm by name (:data:`ARMS`) or any URDF file. Each arm's
links and joints may be renamed with a prefix (several arms on one spacecraft); its gripper and
finger joints are locked (fixed at 0, or at the middle of their range when 0 is outside it) unless
kept, and further joints locked at the values asked for. Angles in rad, lengths in m.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, LockedJointError, ModelError, UnknownNameError
from ..files import absolute_path, read_text_file
from .designed_bodies import LOCKED_ATTRIBUTE
from .lock import default_lock, locked_origin
from .model import MAX_URDF_BYTES, example_robot_data_dir
from .urdf_checks import urdf_document

__all__ = [
    "ARMS",
    "BASE_LINK",
    "GRIPPER_JOINT",
    "ArmPart",
    "ArmSpec",
    "arm_part",
    "arm_urdf",
    "mount_origin",
]

#: example-robot-data arms by name: path of the URDF below ``example-robot-data/robots``.
ARMS = {
    "panda": "panda_description/urdf/panda.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "xarm7": "xarm_description/urdf/xarm7.urdf",
    "z1": "z1_description/urdf/z1.urdf",
}

#: Names of the joints a composed arm locks unless it keeps its gripper (fingers, grippers).
GRIPPER_JOINT = re.compile(r"finger|gripper", re.IGNORECASE)
BASE_LINK = "spacecraft"


def arm_urdf(arm: str | Path) -> Path:
    """Path of an arm's URDF: an example-robot-data arm name or a URDF file path."""
    text = str(arm)
    if text in ARMS:
        share = example_robot_data_dir()
        if share is None:
            raise ModelError(
                f"arm {text!r} needs the example-robot-data package: pip install example-robot-data"
            )
        return share / "example-robot-data" / "robots" / ARMS[text]
    path = Path(text).expanduser()
    if path.suffix.lower() != ".urdf" and not path.exists():
        raise UnknownNameError("arm", text, [*ARMS, "or a path to a .urdf file"])
    read_text_file(path, "arm URDF", MAX_URDF_BYTES, ModelError)  # a regular file, not huge
    return absolute_path(path, "arm URDF", ModelError)


@dataclass(frozen=True)
class ArmSpec:
    """One more arm of a servicer (SI units; angles in rad).

    Attributes:
        arm: example-robot-data arm name or URDF path.
        mount: arm root position in the spacecraft frame (m).
        mount_rpy: arm root roll, pitch, yaw in the spacecraft frame (rad).
        prefix: put before each of its link and joint names; default ``armK_`` (K = 1, 2...).
        lock: joints of this arm to lock: a name (locked at 0, or at the middle of its range
            when 0 is outside it) or ``(name, value)`` (rad or m).
        keep_gripper: keep gripper and finger joints movable.
    """

    arm: str
    mount: tuple[float, ...] = (0.0, 0.0, 0.0)
    mount_rpy: tuple[float, ...] = (0.0, 0.0, 0.0)
    prefix: str = ""
    lock: tuple[str | tuple[str, float], ...] = ()
    keep_gripper: bool = False

    def __post_init__(self) -> None:
        if any(c.isspace() or not c.isprintable() for c in self.prefix):
            raise InputError(
                f"arm prefix {self.prefix!r}: a space, a line break or a control character "
                "would break the names it starts; give letters, digits or '_'"
            )


def mount_origin(xyz: Sequence[float], rpy: Sequence[float]) -> np.ndarray:
    """The 4 x 4 transform of a mount at ``xyz`` (m) with roll, pitch, yaw ``rpy`` (rad)."""
    roll, pitch, yaw = rpy
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    out = np.eye(4)
    out[:3, :3] = np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )
    out[:3, 3] = xyz
    return out


@dataclass(frozen=True)
class ArmPart:
    """One arm's links, joints (mount first) and materials, renamed and locked.

    ``locked``: the joints locked now, with their values (rad or m); ``marked``: those its
    URDF already marks as locked by freefloat (:data:`~.designed_bodies.LOCKED_ATTRIBUTE`).
    """

    links: list[Any]
    joints: list[Any]
    materials: list[Any]
    locked: dict[str, float]
    notes: list[str]
    prismatic: set[str]
    marked: dict[str, float]


def arm_part(arm: ArmSpec) -> ArmPart:
    """The arm read from its URDF, renamed with its prefix, its joints locked, and its mount.

    Raises:
        ModelError: the URDF cannot be read, has no single root link, or already has a link
            named like the spacecraft.
        UnknownNameError: a joint to lock is not in the arm.
        LockedJointError: a value outside the joint's limits.
    """
    import yourdfpy

    source = arm_urdf(arm.arm)
    try:  # one clear line for what is no URDF, before yourdfpy's parser says more
        document = urdf_document(read_text_file(source, "arm URDF", MAX_URDF_BYTES, ModelError))
    except ModelError as exc:
        raise ModelError(f"cannot read arm URDF {source}: {exc}") from None
    marked = _marked(document, arm.prefix, source)  # yourdfpy drops the marks
    try:
        loaded = yourdfpy.URDF.load(
            str(source),
            build_scene_graph=False,
            load_meshes=False,
            filename_handler=yourdfpy.filename_handler_null,  # meshes are referenced, not read
        )
    except Exception as exc:
        raise ModelError(f"cannot read arm URDF {source}: {exc}") from None
    robot = loaded.robot
    if any(link.name == BASE_LINK for link in robot.links):
        raise ModelError(f"the arm already has a link named {BASE_LINK!r}")
    values, notes = _lock_values(arm, robot.joints)
    prefix = arm.prefix
    prismatic = {prefix + j.name for j in robot.joints if j.type == "prismatic"} & set(values)
    joints = []
    for joint in robot.joints:
        joint = replace(
            joint,
            name=prefix + joint.name,
            parent=prefix + joint.parent,
            child=prefix + joint.child,
        )
        if joint.name in values:
            origin = joint.origin if joint.origin is not None else np.eye(4)
            axis = joint.axis if joint.axis is not None else (1.0, 0.0, 0.0)
            joint = replace(
                joint,
                type="fixed",
                origin=locked_origin(origin, joint.type, axis, values[joint.name]),
                limit=None,
                mimic=None,
                axis=None,
                dynamics=None,
                safety_controller=None,
                calibration=None,
            )
        elif joint.mimic is not None:  # the composed URDF would lose it: the arm moves apart
            raise ModelError(
                f"arm joint {joint.name.removeprefix(prefix)!r} mimics "
                f"{joint.mimic.joint!r}: mimic joints are not supported (freefloat moves every "
                "joint on its own path); lock it (--lock), or make it fixed in the arm's URDF"
            )
        joints.append(joint)
    links = []
    for link in robot.links:
        visuals = [_absolute_mesh(v, source.parent) for v in link.visuals]
        collisions = [_absolute_mesh(c, source.parent) for c in link.collisions]
        links.append(replace(link, name=prefix + link.name, visuals=visuals, collisions=collisions))
    roots = [link.name for link in links if link.name not in {j.child for j in joints}]
    if not roots:
        raise ModelError(
            f"arm URDF {source}: closed loop: every link has a parent joint; a tree needs "
            "exactly one root link"
        )
    if len(roots) != 1:
        raise ModelError(f"arm URDF {source} must have one root link, found {roots}")
    mount = yourdfpy.Joint(
        name=prefix + "mount",
        type="fixed",
        parent=BASE_LINK,
        child=roots[0],
        origin=mount_origin(arm.mount, arm.mount_rpy),
    )
    return ArmPart(links, [mount, *joints], list(robot.materials), values, notes, prismatic, marked)


def _marked(document: Any, prefix: str, source: Path) -> dict[str, float]:
    """``{prefixed joint: value}`` (rad or m) of the joints the URDF marks as locked.

    Raises:
        ModelError: a mark that is not a number.
    """
    marked = {}
    for joint in document.findall("joint"):
        value = joint.get(LOCKED_ATTRIBUTE)
        if value is not None:
            try:
                marked[prefix + str(joint.get("name"))] = float(value)
            except ValueError:
                raise ModelError(
                    f"arm URDF {source}: joint {joint.get('name')!r} has {LOCKED_ATTRIBUTE}="
                    f"{value!r}, not a number (rad or m)"
                ) from None
    return marked


def _lock_values(arm: ArmSpec, joints: Sequence[Any]) -> tuple[dict[str, float], list[str]]:
    """``{prefixed name: value}`` (rad or m) of the arm's joints to lock, and what was chosen.

    Raises:
        UnknownNameError: a name to lock is not a joint of the arm.
        LockedJointError: a value outside the joint's limits.
    """
    movable = {j.name: j for j in joints if j.type in ("revolute", "continuous", "prismatic")}
    asked: dict[str, float | None] = dict(
        (item, None) if isinstance(item, str) else (item[0], float(item[1])) for item in arm.lock
    )
    values: dict[str, float] = {}
    notes: list[str] = []
    for name, value in asked.items():
        if name not in movable:  # a fixed joint is no joint to lock: only movable ones listed
            raise UnknownNameError("movable joint to lock", name, list(movable))
        joint = movable[name]
        low, high = _range(joint)
        if value is None:  # no value asked: 0, or the middle of a range without it
            values[arm.prefix + name] = _default_lock(f"joint {arm.prefix + name!r}", joint, notes)
            continue
        if not low <= value <= high:
            scale, unit = (1.0, "m") if joint.type == "prismatic" else (180 / math.pi, "deg")
            shown = (value * scale, low * scale, high * scale)
            raise LockedJointError(arm.prefix + name, *shown, unit)
        values[arm.prefix + name] = value
    fingers = (
        [] if arm.keep_gripper else [j for j in movable.values() if GRIPPER_JOINT.search(j.name)]
    )
    for joint in fingers:
        if joint.name not in asked:
            values[arm.prefix + joint.name] = _default_lock(
                f"finger joint {arm.prefix + joint.name!r}", joint, notes
            )
    for joint in movable.values():  # a follower of a locked joint is locked with it
        target = None if joint.mimic is None else arm.prefix + joint.mimic.joint
        if target in values and arm.prefix + joint.name not in values:
            multiplier = float(joint.mimic.multiplier or 1.0)
            offset = float(joint.mimic.offset or 0.0)
            values[arm.prefix + joint.name] = multiplier * values[target] + offset
    return values, notes


def _range(joint: Any) -> tuple[float, float]:
    """A movable joint's position limits (rad or m; infinite for a continuous one)."""
    if joint.type != "continuous" and joint.limit is not None:
        return float(joint.limit.lower), float(joint.limit.upper)
    return -math.inf, math.inf


def _default_lock(label: str, joint: Any, notes: list[str]) -> float:
    """Where a joint locked without a value is fixed (rad or m): :func:`default_lock`.

    Away from 0, ``notes`` gets its line, ``label`` naming the joint.
    """
    value, note = default_lock(label, joint.type, *_range(joint))
    if note:
        notes.append(note)
    return value


def _absolute_mesh(element: Any, folder: Path) -> Any:
    """Make a relative mesh filename absolute (``package://`` references stay)."""
    geometry = element.geometry
    if geometry is None or geometry.mesh is None:
        return element
    name = geometry.mesh.filename
    if "://" in name or Path(name).is_absolute():
        return element
    mesh = replace(geometry.mesh, filename=str((folder / name).resolve()))
    return replace(element, geometry=replace(geometry, mesh=mesh))
