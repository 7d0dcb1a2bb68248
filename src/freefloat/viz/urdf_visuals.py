"""The robot's visuals as its URDF states them, placed on the joints of its Pinocchio model.

Read from the URDF text with the standard XML parser, not loaded: a mesh file is named, found
and checked to exist, but not parsed (Pinocchio's ``buildGeomFromUrdf`` loads every visual mesh
into collision structures, about 0.5 s for the Panda's COLLADA files, which a drawing never
uses). Each ``<visual>`` of a link becomes one :class:`Visual` named as Pinocchio names it
(``<link>_<k>``, k counting the link's visuals from 0), carried by the joint of the link's body
frame at the frame's placement composed with the visual's ``<origin>``. Its colour follows
urdfdom: the robot-level material of the ``<material>``'s name, else the ``<material>``'s own
``<color>`` (which later visuals then know by that name); without one, none is stated. A
number the URDF gives in the wrong count or form is refused, naming the visual. A mesh
reference is found as ``package://`` in the robot's package folders (and example-robot-data's),
as a ``file://`` or absolute path, or relative to the URDF; a mesh that cannot be found, or is
not a file the viewer reads (:data:`DRAWN_FORMATS`), is drawn as a small sphere
(:data:`MISSING_MESH_RADIUS`), with one warning for the robot.
"""

from __future__ import annotations

import logging
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ViewerError
from ..robot.model import Robot, example_robot_data_dir
from ..robot.urdf_checks import urdf_number

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
        element: the URDF element drawn: ``"visual"``, ``"collision"`` for a link that
            states no visual, ``"skeleton"`` for a body with neither (a ball and rods).
    """

    name: str
    joint: int
    placement: pin.SE3
    shape: str
    size: tuple[float, ...] = ()
    mesh: Path | None = None
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    rgba: tuple[float, float, float, float] | None = None
    element: str = "visual"


def visual_model(robot: Robot) -> list[Visual]:
    """Every visual of the robot's URDF, in link order (a missing mesh: a sphere, warned).

    Raises:
        ViewerError: the URDF cannot be read, or states a visual that cannot be drawn.
    """
    try:
        root = ET.fromstring(robot.urdf_text or Path(robot.urdf).read_text(encoding="utf-8"))
    except (OSError, ET.ParseError) as exc:
        raise ViewerError(f"cannot read the visuals of {robot.urdf}: {exc}") from None
    # urdfdom's rule: a robot-level material of the name wins over a visual's own colour, and
    # a named colour given in a visual is known by that name to the visuals after it
    colours: dict[str, tuple[float, float, float, float]] = {}
    for material in root.findall("material"):
        rgba = _rgba(material, robot)
        if rgba is not None:
            colours[material.get("name", "")] = rgba
    model = robot.model
    out: list[Visual] = []
    missing: list[str] = []
    borrowed: list[str] = []  # links drawn from their collision shapes
    bare: list[str] = []  # links with mass and nothing to draw
    for link in root.findall("link"):
        name = link.get("name", "")
        if not model.existFrame(name, pin.FrameType.BODY):
            continue
        frame = model.frames[model.getFrameId(name, pin.FrameType.BODY)]
        elements = link.findall("visual")
        if not elements:
            elements = link.findall("collision")
            (borrowed if elements else bare if _massive(link) else []).append(name)
        if not elements and _massive(link):  # a body with nothing to draw: its skeleton
            out += _skeleton(root, name, frame, robot)
        for k, element in enumerate(elements):
            label = f"{name}_{k}"
            placement = frame.placement * _origin(element.find("origin"), robot, label)
            drawn = _geometry(element.find("geometry"), robot, label, missing)
            out.append(
                Visual(
                    label,
                    int(frame.parentJoint),
                    placement,
                    *drawn,
                    _colour(element, colours, robot),
                    element.tag,
                )
            )
    _say_undrawn(robot, borrowed, bare)
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


#: Radius (m) of the ball at a skeleton link's frame; its rods are half as thick.
SKELETON_RADIUS = 0.03
#: A skeleton's colour (RGBA): a steel blue, apart from the robot's own colours.
SKELETON_RGBA = (0.45, 0.55, 0.7, 1.0)


def _skeleton(root: ET.Element, name: str, frame: pin.Frame, robot: Robot) -> list[Visual]:
    """A link with nothing to draw as a ball at its frame and a rod to each child joint.

    The rods run from the link's frame to the ``<origin>`` of each joint whose parent it is
    (m, in the link's frame); a child at the frame itself gets no rod.
    """
    joint, out = int(frame.parentJoint), []
    out.append(
        Visual(
            f"{name}_skeleton",
            joint,
            frame.placement,
            "sphere",
            (SKELETON_RADIUS,),
            None,
            (1.0, 1.0, 1.0),
            SKELETON_RGBA,
            "skeleton",
        )
    )
    for k, child in enumerate(j for j in root.findall("joint") if _parent(j) == name):
        xyz = np.asarray(_origin(child.find("origin"), robot, f"{name}_rod{k}").translation)
        length = float(np.linalg.norm(xyz))
        if not (math.isfinite(length) and length > 1e-6):
            continue
        # a capsule runs along its own z: turn z onto the rod, centred halfway
        rotation = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), xyz / length)
        placement = frame.placement * pin.SE3(rotation.matrix(), 0.5 * xyz)
        size = (0.5 * SKELETON_RADIUS, length)
        out.append(
            Visual(
                f"{name}_rod{k}",
                joint,
                placement,
                "capsule",
                size,
                None,
                (1.0, 1.0, 1.0),
                SKELETON_RGBA,
                "skeleton",
            )
        )
    return out


def _parent(joint: ET.Element) -> str:
    parent = joint.find("parent")
    return "" if parent is None else parent.get("link", "")


def _massive(link: ET.Element) -> bool:
    """Whether a link states a mass above zero (a body, not a bare frame)."""
    mass = link.find("inertial/mass")
    try:
        return mass is not None and float(mass.get("value", "0")) > 0.0
    except ValueError:
        return False


def _say_undrawn(robot: Robot, borrowed: list[str], bare: list[str]) -> None:
    """One warning each for links drawn from their collision shapes and links not drawn."""
    urdf = Path(robot.urdf).name
    if borrowed:
        LOGGER.warning(
            "%d link(s) of %s have no <visual> (e.g. %s): drawn from their <collision> shapes",
            len(borrowed),
            urdf,
            borrowed[0],
        )
    if bare:
        LOGGER.warning(
            "%d link(s) of %s with mass have neither a <visual> nor a <collision> shape (e.g. "
            "%s): drawn as a skeleton (a ball at the link's frame, rods to its child joints)",
            len(bare),
            urdf,
            bare[0],
        )


def _colour(
    visual: ET.Element, colours: dict[str, tuple[float, float, float, float]], robot: Robot
) -> tuple[float, float, float, float] | None:
    """A visual's colour by urdfdom's rule (see :func:`visual_model`), or None."""
    material = visual.find("material")
    if material is None:
        return None
    name = material.get("name", "")
    if name in colours:
        return colours[name]
    own = _rgba(material, robot)
    if own is not None and name:
        colours[name] = own
    return own


def _rgba(material: ET.Element, robot: Robot) -> tuple[float, float, float, float] | None:
    """A ``<material>``'s ``<color rgba>``, or None when it gives none."""
    colour = material.find("color")
    if colour is None or colour.get("rgba") is None:
        return None
    r, g, b, a = _numbers(colour.get("rgba"), 4, f"material {material.get('name', '')!r}", robot)
    return (r, g, b, a)


def _numbers(text: str | None, count: int, what: str, robot: Robot) -> tuple[float, ...]:
    """``count`` numbers from a URDF attribute, read as urdfdom reads them (zeros when absent).

    Raises:
        ViewerError: another count of numbers, or a value that is not one.
    """
    if not text:
        return (0.0,) * count
    try:
        values = tuple(urdf_number(x) for x in text.split())
    except ValueError:
        values = ()
    if len(values) != count or not all(math.isfinite(v) for v in values):
        numbers = f"{count} finite number{'s' if count > 1 else ''}"
        raise ViewerError(f"{Path(robot.urdf).name}: {what} gives {text!r}; expected {numbers}")
    return values


def _origin(element: ET.Element | None, robot: Robot, label: str) -> pin.SE3:
    """An ``<origin xyz rpy>`` as a placement (m, rad; URDF's fixed-axis roll, pitch, yaw)."""
    if element is None:
        return pin.SE3.Identity()
    xyz = _numbers(element.get("xyz"), 3, f"the visual {label!r}, origin xyz,", robot)
    rpy = _numbers(element.get("rpy"), 3, f"the visual {label!r}, origin rpy,", robot)
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.array(xyz))


