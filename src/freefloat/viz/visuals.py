"""The robot's visual geometry, loaded from its URDF and drawn as meshcat objects.

Each visual of the URDF becomes one meshcat node ``<root>/visuals/<name>`` holding its shape in
the visual's own frame: a box, sphere or cylinder as the URDF gives it (meshcat's cylinder runs
along y, the URDF's along z, so it is turned), a capsule as a triangulated capsule, a mesh file
as its text (COLLADA with its texture images embedded, Wavefront OBJ) or bytes (STL), with the
URDF's scale in the object's own matrix so that a node's transform is the visual's pose alone
(what an animation frame sets). A mesh file's own materials are kept unless the URDF gives the
visual a material; other shapes take the URDF colour. A link whose mesh file cannot be found
is drawn as a small sphere (:data:`MISSING_MESH_RADIUS`), with a warning.
"""

from __future__ import annotations

import base64
import logging
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import meshcat.geometry as g
import numpy as np
import pinocchio as pin

from ..errors import ViewerError
from ..robot.model import Robot, example_robot_data_dir

__all__ = ["MISSING_MESH_RADIUS", "draw_visuals", "visual_model", "visual_node"]

LOGGER = logging.getLogger(__name__)

#: Radius (m) of the sphere drawn for a link whose mesh file cannot be found.
MISSING_MESH_RADIUS = 0.04
#: meshcat's cylinder axis (y) turned onto the URDF's (z).
_Y_TO_Z = np.array([[1.0, 0, 0, 0], [0, 0, -1.0, 0], [0, 1.0, 0, 0], [0, 0, 0, 1.0]])
_COLLADA = "{http://www.collada.org/2005/11/COLLADASchema}"


def visual_node(root: str, obj: pin.GeometryObject) -> str:
    """The meshcat path of a visual's node."""
    return f"{root}/visuals/{obj.name}"


def draw_visuals(viewer: Any, visual: pin.GeometryModel, root: str) -> list[str]:
    """Set every visual's meshcat object below ``root``; returns the nodes in model order.

    Raises:
        ViewerError: a visual whose shape meshcat cannot draw (a plane, an octree...).
    """
    nodes = []
    for obj in visual.geometryObjects:
        node = visual_node(root, obj)
        shown = _shown(obj)
        if isinstance(shown, _ColladaFile):
            viewer[node].set_object(shown)
        else:
            viewer[node].set_object(shown, _material(obj))
        nodes.append(node)
    return nodes


def _shown(obj: pin.GeometryObject) -> Any:
    """The meshcat geometry (or, for a COLLADA file, the object) of one visual."""
    shape, kind = obj.geometry, type(obj.geometry).__name__
    path = Path(obj.meshPath) if obj.meshPath else None
    scale = np.asarray(obj.meshScale, dtype=float)
    if path is not None and path.suffix.lower() in (".dae", ".obj", ".stl"):
        return _mesh_file(path, scale, obj)
    if kind == "Box":
        return g.Box([float(x) for x in 2.0 * np.asarray(shape.halfSide)])
    if kind == "Sphere":
        return g.Sphere(float(shape.radius))
    if kind == "Cylinder":
        return _Placed(g.Cylinder(2.0 * float(shape.halfLength), float(shape.radius)), _Y_TO_Z)
    if kind == "Capsule":
        return _capsule(float(shape.radius), float(shape.halfLength))
    raise ViewerError(f"the visual {obj.name!r} is a {kind}, which the playback cannot draw")


def _material(obj: pin.GeometryObject) -> Any:
    """The URDF colour of a visual as a meshcat material (transparent below opacity 1)."""
    rgba = np.clip(np.asarray(obj.meshColor, dtype=float), 0.0, 1.0)
    red, green, blue = (int(x) for x in np.rint(rgba[:3] * 255.0))
    colour = red << 16 | green << 8 | blue
    if rgba[3] < 1.0:
        return g.MeshPhongMaterial(color=colour, transparent=True, opacity=float(rgba[3]))
    return g.MeshPhongMaterial(color=colour)


class _Placed(g.Geometry):
    """A meshcat geometry with a fixed matrix of its own (a turned cylinder, a scaled mesh)."""

    def __init__(self, inner: Any, matrix: np.ndarray) -> None:
        super().__init__()
        self.inner, self.uuid = inner, inner.uuid
        self.matrix = np.array(matrix, dtype=float)

    def intrinsic_transform(self) -> np.ndarray:
        """The matrix as meshcat flattens it (row by row) for three.js (column by column)."""
        return self.matrix.T

    def lower(self, object_data: Any) -> Any:
        return self.inner.lower(object_data)


class _ColladaFile(g.Object):
    """A COLLADA file as a whole meshcat object, its texture images embedded as data URLs."""

    def __init__(
        self, text: str, resources: dict[str, str], matrix: np.ndarray, material: Any
    ) -> None:
        g.SceneElement.__init__(self)
        self.text, self.resources, self.matrix, self.material = text, resources, matrix, material

    def lower(self) -> dict[str, Any]:
        data: dict[str, Any] = {
            "metadata": {"version": 4.5, "type": "Object"},
            "geometries": [],
            "materials": [],
            "object": {
                "uuid": self.uuid,
                "type": "_meshfile_object",
                "format": "dae",
                "data": self.text,
                "resources": self.resources,
                "matrix": [float(x) for x in self.matrix.T.flatten()],
            },
        }
        if self.material is not None:
            self.material.lower_in_object(data)
        return data


