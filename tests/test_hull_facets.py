"""The hull-against-mesh shape check by the hull's own proven facets, against SciPy's qhull."""

from __future__ import annotations

import subprocess
import sys

import coal
import numpy as np
import pytest
from scipy.spatial import ConvexHull

import freefloat as ff
from freefloat.robot import meshes
from freefloat.robot.collision import CollisionModel
from freefloat.robot.srdf import known_srdf
from freefloat.verify.clearance import MeshClearance
from freefloat.verify.hull_agreement import _excess_by_facets

from conftest import ROOT, coal_hull


def _qhull_excess(vertices: np.ndarray, points: np.ndarray) -> float:
    """The same figure from SciPy's qhull: each set's largest distance outside the other's
    convex hull by its facet planes."""

    def outside(these: np.ndarray, around: np.ndarray) -> float:
        planes = ConvexHull(around, qhull_options="Qt").equations
        return float((these @ planes[:, :3].T + planes[:, 3]).max())

    return max(outside(vertices, points), outside(points, vertices))


@pytest.mark.parametrize("urdf", ["ur5_servicer.urdf", "panda_servicer.urdf"])
def test_the_facet_route_gives_qhulls_figure_on_every_shipped_mesh(urdf):
    robot = ff.load_robot(ROOT / "robots" / urdf)
    srdf = known_srdf(robot)
    mesh, solver = MeshClearance(robot, srdf), CollisionModel(robot, srdf)
    objects = solver.geometry.geometryObjects
    checked = 0
    for index, (vertices, _) in mesh.meshes.items():
        shape = objects[index].geometry
        points = np.array(shape.points(), dtype=float).reshape(-1, 3)
        got = _excess_by_facets(vertices, points, shape)
        assert got is not None, objects[index].name  # an honest hull proves its facets
        assert got == pytest.approx(_qhull_excess(vertices, points), abs=1e-12)
        assert abs(got) <= 1e-12
        checked += 1
    assert checked >= 6


def test_a_hull_of_part_of_its_mesh_is_caught_by_its_facets():
    """Each UR5 mesh body's hull built from its mesh without the vertices within 8 mm of
    its +x side: every hull point is still a mesh vertex, so the facet route decides, and it
    reports the dropped vertices' distance outside, as qhull does (millimetres)."""
    robot = ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")
    mesh = MeshClearance(robot, known_srdf(robot))
    objects = mesh.geometry.geometryObjects
    for index, (vertices, _) in mesh.meshes.items():
        all_vertices, triangles = meshes.object_triangles(objects[index])
        keep = all_vertices[:, 0] < all_vertices[:, 0].max() - 0.008
        kept = np.flatnonzero(keep)
        inside = triangles[np.all(keep[triangles], axis=1)]
        renumber = np.full(len(all_vertices), -1)
        renumber[kept] = np.arange(len(kept))
        partial = coal_hull(all_vertices[kept], renumber[inside])
        points = np.array(partial.points(), dtype=float).reshape(-1, 3)
        got = _excess_by_facets(vertices, points, partial)
        assert got is not None, objects[index].name
        want = _qhull_excess(vertices, points)
        assert want > 1e-3  # the dropped side lies outside
        assert got == pytest.approx(want, abs=1e-12)


def test_a_hull_of_other_points_is_left_to_qhull():
    """A hull whose points are not the mesh's vertices (moved 5 mm out) proves nothing here."""
    robot = ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf")
    mesh = MeshClearance(robot, known_srdf(robot))
    index, (vertices, _) = next(iter(mesh.meshes.items()))
    all_vertices, triangles = meshes.object_triangles(mesh.geometry.geometryObjects[index])
    moved = all_vertices * 1.01
    hull = coal_hull(moved, triangles)
    points = np.array(hull.points(), dtype=float).reshape(-1, 3)
    assert _excess_by_facets(vertices, points, hull) is None


def test_planning_with_clearance_loads_no_scipy_spatial():
    """A fresh process plans and verifies the shipped Panda servicer (clearance checked)
    without SciPy's spatial package (0.4 s of a fresh call to import on the 2-core machine)."""
    code = (
        "import sys\nimport freefloat as ff\n"
        f"ff.plan(ff.Scenario.from_toml({str(ROOT / 'robots/scenarios/panda_servicer.toml')!r}))\n"
        "print('scipy.spatial' in sys.modules)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "False"


def _convex(points: np.ndarray, triangles: list[tuple[int, int, int]]) -> coal.ConvexBase:
    vertices = coal.StdVec_Vec3s()
    for point in points:
        vertices.append(np.array(point, dtype=float))
    faces = coal.StdVec_Triangle()
    for triangle in triangles:
        faces.append(coal.Triangle(*map(int, triangle)))
    return coal.Convex(vertices, faces)


@pytest.mark.parametrize(
    "triangles",
    [
        [(1, 5, 7), (1, 7, 3), (1, 5, 3), (5, 7, 3)],  # the top square twice over
        [(1, 5, 7), (7, 5, 1), (0, 4, 6), (6, 4, 0)],  # two triangles, each with its reverse
        [(1, 3, 7), (1, 7, 5), (0, 4, 6), (0, 6, 2)],  # top and bottom alone: open
    ],
)
def test_triangles_that_do_not_cover_the_hull_prove_nothing(triangles):
    """A unit cube's points with triangles that close up edge by edge without covering its
    boundary (found by review: the earlier check counted undirected edges and turned each
    normal outward itself, and reported 0 where qhull reports 4 m): left to qhull."""
    cube = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
    mesh = np.vstack([cube, [[5.0, 0.5, 0.5]]])
    hull = _convex(cube, triangles)
    points = np.array(hull.points(), dtype=float).reshape(-1, 3)
    assert _qhull_excess(mesh, points) == pytest.approx(4.0)
    assert _excess_by_facets(mesh, points, hull) is None


def test_a_cubes_outward_triangles_give_qhulls_figure():
    """The same cube with its twelve outward-wound triangles: proved, and the far vertex's
    4 m outside, as qhull has it."""
    cube = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
    mesh = np.vstack([cube, [[5.0, 0.5, 0.5]]])
    triangles = []
    for face in ConvexHull(cube).simplices:  # qhull's facets, wound outward here
        a, b, c = cube[face]
        outward = np.cross(b - a, c - a) @ (a - cube.mean(axis=0)) > 0.0
        triangles.append(tuple(face) if outward else (face[0], face[2], face[1]))
    hull = _convex(cube, triangles)
    points = np.array(hull.points(), dtype=float).reshape(-1, 3)
    assert _excess_by_facets(mesh, points, hull) == pytest.approx(4.0, abs=1e-12)