def _geometry(
    element: ET.Element | None, robot: Robot, name: str, missing: list[str]
) -> tuple[str, tuple[float, ...], Path | None, tuple[float, float, float]]:
    """(shape, size, mesh, scale) of a ``<geometry>``; a missing mesh becomes a sphere."""
    shape = next(iter(element), None) if element is not None else None
    if shape is None:
        raise ViewerError(f"the visual {name!r} states no geometry")
    one = (1.0, 1.0, 1.0)
    what = f"the visual {name!r}, {shape.tag}"
    if shape.tag == "box":
        return "box", _numbers(shape.get("size"), 3, f"{what} size,", robot), None, one
    if shape.tag == "sphere":
        return "sphere", _numbers(shape.get("radius"), 1, f"{what} radius,", robot), None, one
    if shape.tag in ("cylinder", "capsule"):
        radius = _numbers(shape.get("radius"), 1, f"{what} radius,", robot)
        length = _numbers(shape.get("length"), 1, f"{what} length,", robot)
        return shape.tag, radius + length, None, one
    if shape.tag == "mesh":
        reference = shape.get("filename", "")
        found = _mesh_file(reference, robot)
        if found is None or found.suffix.lower() not in DRAWN_FORMATS:
            missing.append(reference)
            return "sphere", (MISSING_MESH_RADIUS,), None, one
        scale = shape.get("scale") or "1 1 1"
        sx, sy, sz = _numbers(scale, 3, f"{what} scale,", robot)
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
