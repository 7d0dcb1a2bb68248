"""Large flat faces of a collision mesh: found before qhull, hulled from joggled input at once.

qhull's triangulated hull ("Qt") fans a flat face from one point and coal refuses a point of
more than 255 neighbours, after qhull has merged the face's points: seconds on a finely
divided cylinder. Truth here: the points each mesh was built with (a cap of n sides holds its
n rim points and its centre), and the brute-force support of the mesh's vertices (numpy).
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial import ConvexHull

from freefloat.robot import meshes
from freefloat.robot.meshes import FAN_POINTS, flat_face_points, true_hull


def _cylinder(sides: int, caps: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """A closed cylinder (radius 0.2 m, length 0.5 m) of ``sides``, each cap fanned from its
    centre (without the caps' triangles when ``caps`` is false: a tube)."""
    angles = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    rim = np.column_stack([0.2 * np.cos(angles), 0.2 * np.sin(angles)])
    vertices = np.vstack(
        [
            np.column_stack([rim, np.full(sides, -0.25)]),
            np.column_stack([rim, np.full(sides, 0.25)]),
            [[0.0, 0.0, -0.25], [0.0, 0.0, 0.25]],
        ]
    )
    triangles = []
    for i in range(sides):
        j = (i + 1) % sides
        triangles += [[i, j, sides + j], [i, sides + j, sides + i]]
        if caps:
            triangles += [[2 * sides, j, i], [2 * sides + 1, sides + i, sides + j]]
    return vertices, np.array(triangles)


def _turned(vertices: np.ndarray) -> np.ndarray:
    """The vertices turned by 0.8 rad about a slanted axis (double precision)."""
    return vertices @ pin.exp3(np.array([0.3, -0.7, 0.2])).T


def _object(vertices: np.ndarray, triangles: np.ndarray) -> pin.GeometryObject:
    model = coal.BVHModelOBBRSS()
    model.beginModel(len(triangles), len(vertices))
    model.addVertices(vertices)
    model.addTriangles(triangles)
    model.endModel()
    return pin.GeometryObject("cylinder", 0, pin.SE3.Identity(), model)


@pytest.mark.parametrize("sides", [300, 600])
def test_a_cap_holds_its_rim_and_centre(sides):
    vertices, triangles = _cylinder(sides)
    assert flat_face_points(vertices, triangles) == sides + 1
    assert flat_face_points(_turned(vertices), triangles) == sides + 1
    far = _turned(vertices) + np.array([500.0, -300.0, 200.0])  # rounding at 500 m
    assert flat_face_points(far, triangles) == sides + 1


def test_slivers_count_nothing_and_the_hull_is_built(monkeypatch):
    """Three points nearly in a line, one triangle of them written 300 times: its normal is
    rounding noise, and the first draft failed on it (IndexError) instead of hulling."""
    monkeypatch.setattr(meshes, "_HULLS", {})
    vertices, triangles = _cylinder(300)
    a, b = np.array([0.01, 0.02, 0.03]), np.array([0.05, -0.04, 0.1])
    vertices = np.vstack([vertices, a, b, (a + b) / 2 + 1e-17])
    sliver = [len(vertices) - 3, len(vertices) - 2, len(vertices) - 1]
    triangles = np.vstack([triangles, [sliver] * 300])
    assert flat_face_points(vertices, triangles) == 301  # the caps still count
    hull = true_hull(_object(vertices, triangles))
    assert hull.num_points == 600


def test_no_flat_face_on_a_round_or_rounded_mesh():
    """A sphere's points; and a turned cap rounded to single precision (points about 1e-8 of
    the size off its plane), which qhull does not merge: both are hulled triangulated."""
    points = np.random.default_rng(3).normal(size=(600, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    triangles = ConvexHull(points).simplices
    assert flat_face_points(points, triangles) == 0
    vertices, triangles = _cylinder(600)
    rounded = _turned(vertices).astype(np.float32).astype(float)
    assert flat_face_points(rounded, triangles) < FAN_POINTS


def test_a_rim_without_triangles_is_not_found():
    """The stated limit: a tube's rims lie on faces of the hull, but no triangle of the mesh
    lies on their planes."""
    vertices, triangles = _cylinder(600, caps=False)
    assert flat_face_points(vertices, triangles) == 0


def test_few_points_need_no_look():
    vertices, triangles = _cylinder(100)  # 202 points: no face of FAN_POINTS
    assert flat_face_points(vertices, triangles) == 0


@pytest.mark.parametrize(
    ("sides", "asked"), [(200, ["Qt"]), (251, ["QJ"]), (260, ["QJ"]), (3000, ["QJ"])]
)
def test_the_hull_of_a_large_cap_comes_from_joggled_input(monkeypatch, sides, asked):
    """Below FAN_POINTS points on a face qhull is asked for the triangulated hull, whose
    points are the mesh's own vertices bit for bit; from there for the joggled hull at once,
    never first for the triangulated one (which fails from 254 points, late: seconds at 8000).
    Either way the hull holds every vertex: brute-force support in 300 directions."""
    monkeypatch.setattr(meshes, "_HULLS", {})
    options: list[str] = []
    build = coal.BVHModelOBBRSS.buildConvexHull

    def counted(shape, triangles, option):
        options.append(option)
        return build(shape, triangles, option)

    monkeypatch.setattr(coal.BVHModelOBBRSS, "buildConvexHull", counted)
    vertices, triangles = _cylinder(sides)
    hull = true_hull(_object(vertices, triangles))
    assert options == asked
    points = np.array(hull.points(), dtype=float).reshape(-1, 3)
    exact = [bool((vertices == p).all(axis=1).any()) for p in points]
    assert all(exact) if asked == ["Qt"] else not any(exact)
    directions = np.random.default_rng(0).normal(size=(300, 3))
    np.testing.assert_allclose(
        (points @ directions.T).max(axis=0), (vertices @ directions.T).max(axis=0), atol=1e-8
    )
