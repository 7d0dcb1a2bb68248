"""A captured payload rigidly attached to the end effector, written into the URDF.

After capture a client satellite of a few hundred kilograms moves with the end effector. It is
added as a link fixed to the end-effector link (Pinocchio merges it into that body), so the
momentum map, the torques, the planar bounds, verification and playback all see it, and a
plan's URDF carries it. Units: kg, m, kg m^2 (inertia about the payload's own centre of mass,
in the end-effector frame).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import InputError, ModelError
from .model import Robot
from .urdf_shapes import PAYLOAD_LINK

__all__ = ["PAYLOAD_LINK", "Payload", "attach_payload", "check_mass", "held_payload"]


def check_mass(mass: float) -> None:
    """Refuse a payload mass (kg) that is not a finite number > 0 (:class:`InputError`)."""
    if not (math.isfinite(mass) and mass > 0.0):
        raise InputError(f"payload mass must be a finite number > 0 kg, got {mass!r}")


@dataclass(frozen=True)
class Payload:
    """A rigid payload held by the end effector.

    Attributes:
        mass: mass (kg), > 0.
        com_xyz: its centre of mass in the end-effector frame (m).
        inertia: ``[ixx, iyy, izz, ixy, ixz, iyz]`` about its centre of mass (kg m^2); must
            be physical (positive definite, each principal moment at most the sum of the
            other two).
        box: optional collision and visual shape, a box centred on the centre of mass (m).
    """

    mass: float
    com_xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: tuple[float, float, float, float, float, float] = (0.0,) * 6
    box: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        check_mass(self.mass)
        if not all(math.isfinite(v) for v in (*self.com_xyz, *self.inertia)):
            raise InputError("payload com_xyz and inertia must be finite numbers")
        moments = np.linalg.eigvalsh(self.matrix)
        if moments.min() <= 0.0:
            raise InputError(
                "payload inertia is not positive definite (principal moments "
                f"{np.round(moments, 6).tolist()} kg m^2); give [ixx, iyy, izz, ixy, ixz, iyz] "
                "about its centre of mass"
            )
        largest = float(moments.max())
        if largest > float(moments.sum() - largest) * (1.0 + 1e-12):
            raise InputError(
                f"payload inertia breaks the triangle inequality (principal moments "
                f"{np.round(moments, 6).tolist()} kg m^2): no rigid body has it"
            )
        if self.box is not None and not all(math.isfinite(s) and s > 0.0 for s in self.box):
            raise InputError(f"payload box sizes must be finite and > 0 m, got {list(self.box)}")

    @classmethod
    def uniform_box(
        cls,
        mass: float,
        box: tuple[float, float, float],
        com_xyz: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ) -> Payload:
        """A uniform box of ``mass`` (kg) and edges ``box`` (m), centred on its centre of mass.

        Its inertia about the centre of mass is ``m / 12 (y^2 + z^2)`` and so on (kg m^2).
        """
        x, y, z = box
        m = mass / 12.0
        inertia = (m * (y * y + z * z), m * (x * x + z * z), m * (x * x + y * y), 0.0, 0.0, 0.0)
        return cls(mass=mass, com_xyz=com_xyz, inertia=inertia, box=box)

    @property
    def matrix(self) -> np.ndarray:
        """The 3 x 3 inertia matrix about the centre of mass (kg m^2)."""
        ixx, iyy, izz, ixy, ixz, iyz = self.inertia
        return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)


def _xyz(values: tuple[float, ...]) -> str:
    return " ".join(repr(float(v)) for v in values)


def attach_payload(
    text: str, end_effector_link: str, payload: Payload, source_dir: Path | None = None
) -> str:
    """The URDF ``text`` with ``payload`` fixed to ``end_effector_link``.

    Relative mesh file names are made absolute against ``source_dir`` (the folder of the
    original URDF), so the new text can be written anywhere.

    Raises:
        ModelError: the URDF has no such link, or already has a payload link.
    """
    root = ET.fromstring(text)
    if source_dir is not None:
        for mesh in root.iter("mesh"):
            name = mesh.get("filename", "")
            if name and "://" not in name and not Path(name).is_absolute():
                mesh.set("filename", str((source_dir / name).resolve()))
    links = {link.get("name") for link in root.findall("link")}
    if end_effector_link not in links:
        raise ModelError(f"no link {end_effector_link!r} to attach the payload to")
    if PAYLOAD_LINK in links:
        raise ModelError(
            f"the URDF already has a link {PAYLOAD_LINK!r} (a payload composed into it): "
            "drop the scenario's [payload] table, or compose the servicer without --payload-*"
        )
    link = ET.SubElement(root, "link", name=PAYLOAD_LINK)
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz=_xyz(payload.com_xyz), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=repr(float(payload.mass)))
    ixx, iyy, izz, ixy, ixz, iyz = (repr(float(v)) for v in payload.inertia)
    ET.SubElement(inertial, "inertia", ixx=ixx, iyy=iyy, izz=izz, ixy=ixy, ixz=ixz, iyz=iyz)
    if payload.box is not None:
        for kind in ("visual", "collision"):
            element = ET.SubElement(link, kind)
            ET.SubElement(element, "origin", xyz=_xyz(payload.com_xyz), rpy="0 0 0")
            geometry = ET.SubElement(element, "geometry")
            ET.SubElement(geometry, "box", size=_xyz(payload.box))
    joint = ET.SubElement(root, "joint", name=f"{PAYLOAD_LINK}_joint", type="fixed")
    ET.SubElement(joint, "parent", link=end_effector_link)
    ET.SubElement(joint, "child", link=PAYLOAD_LINK)
    ET.SubElement(joint, "origin", xyz="0 0 0", rpy="0 0 0")
    return "<?xml version='1.0' encoding='UTF-8'?>\n" + ET.tostring(root, encoding="unicode")


def held_payload(robot: Robot) -> pin.Inertia | None:
    """The captured payload's inertia in its own link frame, as the robot's URDF states it.

    Mass (kg), centre of mass (m) and inertia about it (kg m^2, turned by the inertial's
    ``rpy`` into the link frame); None when the robot holds none. Pinocchio merges the
    payload's link into the end effector's body, so its values are read from the URDF text
    the robot was loaded from.
    """
    if not any(frame.name == PAYLOAD_LINK for frame in robot.model.frames):
        return None
    try:
        root = ET.fromstring(robot.urdf_text)
    except ET.ParseError:
        return None
    link = next((k for k in root.findall("link") if k.get("name") == PAYLOAD_LINK), None)
    inertial = None if link is None else link.find("inertial")
    if inertial is None:
        return None
    origin, mass, inertia = (inertial.find(tag) for tag in ("origin", "mass", "inertia"))

    def floats(text: str | None) -> np.ndarray:
        return np.array([float(v) for v in (text or "0 0 0").split()])

    com = floats(None if origin is None else origin.get("xyz"))
    rotation = pin.rpy.rpyToMatrix(*floats(None if origin is None else origin.get("rpy")))
    ixx, iyy, izz, ixy, ixz, iyz = (
        float(inertia.get(k, "0")) if inertia is not None else 0.0
        for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
    )
    matrix = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    value = float(mass.get("value", "0")) if mass is not None else 0.0
    return pin.Inertia(value, com, rotation @ matrix @ rotation.T)
