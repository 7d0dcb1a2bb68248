"""The solver's hulls against the original meshes (a cross-check of the solver's model).

A true hull is the convex hull of its mesh. Two comparisons, neither sharing the solver's
geometry code:

- **shapes**, once per mesh and independent of any configuration: every mesh vertex lies
  inside the solver's hull, and every hull vertex inside the convex hull of the mesh's
  vertices (each facet plane's signed distance), both to
  :data:`~freefloat.verify.clearance.HULL_TOLERANCE` (:func:`shape_excess`). The facets are
  the hull's own triangles once proved to be its facets (closed, each plane supporting every
  hull point; then a hull made of mesh vertices lies inside the mesh's hull), else SciPy's
  qhull's: the proof costs a few milliseconds a body where importing SciPy's spatial package
  costs a fresh process 0.4 s;
- **placements**, at the instant of the smallest clearance: a pair's hull distance is at most
  its mesh distance (within ``HULL_TOLERANCE``, GJK's) and at least the mesh distance minus the
  two hulls' slack (:func:`hull_slack`), for the pairs the
  certificate measured there (the closest ones) and, for each body none of those holds, the
  pair in which it lies nearest another body by its leaf spheres: every body's placement is
  compared at least once where clearance binds (a pair with a primitive where the body has
  one: cheaper to measure exactly than two meshes).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable

import coal
import numpy as np

from ..robot.collision import CollisionModel
from .clearance import MeshClearance

__all__ = ["hull_agreement", "hull_slack", "shape_excess"]


def hull_agreement(
    mesh: MeshClearance,
    solver: CollisionModel,
    time: float,
    joints: np.ndarray,
    placements: np.ndarray,
    measured: set[int],
    distance: Callable[[int], float],
) -> tuple[float, str]:
    """How far the solver's hull distances stray outside what their meshes allow (m).

    Args:
        mesh: the original-geometry model.
        solver: the solvers' hull model.
        time: the instant (s), for the message.
        joints: the instant's joint values (rad or m).
        placements: (G, 4, 4) the instant's body poses (:meth:`MeshClearance.placements`).
        measured: the pairs whose mesh distance is known there.
        distance: pair -> its signed mesh distance there (m).

    Returns the worst excess over the bounds, the shapes' (:func:`shape_excess`) included
    (negative or within ``HULL_TOLERANCE`` when everything compared agrees), and where it
    occurs.
    """
    if solver.names != mesh.names:
        return math.inf, "the solver checks other pairs than the URDF states"
    worst, where = shape_excess(mesh, solver)
    slack = [hull_slack(solver, i) for i in range(len(mesh.shapes))]
    pairs = compared(mesh, placements, measured)
    for k, hull in zip(pairs, solver.pair_distances(joints, pairs).tolist(), strict=True):
        a, b = mesh.pairs[k]
        true = distance(k)
        farther = hull - true
        nearer = true - hull - slack[a] - slack[b] if true > 0.0 else -math.inf
        if max(farther, nearer) > worst:
            worst = max(farther, nearer)
            where = (
                f"{mesh.names[k]} at t = {time:.4g} s: hull {hull:.6g} m, mesh {true:.6g} m, "
                f"hull slack {slack[a] + slack[b]:.3g} m"
            )
    return worst, where


def compared(mesh: MeshClearance, placements: np.ndarray, measured: set[int]) -> list[int]:
    """The pairs compared, in pair order: ``measured``, then one more pair per other body.

    A body no chosen pair holds gets the pair in which it lies nearest another body by its
    leaf spheres at ``placements`` (which covers that other body too), among its pairs with
    at most one mesh when it has any: a mesh against a primitive is one traversal of one
    mesh's bounding volumes, mesh against mesh a traversal of both (on the UR5 servicer about
    60 us against 0.6-1.1 ms), and either compares the body's hull with its mesh.
    """
    count = len(mesh.pairs)
    if count == 0:
        return []
    chosen = set(measured)
    every = np.arange(count)
    bounds = mesh.leaves.bounds(placements[None], np.zeros(count, dtype=int), every)
    covered = {int(g) for k in chosen for g in mesh.pairs[k]}
    both_meshes = np.array([a in mesh.meshes and b in mesh.meshes for a, b in mesh.pairs])
    for body in range(len(mesh.shapes)):
        mine = np.flatnonzero((mesh.first == body) | (mesh.second == body))
        if body in covered or len(mine) == 0:
            continue
        cheap = mine[~both_meshes[mine]]
        mine = cheap if len(cheap) else mine
        nearest = int(mine[np.argmin(bounds[mine])])
        chosen.add(nearest)
        covered.update(int(g) for g in mesh.pairs[nearest])
    return sorted(chosen)


def shape_excess(mesh: MeshClearance, solver: CollisionModel) -> tuple[float, str]:
    """How far the solver's hull shapes stray from their meshes' convex hulls (m), and where.

    In each body's own frame: the largest distance of a mesh vertex outside the solver's hull
    (a hull that misses part of its mesh) or of a hull vertex outside the convex hull of the
    mesh's vertices (a hull of more than its mesh), by facet planes (:func:`_excess_by_facets`,
    else qhull's). Remembered per pair of
    vertex sets (the shapes do not change with the configuration). ``-inf`` when no mesh has a
    hull.
    """
    objects = solver.geometry.geometryObjects
    worst, where = -math.inf, ""
    for index, (vertices, _) in mesh.meshes.items():
        if objects[index].name != mesh.geometry.geometryObjects[index].name:
            return math.inf, "the solver's bodies are not the URDF's, in its order"
        shape = objects[index].geometry
        if not isinstance(shape, coal.ConvexBase):
            continue
        points = np.array(shape.points(), dtype=float).reshape(-1, 3)
        key = (_digest(points), _digest(vertices))
        if key not in _SHAPES:
            by_facets = _excess_by_facets(vertices, points, shape)
            _SHAPES[key] = (
                by_facets
                if by_facets is not None
                else max(_outside(vertices, points), _outside(points, vertices))
            )
        if _SHAPES[key] > worst:
            worst = _SHAPES[key]
            where = f"{objects[index].name}: hull and mesh vertices {worst:.3g} m apart"
    return worst, where


def _excess_by_facets(
    vertices: np.ndarray, points: np.ndarray, hull: coal.ConvexBase
) -> float | None:
    """:func:`shape_excess` of one body without qhull, or None when it cannot be told so.

    The hull's own triangles are taken as candidate facets and proved to cover its boundary:
    they form a closed surface oriented by their winding (every directed edge in exactly one
    triangle, and its reverse in exactly one other), none is a sliver, and the plane through
    each, its normal from its winding, has every hull point on its inner side (to 1e-9 of the
    hull's size). Such a surface lies in the boundary of the points' convex hull with every
    triangle facing out, so it covers that boundary a whole number of times, at least once:
    every facet of the hull holds one of the triangles, and their planes are its facet planes.
    The mesh vertices' largest distance outside them (plus the largest point beyond a plane, a
    number of rounding size) is then the distance qhull's facets give. When every hull point
    is one of the mesh's vertices, none lies outside the mesh's convex hull: the other side is
    0. Otherwise (a hull of moved or extra points, triangles that do not prove themselves:
    doubled, reversed, open), None: qhull decides.
    """
    known = {row.tobytes() for row in np.ascontiguousarray(vertices)}
    if any(row.tobytes() not in known for row in np.ascontiguousarray(points)):
        return None
    triangles = np.array(
        [[hull.polygons(i)[k] for k in range(3)] for i in range(hull.num_polygons)], dtype=int
    ).reshape(-1, 3)
    size = float(np.ptp(points, axis=0).max()) if len(points) else 0.0
    if len(triangles) < 4 or size <= 0.0 or not _closed_and_oriented(triangles):
        return None
    a, b, c = (points[triangles[:, k]] for k in range(3))
    normals = np.cross(b - a, c - a)
    lengths = np.linalg.norm(normals, axis=1)
    if np.any(lengths <= 1e-12 * size**2):
        return None
    normals /= lengths[:, None]
    offsets = np.einsum("ij,ij->i", normals, a)
    beyond = float((points @ normals.T - offsets).max())
    if beyond > 1e-9 * size:
        return None
    return float((vertices @ normals.T - offsets).max()) + max(beyond, 0.0)


def _closed_and_oriented(triangles: np.ndarray) -> bool:
    """Whether the (T, 3) triangles close up, consistently oriented by their winding.

    Every directed edge in exactly one triangle, and its reverse in exactly one other.
    """
    directed = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    pairs, counts = np.unique(directed, axis=0, return_counts=True)
    if np.any(counts != 1):
        return False
    found = {(int(i), int(j)) for i, j in pairs}
    return all((j, i) in found for i, j in found)


def _outside(points: np.ndarray, around: np.ndarray) -> float:
    """Largest signed distance (m) of ``points`` outside the convex hull of ``around``.

    By the hull's face planes (unit normals): negative when every point is inside. A flat
    vertex set (no volume) is joggled (qhull's ``QJ``), which moves it by ~1e-11 of its size.
    """
    from scipy.spatial import ConvexHull, QhullError  # when needed: it costs start-up time

    try:
        hull = ConvexHull(around, qhull_options="Qt")
    except QhullError:
        hull = ConvexHull(around, qhull_options="QJ")
    planes = hull.equations
    return float((points @ planes[:, :3].T + planes[:, 3]).max())


def _digest(array: np.ndarray) -> bytes:
    return hashlib.blake2b(np.ascontiguousarray(array).tobytes(), digest_size=16).digest()


#: Shape excess (m) per pair of vertex sets (hull's, mesh's), computed once per process.
_SHAPES: dict[tuple[bytes, bytes], float] = {}


#: Slack per hull object (id of the coal shape; hulls are shared and kept, see true_hull).
_SLACK: dict[int, float] = {}


def hull_slack(model: CollisionModel, index: int) -> float:
    """How far a solver hull's surface may lie from its mesh (m): 0 for primitives.

    Every hull vertex is a mesh vertex, so every point of a hull face lies within the face's
    longest edge over sqrt(3) of a mesh point.
    """
    shape = model.geometry.geometryObjects[index].geometry
    if not isinstance(shape, coal.ConvexBase):
        return 0.0
    if id(shape) not in _SLACK:
        points = np.array(shape.points(), dtype=float).reshape(-1, 3)
        faces = np.array(
            [[f[0], f[1], f[2]] for f in (shape.polygons(i) for i in range(shape.num_polygons))]
        )
        corners = points[faces]
        edges = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2)
        _SLACK[id(shape)] = float(edges.max()) / math.sqrt(3.0)
    return _SLACK[id(shape)]
