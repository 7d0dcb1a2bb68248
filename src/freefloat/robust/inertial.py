"""Inertial values of URDF links: read them, change them, keep them physical.

A link's ``<inertial>`` holds its mass (kg), the position of its centre of mass in the link
frame (``origin xyz``, m) and its rotational inertia about that centre of mass (kg m^2, in the
frame of ``origin rpy``). This module names those values by dotted keys, as sweeps do:

    mass, com.0, com.1, com.2, inertia.ixx, inertia.iyy, inertia.izz, inertia.ixy,
    inertia.ixz, inertia.iyz

and writes a URDF text with new values for named links (:func:`with_inertials`), or changes a
loaded robot's model the same way (:func:`perturbed_robot`), refusing any value no rigid body
can have (a non-positive mass, an inertia that is not positive definite or
breaks the triangle inequality of its principal moments). The robot's other content is kept.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from ..errors import InputError, ModelError, UnknownNameError
from ..files import read_text_file
from ..robot.model import MAX_URDF_BYTES, Robot
from ..robot.payload import PAYLOAD_LINK

__all__ = [
    "INERTIA_KEYS",
    "PARAMETERS",
    "LinkInertial",
    "check_physical",
    "link_inertials",
    "perturbed_robot",
    "robot_text",
    "with_inertials",
]

#: The six inertia components, in the order of :attr:`LinkInertial.inertia`.
INERTIA_KEYS = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
#: Every inertial value a key can name (units: kg, m, kg m^2).
PARAMETERS = ("mass", "com.0", "com.1", "com.2", *(f"inertia.{k}" for k in INERTIA_KEYS))


@dataclass(frozen=True)
class LinkInertial:
    """The inertial values of one URDF link.

    Attributes:
        link: the link's name.
        mass: mass (kg).
        com: centre of mass in the link frame (m).
        rpy: orientation of the inertia's frame in the link frame (rad).
        inertia: ``(ixx, iyy, izz, ixy, ixz, iyz)`` about the centre of mass (kg m^2).
    """

    link: str
    mass: float
    com: tuple[float, float, float]
    rpy: tuple[float, float, float]
    inertia: tuple[float, float, float, float, float, float]

    def value(self, key: str) -> float:
        """The value a key of :data:`PARAMETERS` names (kg, m or kg m^2)."""
        if key == "mass":
            return self.mass
        if key.startswith("com."):
            return self.com[int(key[4:])]
        return self.inertia[INERTIA_KEYS.index(key.removeprefix("inertia."))]

    def with_value(self, key: str, value: float) -> LinkInertial:
        """A copy with ``key`` set to ``value`` (kg, m or kg m^2)."""
        if key == "mass":
            return replace(self, mass=float(value))
        if key.startswith("com."):
            com = list(self.com)
            com[int(key[4:])] = float(value)
            return replace(self, com=(com[0], com[1], com[2]))
        inertia = list(self.inertia)
        inertia[INERTIA_KEYS.index(key.removeprefix("inertia."))] = float(value)
        return replace(self, inertia=tuple(inertia))  # type: ignore[arg-type]

    @property
    def matrix(self) -> np.ndarray:
        """The 3 x 3 inertia about the centre of mass (kg m^2, in the inertia's frame)."""
        ixx, iyy, izz, ixy, ixz, iyz = self.inertia
        return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


def check_physical(inertial: LinkInertial) -> None:
    """Refuse inertial values no rigid body has.

    Raises:
        InputError: a mass that is not finite and > 0, non-finite values, an inertia that is not
            positive definite, or principal moments that break the triangle inequality (each at
            most the sum of the other two).
    """
    name = inertial.link
    if not (math.isfinite(inertial.mass) and inertial.mass > 0.0):
        raise InputError(f"link {name!r}: mass must be a finite number > 0 kg, got {inertial.mass}")
    if not all(math.isfinite(v) for v in (*inertial.com, *inertial.inertia)):
        raise InputError(f"link {name!r}: centre of mass and inertia must be finite numbers")
    moments = np.linalg.eigvalsh(inertial.matrix)
    if moments.min() <= 0.0:
        raise InputError(
            f"link {name!r}: inertia not positive definite (principal moments "
            f"{np.round(moments, 9).tolist()} kg m^2); no rigid body has it"
        )
    largest = float(moments.max())
    if largest > float(moments.sum() - largest) * (1.0 + 1e-12):
        raise InputError(
            f"link {name!r}: principal moments {np.round(moments, 9).tolist()} kg m^2 break the "
            "triangle inequality (each must be at most the sum of the other two)"
        )


def _floats(text: str | None, count: int, default: float = 0.0) -> tuple[float, ...]:
    if text is None:
        return (default,) * count
    values = tuple(float(v) for v in text.split())
    if len(values) != count:
        raise ModelError(f"expected {count} numbers, got {text!r}")
    return values


def link_inertials(text: str) -> dict[str, LinkInertial]:
    """The inertial values of every URDF link that has an ``<inertial>``, by link name."""
    out = {}
    for link in ET.fromstring(text).findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        origin = inertial.find("origin")
        mass = inertial.find("mass")
        inertia = inertial.find("inertia")
        com = _floats(None if origin is None else origin.get("xyz"), 3)
        rpy = _floats(None if origin is None else origin.get("rpy"), 3)
        moments = tuple(
            float(inertia.get(k, "0")) if inertia is not None else 0.0 for k in INERTIA_KEYS
        )
        name = str(link.get("name"))
        out[name] = LinkInertial(
            link=name,
            mass=float(mass.get("value", "0")) if mass is not None else 0.0,
            com=(com[0], com[1], com[2]),
            rpy=(rpy[0], rpy[1], rpy[2]),
            inertia=moments,  # type: ignore[arg-type]
        )
    return out


def _check_key(key: str) -> None:
    if key not in PARAMETERS:
        raise UnknownNameError("inertial value", key, PARAMETERS)


def _link_named(given: str, current: Mapping[str, object]) -> str:
    """The link ``given`` names among those with inertial values (``"payload"``: the payload's).

    Raises:
        InputError: ``"payload"`` on a robot that holds none.
        UnknownNameError: another name of no such link (naming the valid ones).
    """
    name = PAYLOAD_LINK if given == "payload" else given
    if name in current:
        return name
    if given == "payload":
        raise InputError(
            "payload keys need a robot that holds a captured payload ([payload] in the "
            "scenario, or freefloat compose --payload-mass); this one holds none"
        )
    raise UnknownNameError("link with inertial values", given, sorted(current))


def with_inertials(text: str, changes: Mapping[str, Mapping[str, float]]) -> str:
    """The URDF ``text`` with new inertial values for named links.

    Args:
        text: a URDF.
        changes: ``{link: {key: value}}`` with keys of :data:`PARAMETERS` (kg, m, kg m^2);
            ``"payload"`` names the captured payload's link.

    Raises:
        UnknownNameError: a link without ``<inertial>`` or an unknown key (naming the valid ones).
        InputError: the new values are not physical (:func:`check_physical`).
    """
    root = ET.fromstring(text)
    current = link_inertials(text)
    links = {str(link.get("name")): link for link in root.findall("link")}
    for given, values in changes.items():
        name = _link_named(given, current)
        inertial = current[name]
        for key, value in values.items():
            _check_key(key)
            inertial = inertial.with_value(key, value)
        check_physical(inertial)
        element = links[name].find("inertial")
        assert element is not None
        origin = element.find("origin")
        if origin is None:
            origin = ET.SubElement(element, "origin", rpy="0 0 0")
        origin.set("xyz", " ".join(repr(v) for v in inertial.com))
        mass = element.find("mass")
        if mass is None:
            mass = ET.SubElement(element, "mass")
        mass.set("value", repr(inertial.mass))
        inertia = element.find("inertia")
        if inertia is None:
            inertia = ET.SubElement(element, "inertia")
        for key, value in zip(INERTIA_KEYS, inertial.inertia, strict=True):
            inertia.set(key, repr(value))
    return "<?xml version='1.0' encoding='UTF-8'?>\n" + ET.tostring(root, encoding="unicode")


def robot_text(robot: Robot) -> str:
    """The URDF text a robot was loaded from (read from its file for one loaded without it).

    The text, not the file as it is now: the file may have changed since.
    """
    return robot.urdf_text or read_text_file(robot.urdf, "URDF", MAX_URDF_BYTES, ModelError)


def _spatial_inertia(inertial: LinkInertial) -> pin.Inertia:
    """The link's inertia in its own frame, as Pinocchio's URDF parser builds it."""
    rotation = pin.rpy.rpyToMatrix(*inertial.rpy)
    return pin.Inertia(
        inertial.mass, np.array(inertial.com), rotation @ inertial.matrix @ rotation.T
    )


def perturbed_robot(
    robot: Robot, changes: Mapping[str, Mapping[str, float]], text: str | None = None
) -> Robot:
    """The robot with new inertial values for named links (see :func:`with_inertials`).

    Pinocchio merges a link joined by fixed joints into the body of its parent joint; a
    body's dynamic parameters are linear in its links' inertias, so the link's old
    contribution is replaced by its new one in a copy of the model (no re-parsing; a test
    holds it to Pinocchio's parser of the changed URDF). ``text`` is the robot's URDF when
    already read. The new robot keeps the file's path (for its meshes) and end effector.

    Raises:
        UnknownNameError: a link without ``<inertial>`` or an unknown key.
        InputError: the new values are not physical (:func:`check_physical`).
    """
    current = link_inertials(robot_text(robot) if text is None else text)
    model = robot.model.copy()
    for given, values in changes.items():
        name = _link_named(given, current)
        inertial = current[name]
        for key, value in values.items():
            _check_key(key)
            inertial = inertial.with_value(key, value)
        check_physical(inertial)
        frame = model.frames[model.getFrameId(name, pin.FrameType.BODY)]
        before = frame.placement.act(_spatial_inertia(current[name])).toDynamicParameters()
        after = frame.placement.act(_spatial_inertia(inertial)).toDynamicParameters()
        body = model.inertias[frame.parentJoint].toDynamicParameters()
        model.inertias[frame.parentJoint] = pin.Inertia.FromDynamicParameters(body - before + after)
    return replace(robot, model=model)
