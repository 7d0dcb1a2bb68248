"""Compose a servicer: mount a robot arm on a box spacecraft and write one validated URDF.

The arm is an ``example-robot-data`` arm by name (:data:`ARMS`) or any URDF file. The new root
link ``spacecraft`` is a uniform box (mass in kg, size in m; inertia in kg m^2 from the box
unless given); a fixed joint ``mount`` places the arm's root link at ``mount`` (m) with
roll-pitch-yaw ``mount_rpy`` (rad) in the spacecraft frame. Gripper and finger joints are locked
(made fixed at their zero position) by default. Mesh references stay ``package://`` (resolved
at load time against ``example-robot-data``'s share folder) or become absolute paths for a URDF
given by path. yourdfpy builds, validates and writes the result. An optional captured payload
(:class:`~freefloat.robot.payload.Payload`) is then fixed to the composed robot's default end
effector (link ``captured_payload``); :func:`payload_parent` names that link, so the payload
link never becomes the end effector (``load_robot(path, payload_parent(text))``).
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, ModelError, UnknownNameError
from ..files import absolute_path, atomic_write_text, read_text_file
from .model import MAX_URDF_BYTES, example_robot_data_dir
from .payload import PAYLOAD_LINK, Payload

LOGGER = logging.getLogger(__name__)

__all__ = [
    "ARMS",
    "ServicerSpec",
    "arm_urdf",
    "compose_servicer",
    "compose_servicer_text",
    "payload_parent",
    "resolve_mesh",
]

#: example-robot-data arms by name: path of the URDF below ``example-robot-data/robots``.
ARMS = {
    "panda": "panda_description/urdf/panda.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "xarm7": "xarm_description/urdf/xarm7.urdf",
    "z1": "z1_description/urdf/z1.urdf",
}

_GRIPPER = re.compile(r"finger|gripper", re.IGNORECASE)
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
class ServicerSpec:
    """What to compose (SI units; angles in rad).

    Attributes:
        arm: example-robot-data arm name or URDF path.
        base_mass: spacecraft mass (kg), > 0.
        base_size: spacecraft box edges x, y, z (m), > 0.
        mount: arm root position in the spacecraft frame (m).
        mount_rpy: arm root roll, pitch, yaw in the spacecraft frame (rad).
        base_inertia: principal moments Ixx, Iyy, Izz (kg m^2); default: the uniform box's.
        lock: extra joints to lock (make fixed at zero).
        keep_gripper: keep gripper and finger joints movable.
        payload: a captured payload fixed to the end effector (validated by ``Payload``).
    """

    arm: str
    base_mass: float
    base_size: tuple[float, ...]
    mount: tuple[float, ...] = (0.0, 0.0, 0.0)
    mount_rpy: tuple[float, ...] = (0.0, 0.0, 0.0)
    base_inertia: tuple[float, ...] | None = None
    lock: tuple[str, ...] = field(default_factory=tuple)
    keep_gripper: bool = False
    payload: Payload | None = None

    def __post_init__(self) -> None:
        numbers = [self.base_mass, *self.base_size, *self.mount, *self.mount_rpy]
        numbers += list(self.base_inertia or ())
        if not all(isinstance(x, (int, float)) and math.isfinite(x) for x in numbers):
            raise InputError("servicer numbers must be finite (mass, size, mount, inertia)")
        if len(self.base_size) != 3 or len(self.mount) != 3 or len(self.mount_rpy) != 3:
            raise InputError("base size, mount and mount rpy take three numbers each")
        if self.base_mass <= 0:
            raise InputError(f"base mass must be > 0 kg, got {self.base_mass:g}")
        if min(self.base_size) <= 0:
            raise InputError(f"base size must be > 0 m on each axis, got {list(self.base_size)}")
        if self.base_inertia is not None:
            ixx, iyy, izz = self.base_inertia
            if min(ixx, iyy, izz) <= 0 or ixx + iyy < izz or iyy + izz < ixx or ixx + izz < iyy:
                raise InputError(
                    f"base inertia {list(self.base_inertia)} kg m^2 is not physical: each moment "
                    "must be > 0 and no larger than the sum of the other two"
                )

    @property
    def inertia(self) -> tuple[float, float, float]:
        """Principal moments of the spacecraft (kg m^2)."""
        if self.base_inertia is not None:
            return (
                float(self.base_inertia[0]),
                float(self.base_inertia[1]),
                float(self.base_inertia[2]),
            )
        x, y, z = self.base_size
        m = self.base_mass / 12.0
        return (m * (y * y + z * z), m * (x * x + z * z), m * (x * x + y * y))

    def key(self) -> str:
        """A short hash of the spec and the arm file (for cache file names)."""
        payload = json.dumps([self.__dict__, arm_urdf(self.arm).read_text()], default=str)
        return hashlib.sha256(payload.encode()).hexdigest()[:16]


def _origin(xyz: Sequence[float], rpy: Sequence[float]) -> np.ndarray:
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


def compose_servicer(spec: ServicerSpec, output: str | Path) -> Path:
    """Compose the servicer, validate it with yourdfpy and write it atomically to ``output``.

    Raises:
        ModelError: the arm URDF cannot be read, or the result does not validate.
        UnknownNameError: a joint to lock is not in the arm (lists the arm's joints).
        InputError: bad numbers in ``spec``.
    """
    text = compose_servicer_text(spec)
    return atomic_write_text(output, text)


def compose_servicer_text(spec: ServicerSpec) -> str:
    """Compose the servicer and validate it with yourdfpy; return the URDF text (no file).

    Raises:
        ModelError: the arm URDF cannot be read, or the result does not validate.
        UnknownNameError: a joint to lock is not in the arm (lists the arm's joints).
        InputError: bad numbers in ``spec``.
    """
    import yourdfpy

    source = arm_urdf(spec.arm)
    try:
        arm = yourdfpy.URDF.load(
            str(source),
            build_scene_graph=False,
            load_meshes=False,
            filename_handler=yourdfpy.filename_handler_null,  # meshes are referenced, not read
        )
    except Exception as exc:
        raise ModelError(f"cannot read arm URDF {source}: {exc}") from None
    robot = arm.robot
    names = [j.name for j in robot.joints]
    for name in spec.lock:
        if name not in names:
            raise UnknownNameError("joint to lock", name, names)
    if any(link.name == BASE_LINK for link in robot.links):
        raise ModelError(f"the arm already has a link named {BASE_LINK!r}")

    joints = _locked_joints(robot, spec)

    links = []
    for link in robot.links:
        visuals = [_absolute_mesh(v, source.parent) for v in link.visuals]
        collisions = [_absolute_mesh(c, source.parent) for c in link.collisions]
        links.append(replace(link, visuals=visuals, collisions=collisions))

    roots = [link.name for link in robot.links if link.name not in {j.child for j in joints}]
    if len(roots) != 1:
        raise ModelError(f"arm URDF {source} must have one root link, found {roots}")
    spacecraft, hull = _spacecraft(spec)
    mount = yourdfpy.Joint(
        name="mount",
        type="fixed",
        parent=BASE_LINK,
        child=roots[0],
        origin=_origin(spec.mount, spec.mount_rpy),
    )
    arm_name = spec.arm if spec.arm in ARMS else Path(spec.arm).stem
    composed = yourdfpy.Robot(
        name=f"{arm_name}_servicer",
        links=[spacecraft, *links],
        joints=[mount, *joints],
        materials=[hull, *robot.materials],
    )
    urdf = yourdfpy.URDF(
        robot=composed,
        build_scene_graph=False,
        load_meshes=False,
        filename_handler=yourdfpy.filename_handler_null,
    )
    missing = sorted({name for name in _mesh_names(composed) if resolve_mesh(name) is None})
    if missing:  # the dynamics do not need them; playback draws such links as simple shapes
        LOGGER.warning(
            "%d mesh file(s) of the arm cannot be found (e.g. %s); the servicer is composed "
            "and plans, and playback draws those links as simple shapes",
            len(missing),
            missing[0],
        )
    if not urdf.validate():
        errors = "; ".join(str(e) for e in getattr(urdf, "errors", []))
        raise ModelError(f"the composed URDF does not validate: {errors or 'unknown error'}")

    from lxml import etree  # yourdfpy's own XML library

    body = etree.tostring(urdf.write_xml(), pretty_print=True, encoding="unicode")
    text = "<?xml version='1.0' encoding='UTF-8'?>\n" + body
    if spec.payload is None:
        return text
    from .model import load_robot
    from .payload import attach_payload

    # The default end effector of the servicer without the payload holds it.
    end_effector = load_robot(source.parent / f"{arm_name}_servicer.urdf", text=text).end_effector
    return attach_payload(text, end_effector, spec.payload)


def _locked_joints(robot: Any, spec: ServicerSpec) -> list[Any]:
    """The arm's joints, those locked by ``spec`` (and the gripper's, unless kept) fixed."""
    locked = set(spec.lock)
    if not spec.keep_gripper:
        locked |= {j.name for j in robot.joints if j.type != "fixed" and _GRIPPER.search(j.name)}
    joints = []
    for joint in robot.joints:
        if joint.name in locked:
            joint = replace(
                joint,
                type="fixed",
                limit=None,
                mimic=None,
                axis=None,
                dynamics=None,
                safety_controller=None,
                calibration=None,
            )
        elif joint.mimic is not None and joint.mimic.joint in locked:
            joint = replace(joint, mimic=None)
        joints.append(joint)
    return joints


def _spacecraft(spec: ServicerSpec) -> tuple[Any, Any]:
    """The spacecraft link (a box hull of ``base_size`` m, ``base_mass`` kg) and its material."""
    import yourdfpy

    ixx, iyy, izz = spec.inertia
    box = yourdfpy.Geometry(box=yourdfpy.Box(size=np.array(spec.base_size, dtype=float)))
    hull = yourdfpy.Material(
        name="freefloat_hull", color=yourdfpy.Color(rgba=np.array([0.78, 0.78, 0.82, 1.0]))
    )
    spacecraft = yourdfpy.Link(
        name=BASE_LINK,
        inertial=yourdfpy.Inertial(
            origin=np.eye(4), mass=float(spec.base_mass), inertia=np.diag([ixx, iyy, izz])
        ),
        visuals=[yourdfpy.Visual(name="hull", origin=np.eye(4), geometry=box, material=hull)],
        collisions=[yourdfpy.Collision(name="hull", origin=np.eye(4), geometry=box)],
    )
    return spacecraft, hull


def payload_parent(text: str) -> str | None:
    """The link a URDF's captured payload is fixed to (its end effector), or None if none."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(text)
    except ET.ParseError:
        return None
    for joint in root.findall("joint"):
        child, parent = joint.find("child"), joint.find("parent")
        if child is not None and parent is not None and child.get("link") == PAYLOAD_LINK:
            return parent.get("link")
    return None


def _mesh_names(robot: Any) -> list[str]:
    return [
        element.geometry.mesh.filename
        for link in robot.links
        for element in (*link.visuals, *link.collisions)
        if element.geometry is not None and element.geometry.mesh is not None
    ]


def resolve_mesh(name: str) -> Path | None:
    """Absolute path of a mesh reference (``package://`` via example-robot-data), or None."""
    if name.startswith("package://"):
        share = example_robot_data_dir()
        path = share / name[len("package://") :] if share else None
    elif name.startswith("file://"):
        path = Path(name[len("file://") :])
    else:
        path = Path(name)
    return path if path is not None and path.is_file() else None


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
