"""The robot's visuals as its URDF states them, placed on the joints of its Pinocchio model.

Read from the URDF text with the standard XML parser, not loaded: a mesh file is named, found
and checked to exist, but not parsed (Pinocchio's ``buildGeomFromUrdf`` loads every visual mesh
into collision structures, about 0.5 s for the Panda's COLLADA files, which a drawing never
uses). Each ``<visual>`` of a link becomes one :class:`Visual` named as Pinocchio names it
(``<link>_<k>``, k counting the link's visuals from 0), carried by the joint of the link's body
frame at the frame's placement composed with the visual's ``<origin>``. Its colour is the
``<material>``'s ``<color>``, or the colour of the robot-level material of that name; without
one, none is stated. A mesh reference is found as ``package://`` in the robot's package folders
(and example-robot-data's), as a ``file://`` or absolute path, or relative to the URDF; a mesh
that cannot be found, or is not a file the viewer reads (:data:`DRAWN_FORMATS`), is drawn as a
small sphere (:data:`MISSING_MESH_RADIUS`), with one warning for the robot.
"""

from __future__ import annotations

import logging
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ViewerError
from ..robot.model import Robot, example_robot_data_dir

__all__ = ["MISSING_MESH_RADIUS", "Visual", "visual_model"]

LOGGER = logging.getLogger(__name__)

#: Radius (m) of the sphere drawn for a link whose mesh file cannot be found.
MISSING_MESH_RADIUS = 0.04
#: The mesh files the page's viewer reads (file name endings, lower case).
DRAWN_FORMATS = (".stl", ".obj", ".dae")
#: The colour a visual without a material is drawn in (RGBA, Pinocchio's default).
DEFAULT_RGBA = (0.9, 0.9, 0.9, 1.0)


@dataclass(frozen=True)
class Visual:
    """One visual of the URDF.

    Attributes:
        name: ``<link>_<k>``.
        joint: the Pinocchio joint that carries it.
        placement: its frame in the joint's frame (m).
        shape: ``"box"``, ``"sphere"``, ``"cylinder"``, ``"capsule"`` or ``"mesh"``.
        size: box edge lengths (x, y, z); sphere radius; cylinder or capsule radius and length
            (m); empty for a mesh.
        mesh: the mesh file, for ``"mesh"``.
        scale: the mesh's scale per axis.
        rgba: the URDF's colour, or None when it states none.
    """

    name: str
    joint: int
    placement: pin.SE3
    shape: str
    size: tuple[float, ...] = ()
    mesh: Path | None = None
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    rgba: tuple[float, float, float, float] | None = None


def visual_model(robot: Robot) -> list[Visual]:
    """Every visual of the robot's URDF, in link order (a missing mesh: a sphere, warned).

    Raises:
        ViewerError: the URDF cannot be read, or states a visual that cannot be drawn.
    """
    try:
        root = ET.fromstring(robot.urdf_text or Path(robot.urdf).read_text(encoding="utf-8"))
    except (OSError, ET.ParseError) as exc:
        raise ViewerError(f"cannot read the visuals of {robot.urdf}: {exc}") from None
    colours = {
        m.get("name", ""): _rgba(m) for m in root.findall("material") if _rgba(m) is not None
    }
    model = robot.model
    out: list[Visual] = []
    missing: list[str] = []
    for link in root.findall("link"):
        name = link.get("name", "")
        if not model.existFrame(name, pin.FrameType.BODY):
            continue
        frame = model.frames[model.getFrameId(name, pin.FrameType.BODY)]
        for k, element in enumerate(link.findall("visual")):
            placement = frame.placement * _origin(element.find("origin"))
            drawn = _geometry(element.find("geometry"), robot, f"{name}_{k}", missing)
            material = element.find("material")
            rgba = None
            if material is not None:
                rgba = _rgba(material) or colours.get(material.get("name", ""))
            out.append(Visual(f"{name}_{k}", int(frame.parentJoint), placement, *drawn, rgba))
    if missing:
        LOGGER.warning(
            "%d mesh file(s) of %s cannot be found or are not STL, OBJ or COLLADA files (e.g. "
            "%s); those links are drawn as spheres of %g m",
            len(missing),
            Path(robot.urdf).name,
            missing[0],
            MISSING_MESH_RADIUS,
        )
    return out


def _rgba(material: ET.Element) -> tuple[float, float, float, float] | None:
    """A ``<material>``'s ``<color rgba>``, or None."""
    colour = material.find("color")
    if colour is None or colour.get("rgba") is None:
        return None
    values = [float(x) for x in str(colour.get("rgba")).split()]
    if len(values) != 4:
        return None
    return (values[0], values[1], values[2], values[3])


def _numbers(text: str | None, default: tuple[float, ...]) -> tuple[float, ...]:
    return tuple(float(x) for x in text.split()) if text else default


def _origin(element: ET.Element | None) -> pin.SE3:
    """An ``<origin xyz rpy>`` as a placement (m, rad; URDF's fixed-axis roll, pitch, yaw)."""
    if element is None:
        return pin.SE3.Identity()
    xyz = _numbers(element.get("xyz"), (0.0, 0.0, 0.0))
    rpy = _numbers(element.get("rpy"), (0.0, 0.0, 0.0))
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.array(xyz))


def _geometry(
    element: ET.Element | None, robot: Robot, name: str, missing: list[str]
) -> tuple[str, tuple[float, ...], Path | None, tuple[float, float, float]]:
    """(shape, size, mesh, scale) of a ``<geometry>``; a missing mesh becomes a sphere."""
    shape = next(iter(element), None) if element is not None else None
    if shape is None:
        raise ViewerError(f"the visual {name!r} states no geometry")
    one = (1.0, 1.0, 1.0)
    if shape.tag == "box":
        return "box", _numbers(shape.get("size"), (0.0, 0.0, 0.0)), None, one
    if shape.tag == "sphere":
        return "sphere", (float(shape.get("radius", 0.0)),), None, one
    if shape.tag in ("cylinder", "capsule"):
        size = (float(shape.get("radius", 0.0)), float(shape.get("length", 0.0)))
        return shape.tag, size, None, one
    if shape.tag == "mesh":
        reference = shape.get("filename", "")
        found = _mesh_file(reference, robot)
        if found is None or found.suffix.lower() not in DRAWN_FORMATS:
            missing.append(reference)
            return "sphere", (MISSING_MESH_RADIUS,), None, one
        sx, sy, sz = _numbers(shape.get("scale"), one)
        return "mesh", (), found, (sx, sy, sz)
    raise ViewerError(f"the visual {name!r} is a {shape.tag}, which the playback cannot draw")


def _mesh_file(reference: str, robot: Robot) -> Path | None:
    """The file a URDF mesh reference names, if it exists (as Pinocchio would look it up)."""
    if reference.startswith("package://"):
        rest = reference[len("package://") :]
        folders = [*robot.package_dirs, example_robot_data_dir()]
        found = (Path(d) / rest for d in folders if d is not None)
        return next((p for p in found if p.is_file()), None)
    path = Path(reference[len("file://") :] if reference.startswith("file://") else reference)
    path = path if path.is_absolute() else Path(robot.urdf).parent / path
    return path if path.is_file() else None