def _mesh_file(path: Path, scale: np.ndarray, obj: pin.GeometryObject) -> Any:
    """A mesh file as meshcat geometry (OBJ, STL) or a whole object (COLLADA), scaled."""
    matrix = np.diag([*scale, 1.0])
    suffix = path.suffix.lower()
    try:
        if suffix == ".stl":
            return _Placed(g.StlMeshGeometry.from_file(str(path)), matrix)
        text = path.read_text(encoding="utf-8", errors="replace")
        if suffix == ".obj":
            return _Placed(g.MeshGeometry(text, "obj"), matrix)
        material = _material(obj) if obj.overrideMaterial else None
        return _ColladaFile(text, _textures(path), matrix, material)
    except OSError as exc:
        raise ViewerError(f"cannot read the mesh {path}: {exc}") from None


def _textures(path: Path) -> dict[str, str]:
    """A COLLADA file's texture images, by the name the file uses, as data URLs."""
    try:
        images = ET.parse(path).find(f"{_COLLADA}library_images")
    except ET.ParseError:
        return {}
    out = {}
    for element in images.iter() if images is not None else ():
        if not element.tag.endswith("init_from") or not element.text:
            continue
        image = Path(element.text)
        found = image if image.is_absolute() else path.parent / image
        if found.is_file():
            kind = "jpeg" if found.suffix.lower() in (".jpg", ".jpeg") else "png"
            data = base64.b64encode(found.read_bytes()).decode("ascii")
            out[element.text] = f"data:image/{kind};base64,{data}"
    return out


def _capsule(radius: float, half_length: float, around: int = 24, rings: int = 8) -> Any:
    """A capsule along z (m): a sphere's two halves ``half_length`` apart, triangulated."""
    polar = np.linspace(0.0, np.pi, 2 * rings + 1)
    polar = np.insert(polar, rings + 1, polar[rings])  # the equator twice: top and bottom
    azimuth = np.linspace(0.0, 2.0 * np.pi, around, endpoint=False)
    shift = np.where(np.arange(len(polar)) <= rings, half_length, -half_length)
    ring = np.stack(
        [
            radius * np.outer(np.sin(polar), np.cos(azimuth)),
            radius * np.outer(np.sin(polar), np.sin(azimuth)),
            (radius * np.cos(polar) + shift)[:, None] * np.ones(around),
        ],
        axis=-1,
    )
    vertices = ring.reshape(-1, 3)
    faces = []
    for i in range(len(polar) - 1):
        for j in range(around):
            a, b = i * around + j, i * around + (j + 1) % around
            faces += [[a, a + around, b], [b, a + around, b + around]]
    return g.TriangularMeshGeometry(vertices, np.array(faces))


def _mesh_found(name: str, robot: Robot) -> bool:
    """Whether a URDF mesh reference resolves to a file (as Pinocchio would look it up)."""
    if name.startswith("package://"):
        rest = name[len("package://") :]
        folders = [*robot.package_dirs, example_robot_data_dir()]
        return any(d is not None and (Path(d) / rest).is_file() for d in folders)
    path = Path(name[len("file://") :] if name.startswith("file://") else name)
    return (path if path.is_absolute() else Path(robot.urdf).parent / path).is_file()


def _with_simple_shapes(robot: Robot) -> tuple[str | None, list[str]]:
    """The URDF text with every missing visual mesh replaced by a small sphere, and the names.

    Returns ``(None, [])`` when every mesh is found (the file is used as it is).
    """
    try:
        root = ET.fromstring(robot.urdf_text or Path(robot.urdf).read_text(encoding="utf-8"))
    except (OSError, ET.ParseError):
        return None, []
    missing = []
    for visual in root.iter("visual"):
        geometry = visual.find("geometry")
        mesh = geometry.find("mesh") if geometry is not None else None
        if geometry is None or mesh is None or _mesh_found(mesh.get("filename", ""), robot):
            continue
        missing.append(mesh.get("filename", ""))
        geometry.remove(mesh)
        ET.SubElement(geometry, "sphere", radius=repr(MISSING_MESH_RADIUS))
    if not missing:
        return None, []
    return ET.tostring(root, encoding="unicode"), missing


def visual_model(robot: Robot) -> pin.GeometryModel:
    """The robot's visual geometry model (a missing mesh replaced by a sphere, with a warning).

    Raises:
        ViewerError: Pinocchio cannot build the visual geometry.
    """
    text, missing = _with_simple_shapes(robot)
    if missing:
        LOGGER.warning(
            "%d mesh file(s) of %s cannot be found (e.g. %s); those links are drawn as "
            "spheres of %g m",
            len(missing),
            Path(robot.urdf).name,
            missing[0],
            MISSING_MESH_RADIUS,
        )
    dirs = [str(d) for d in robot.package_dirs]
    try:
        text = text if text is not None else robot.urdf_text
        if text:  # the text the robot was loaded from (a plan's copy of its URDF)
            return pin.buildGeomFromUrdfString(
                robot.model, text, pin.GeometryType.VISUAL, package_dirs=dirs
            )
        return pin.buildGeomFromUrdf(
            robot.model, str(robot.urdf), pin.GeometryType.VISUAL, package_dirs=dirs
        )
    except (RuntimeError, ValueError) as exc:
        raise ViewerError(f"cannot load the visual geometry of {robot.urdf}: {exc}") from None
