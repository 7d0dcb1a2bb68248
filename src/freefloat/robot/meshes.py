"""Meshes of collision geometry: their true convex hulls, triangles and volumes.

A mesh object is known by its file, scale and a digest of its vertices (:func:`mesh_key`):
hulls (qhull through coal, :func:`true_hull`) and triangles (:func:`object_triangles`) are
worked out once per key in a process, so a mesh file changed on disk never meets the hull or
triangles of its former content.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from ..errors import ModelError

__all__ = [
    "FAN_POINTS",
    "HullInfo",
    "MeshKey",
    "check_finite_meshes",
    "flat_face_points",
    "hull_volume",
    "mesh_key",
    "mesh_triangles",
    "mesh_volume",
    "object_triangles",
    "true_hull",
]

#: A mesh object's file, scale and a digest of its vertices (see mesh_key).
MeshKey = tuple[str, tuple[float, ...], str]


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


def mesh_key(obj: pin.GeometryObject) -> MeshKey:
    """A mesh object's file, scale and a digest of the vertices it was read with.

    A mesh file changed on disk (between two plans, or while one is made) never meets the
    cached hull or triangles of its former content.
    """
    vertices = np.ascontiguousarray(np.array(obj.geometry.vertices(), dtype=float))
    digest = hashlib.sha256(vertices.tobytes()).hexdigest()
    return str(obj.meshPath), tuple(float(s) for s in obj.meshScale), digest


def true_hull(obj: pin.GeometryObject, key: MeshKey | None = None) -> coal.ConvexBase:
    """The real convex hull (qhull, coal ``buildConvexHull``: :func:`_hull`) of a mesh object.

    Remembered per mesh file, scale and vertices (``key``: the object's, if known, as
    :func:`.geometry.load_shared_geometry` gives it). Never ``buildConvexRepresentation``: for a
    non-convex mesh that keeps the mesh's own faces, and GJK's support search on it stops at
    local maxima.
    """
    key = mesh_key(obj) if key is None else key
    if key not in _HULLS:
        _check_solid(obj)
        _HULLS[key] = _hull(obj, object_triangles(obj, key))
    return _HULLS[key]


#: qhull's triangulated hull (``Qt``) fans a flat face from one of its points, and coal keeps
#: at most 255 neighbours of a point: a face of 254 points or more fails (a cylinder's cap,
#: measured). From this many points on one face of the mesh, the joggled hull is built at once.
FAN_POINTS = 250
#: How far (relative to the mesh's largest coordinate, or its size if larger) a vertex may lie
#: from a face's plane and count as on it: qhull merges only points coplanar to its rounding,
#: and a cap rounded to single precision and tilted is hulled by ``Qt`` in milliseconds (2000
#: sides: 16 ms).
COPLANAR = 1e-12


def _hull(obj: pin.GeometryObject, mesh: tuple[np.ndarray, np.ndarray]) -> coal.ConvexBase:
    """The hull of a mesh object's vertices by qhull: triangulated, or else joggled.

    Triangulated output (``Qt``) splits a flat face of many vertices into a fan: the cap of a
    finely divided cylinder then gives one vertex more neighbours than coal's hull stores
    (255: "Too many neighbors"). Joggled input (``QJ``) makes every face a triangle of its
    own, with no fan: qhull moves every point by about 1e-9 of its largest coordinate first,
    more if it must try again (a 2000-sided cylinder of 0.2 m: 1.4e-10 m; 4000 sides of 0.5 m:
    3.4e-9 m), far inside the 1e-6 m to which verification holds every mesh vertex inside the
    hull (:mod:`freefloat.verify.hull_agreement`). The triangulated attempt fails late on
    large faces, after qhull has merged their points (8000 sides: 5.7 s, against 0.15 s
    joggled), so a mesh with a face of :data:`FAN_POINTS` points (:func:`flat_face_points`,
    ``mesh``: its vertices and triangles) is hulled from joggled input at once.

    Raises:
        ModelError: qhull finds no hull either way (its message, one line).
    """
    first = ""
    tries = ("QJ",) if flat_face_points(*mesh) >= FAN_POINTS else ("Qt", "QJ")
    for options in tries:
        shape = obj.geometry.clone()  # the object's own shape is left as it is
        try:
            shape.buildConvexHull(True, options)
        except (ValueError, RuntimeError) as exc:  # qhull's refusals, one line
            first = first or str(exc).strip().splitlines()[-1][:200]
            if "neighbor" not in first:
                break
            continue
        return shape.convex
    raise ModelError(f"collision mesh {obj.meshPath} ({obj.name}): no hull ({first})")


def flat_face_points(vertices: np.ndarray, triangles: np.ndarray) -> int:
    """The most vertices (a count) of one plane of the mesh's own triangles on a hull face.

    0 when no such face holds :data:`FAN_POINTS` of them.

    The triangles are grouped by normal and offset to 1e-3 (of the mesh's size); a group whose
    triangles have :data:`FAN_POINTS` distinct vertices or more has its plane fitted to them,
    and those on that plane (within :data:`COPLANAR` of the largest coordinate) are counted
    when every vertex of the mesh lies on one side of it (a face of the hull). Each group is
    read once, and the whole mesh only for such a group: no pass over all vertices per plane.
    Not found (the triangulated hull is then tried first, as for any mesh): points on a hull
    face that no triangle of the mesh lies on (a tube's rim), a face whose triangles' normals
    fall into several groups (rounding at a group's edge), a face with a chamfer near it.
    A mesh whose planes cannot be worked out (rounding noise) counts 0.
    ``vertices``: (V, 3) (m); ``triangles``: (F, 3) vertex indices.
    """
    if len(vertices) < FAN_POINTS or len(triangles) == 0:
        return 0
    with np.errstate(all="ignore"):
        try:
            return _flat_face_points(np.asarray(vertices, float), np.asarray(triangles, int))
        except (ValueError, IndexError, np.linalg.LinAlgError):
            return 0


def _flat_face_points(vertices: np.ndarray, triangles: np.ndarray) -> int:
    """:func:`flat_face_points`'s work."""
    size = float(np.ptp(vertices, axis=0).max())
    reach = max(size, float(np.abs(vertices).max()))  # rounding grows with the coordinates
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    normals = np.cross(b - a, c - a)
    lengths = np.linalg.norm(normals, axis=1)
    kept = lengths > 0.0
    normals, triangles = normals[kept] / lengths[kept, None], triangles[kept]
    offsets = np.einsum("ij,ij->i", normals, a[kept]) / size
    keys = np.round(np.column_stack([normals, offsets]) * 1e3).astype(np.int64)
    order = np.lexsort(keys.T[::-1])  # the triangles of one group next to each other
    sorted_keys = keys[order]
    starts = np.flatnonzero(np.r_[True, np.any(sorted_keys[1:] != sorted_keys[:-1], axis=1)])
    ends = np.r_[starts[1:], len(order)]
    most = 0
    for g in np.flatnonzero(3 * (ends - starts) >= FAN_POINTS):  # fewer: too few vertices
        members = np.unique(triangles[order[starts[g] : ends[g]]])
        if len(members) < FAN_POINTS:
            continue
        near = vertices[members]
        centre = near.mean(axis=0)
        normal = np.linalg.svd(near - centre, full_matrices=False)[2][2]  # the best plane
        on = int(np.count_nonzero(np.abs((near - centre) @ normal) <= COPLANAR * reach))
        if on < max(FAN_POINTS, most + 1):
            continue
        heights = (vertices - centre) @ normal
        if heights.min() >= -COPLANAR * reach or heights.max() <= COPLANAR * reach:
            most = on  # every vertex on one side: a face of the hull
    return most


#: Largest vertex coordinate of a collision mesh (m, after its scale): a kilometre.
MAX_VERTEX_M = 1000.0


def check_finite_meshes(geometry: pin.GeometryModel) -> None:
    """Refuse a collision mesh with a vertex not a finite number, or beyond a kilometre.

    Raises:
        ModelError: such a mesh, named with its file.
    """
    for obj in geometry.geometryObjects:
        mesh = obj.geometry
        if not isinstance(mesh, coal.BVHModelBase):
            continue
        vertices = np.asarray(mesh.vertices(), dtype=float)
        if not np.isfinite(vertices).all():
            raise ModelError(
                f"collision mesh {obj.meshPath} ({obj.name}) has vertex coordinates that are "
                "not finite numbers (NaN or inf); repair or re-export the mesh"
            )
        farthest = float(np.abs(vertices).max(initial=0.0))
        if farthest > MAX_VERTEX_M:
            raise ModelError(
                f"collision mesh {obj.meshPath} ({obj.name}) has a vertex "
                f"{farthest:.3g} m from its origin, beyond the "
                f"{MAX_VERTEX_M:g} m freefloat takes (a unit slip: mm for m?); scale or "
                "repair the mesh"
            )


def _check_solid(obj: pin.GeometryObject) -> None:
    """Refuse a collision mesh whose vertices span no volume (coal's hull code crashes on it).

    Raises:
        ModelError: fewer than four vertices, or all in one plane (or on one line).
    """
    vertices = np.array(obj.geometry.vertices(), dtype=float).reshape(-1, 3)
    flat = len(vertices) < 4
    if not flat:  # the spread's eigenvalues (squared singular values): a 3 x 3 problem
        centred = vertices - vertices.mean(axis=0)
        spread = np.linalg.eigvalsh(centred.T @ centred)
        flat = bool(spread[0] <= 1e-18 * max(float(spread[2]), 1e-300))
    if flat:
        raise ModelError(
            f"collision mesh {obj.meshPath} ({obj.name}) is flat: its {len(vertices)} vertices "
            "span no volume, and clearance needs a solid; give a thin <box> for a panel"
        )


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
    key = mesh_key(obj) if key is None else key
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
    """Volume of a coal convex hull (m^3), from its own faces (coal's ``computeVolume``).

    Until December 2026 qhull through SciPy: importing it cost a quarter of a second of a
    ``-v`` plan, which logs these volumes.
    """
    return float(hull.computeVolume())
