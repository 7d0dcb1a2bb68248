"""The robot's visuals (:mod:`.urdf_visuals`) drawn as meshcat objects.

Each visual of the URDF becomes one meshcat node ``<root>/visuals/<name>`` holding its shape in
the visual's own frame: a box, sphere or cylinder as the URDF gives it (meshcat's cylinder runs
along y, the URDF's along z, so it is turned), a capsule as a triangulated capsule, a mesh file
as its text (COLLADA with its texture images embedded, Wavefront OBJ) or bytes (STL), with the
URDF's scale in the object's own matrix so that a node's transform is the visual's pose alone
(what an animation frame sets). A COLLADA file keeps its own materials (the viewer draws its
colours, as with Pinocchio's visualizer); other shapes take the URDF colour (Pinocchio's light
grey without one).
"""

from __future__ import annotations

import base64
import io
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import meshcat.geometry as g
import numpy as np

from .mesh_files import checked_mesh
from .urdf_visuals import DEFAULT_RGBA, Visual

__all__ = ["draw_visuals"]

#: meshcat's cylinder axis (y) turned onto the URDF's (z).
_Y_TO_Z = np.array([[1.0, 0, 0, 0], [0, 0, -1.0, 0], [0, 1.0, 0, 0], [0, 0, 0, 1.0]])
_COLLADA = "{http://www.collada.org/2005/11/COLLADASchema}"


def _visual_node(root: str, visual: Visual) -> str:
    """The meshcat path of a visual's node."""
    return f"{root}/visuals/{visual.name}"


def draw_visuals(viewer: Any, visuals: list[Visual], root: str) -> list[str]:
    """Set every visual's meshcat object below ``root``; returns the nodes in the same order.

    Raises:
        ViewerError: a mesh file that cannot be read.
    """
    nodes = []
    for visual in visuals:
        node = _visual_node(root, visual)
        shown = _shown(visual)
        if isinstance(shown, _ColladaFile):
            viewer[node].set_object(shown)
        else:
            viewer[node].set_object(shown, _material(visual))
        nodes.append(node)
    return nodes


def _shown(visual: Visual) -> Any:
    """The meshcat geometry (or, for a COLLADA file, the object) of one visual."""
    size = visual.size
    if visual.mesh is not None:
        return _mesh_file(visual.mesh, np.asarray(visual.scale, dtype=float))
    if visual.shape == "box":
        return g.Box([float(x) for x in size])
    if visual.shape == "sphere":
        return g.Sphere(float(size[0]))
    if visual.shape == "cylinder":
        return _Placed(g.Cylinder(float(size[1]), float(size[0])), _Y_TO_Z)
    return _capsule(float(size[0]), 0.5 * float(size[1]))


def _material(visual: Visual) -> Any:
    """The URDF colour of a visual as a meshcat material (transparent below opacity 1)."""
    rgba = np.clip(np.asarray(visual.rgba or DEFAULT_RGBA, dtype=float), 0.0, 1.0)
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

    def __init__(self, text: str, resources: dict[str, str], matrix: np.ndarray) -> None:
        g.SceneElement.__init__(self)
        self.text, self.resources, self.matrix = text, resources, matrix

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
        return data


def _mesh_file(path: Path, scale: np.ndarray) -> Any:
    """A mesh file as meshcat geometry (OBJ, STL) or a whole object (COLLADA), scaled.

    Raises:
        ViewerError: a file the viewer could not read (:func:`.mesh_files.checked_mesh`).
    """
    matrix = np.diag([*scale, 1.0])
    suffix = path.suffix.lower()
    data = checked_mesh(path)
    if suffix == ".stl":
        return _Placed(g.StlMeshGeometry.from_stream(io.BytesIO(data)), matrix)
    text = data.decode("utf-8", errors="replace")
    if suffix == ".obj":
        return _Placed(g.MeshGeometry(text, "obj"), matrix)
    return _ColladaFile(text, _textures(path, data), matrix)


def _textures(path: Path, data: bytes) -> dict[str, str]:
    """A COLLADA file's (``data``, read from ``path``) texture images, as data URLs by name."""
    images = ET.fromstring(data).find(f"{_COLLADA}library_images")
    out = {}
    for element in images.iter() if images is not None else ():
        if not element.tag.endswith("init_from") or not element.text:
            continue
        image = Path(element.text)
        found = image if image.is_absolute() else path.parent / image
        if found.is_file():
            kind = "jpeg" if found.suffix.lower() in (".jpg", ".jpeg") else "png"
            encoded = base64.b64encode(found.read_bytes()).decode("ascii")
            out[element.text] = f"data:image/{kind};base64,{encoded}"
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
