"""Reference geometry computed without coal or freefloat: numpy and quadprog only.

- :func:`read_stl`: triangles of a binary or ASCII STL file, parsed here;
  :func:`world_meshes`: those of a robot's STL collision meshes, placed by Pinocchio's
  kinematics.
- :func:`point_mesh_distance`: exact distance from points to a triangle soup (projection onto
  each triangle's plane, else the nearest edge).
- :func:`point_hull_distance`: exact distance from a point to the convex hull of vertices, a
  quadratic programme over convex weights (quadprog) of the vertices scipy's qhull keeps.
- :func:`box_hull_distance`: exact distance between a box and the convex hull of vertices (a
  quadratic programme over convex weights and the box's coordinates).
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pinocchio as pin
import quadprog


def read_stl(path: str | Path, scale: float = 1.0) -> np.ndarray:
    """(F, 3, 3) triangle corners of an STL file (m, times ``scale``)."""
    data = Path(path).read_bytes()
    if data[:5] == b"solid" and b"facet" in data[:400]:
        numbers = [
            [float(x) for x in line.split()[1:4]]
            for line in data.decode().splitlines()
            if line.strip().startswith("vertex")
        ]
        return np.array(numbers).reshape(-1, 3, 3) * scale
    (count,) = struct.unpack("<I", data[80:84])
    records = np.frombuffer(
        data[84 : 84 + 50 * count], dtype=np.dtype([("n", "<3f4"), ("v", "<9f4"), ("a", "<u2")])
    )
    return records["v"].astype(float).reshape(-1, 3, 3) * scale


def write_stl(path: Path, triangles: np.ndarray) -> None:
    """Write (F, 3, 3) triangles as an ASCII STL."""
    lines = ["solid test"]
    for tri in triangles:
        n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
        n = n / np.linalg.norm(n)
        lines += [f"facet normal {n[0]} {n[1]} {n[2]}", "outer loop"]
        lines += [f"vertex {v[0]} {v[1]} {v[2]}" for v in tri]
        lines += ["endloop", "endfacet"]
    lines.append("endsolid test")
    path.write_text("\n".join(lines) + "\n")


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(
        np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300),
        0.0,
        1.0,
    )
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def point_mesh_distance(point: np.ndarray, triangles: np.ndarray) -> float:
    """Exact distance (m) from ``point`` to the nearest point of any triangle."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    p = np.broadcast_to(np.asarray(point, float), a.shape)
    n = np.cross(b - a, c - a)
    area2 = np.linalg.norm(n, axis=1)
    good = area2 > 1e-15
    unit = np.where(good[:, None], n / np.where(good, area2, 1.0)[:, None], 0.0)
    height = np.einsum("ij,ij->i", p - a, unit)
    foot = p - height[:, None] * unit
    inside = good.copy()
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(v - u, foot - u), unit) >= 0.0
    edges = np.minimum.reduce(
        [_segment_distance(p, a, b), _segment_distance(p, b, c), _segment_distance(p, c, a)]
    )
    return float(np.where(inside, np.abs(height), edges).min())


def _convex_qp(
    vertices: np.ndarray, target: np.ndarray, box: tuple[np.ndarray, np.ndarray] | None = None
) -> float:
    """min |V^T w - R u - target| over convex weights w (and |u_i| <= h_i for a box R, h)."""
    n = len(vertices)
    extra = 0 if box is None else 3
    columns = [vertices.T] if box is None else [vertices.T, -box[0]]
    a_mat = np.hstack(columns)  # residual = a_mat @ x - target, x = [w, u]
    hessian = a_mat.T @ a_mat + 1e-12 * np.eye(n + extra)
    linear = a_mat.T @ target
    identity = np.eye(n + extra)
    rows = [np.concatenate([np.ones(n), np.zeros(extra)])] + [identity[i] for i in range(n)]
    lower = [1.0] + [0.0] * n
    for i in range(extra):
        rows += [identity[n + i], -identity[n + i]]
        lower += [-box[1][i], -box[1][i]]  # type: ignore[index]
    x = quadprog.solve_qp(hessian, linear, np.array(rows).T, np.array(lower), meq=1)[0]
    return float(np.linalg.norm(a_mat @ x - target))


def _extreme(vertices: np.ndarray) -> np.ndarray:
    """The vertices on the hull (scipy's qhull), so that the programme stays small."""
    from scipy.spatial import ConvexHull

    points = np.unique(vertices, axis=0)
    return points[ConvexHull(points).vertices]


def point_hull_distance(point: np.ndarray, vertices: np.ndarray) -> float:
    """Exact distance (m) from ``point`` to the convex hull of ``vertices`` (0 inside)."""
    vertices = _extreme(vertices)
    centre = vertices.mean(axis=0)
    return _convex_qp(vertices - centre, np.asarray(point, float) - centre)


def box_hull_distance(
    centre: np.ndarray, rotation: np.ndarray, half: np.ndarray, vertices: np.ndarray
) -> float:
    """Exact distance (m) between a box (centre, rotation, half sizes) and a hull (0: they meet)."""
    vertices = _extreme(vertices)
    origin = vertices.mean(axis=0)
    return _convex_qp(vertices - origin, np.asarray(centre, float) - origin, (rotation, half))


def world_meshes(model, joints: np.ndarray) -> dict[int, np.ndarray]:
    """Triangles (m, spacecraft frame) of every STL object of a collision model's geometry.

    Only the objects' file names, scales and placements are read from ``model``; the triangles
    come from the files.
    """
    robot = model.robot
    data, gdata = robot.model.createData(), pin.GeometryData(model.geometry)
    pin.forwardKinematics(robot.model, data, robot.configuration(joints))
    pin.updateGeometryPlacements(robot.model, data, model.geometry, gdata)
    out = {}
    for i, obj in enumerate(model.geometry.geometryObjects):
        if str(obj.meshPath).lower().endswith(".stl"):
            m = gdata.oMg[i]
            out[i] = read_stl(obj.meshPath, float(obj.meshScale[0])) @ m.rotation.T + m.translation
    return out
