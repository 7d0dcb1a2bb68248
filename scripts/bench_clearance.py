"""Benchmark section: the cost of true hulls and of the certified clearance check.

Run through ``scripts/bench.py --clearance`` (or alone: ``python scripts/bench_clearance.py``).
Side by side in one run:

- distance queries per configuration on the meshes' own faces (the model before plan format 4,
  built here as the baseline) against true hulls (today), and the hull build, cold and cached;
- verification's clearance check: the sampled check on hulls (401 samples, refined minima;
  the check before plan format 4) against the certificate on the original meshes;
- a whole ``ff.plan`` of each shipped servicer with and without clearance, each a fresh call;
- the hull of a finely divided cylinder mesh (500 to 8000 sides): as built today (a flat face
  of many points hulled from joggled input at once) against the triangulated hull tried first.
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

import freefloat as ff
from freefloat.problem.constraints.clearance import Clearance
from freefloat.problem.constraints.registry import scenario_constraints
from freefloat.robot import geometry, meshes
from freefloat.robot.collision import CollisionModel, known_srdf
from freefloat.verify.clearance_check import clearance_certificate
from freefloat.verify.path_eval import file_path

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ("panda_servicer", "ur5_servicer")


def _median_ms(fn, runs: int) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(1e3 * (time.perf_counter() - start))
    return statistics.median(times)


def _face_model_distances(robot: ff.Robot, srdf: Path | None):  # type: ignore[no-untyped-def]
    """The baseline: every mesh as coal's convex representation of its own faces (not a hull)."""
    geom = geometry.load_collision_geometry(robot)
    for obj in geom.geometryObjects:
        if isinstance(obj.geometry, coal.BVHModelBase):
            obj.geometry.buildConvexRepresentation(False)
            obj.geometry = obj.geometry.convex
    pairs = geometry.checked_pairs(robot, geom, srdf)
    data, gdata = robot.model.createData(), pin.GeometryData(geom)
    request = coal.DistanceRequest()
    request.gjk_tolerance = request.epa_tolerance = 1e-9
    request.enable_signed_distance = True
    shapes = [o.geometry for o in geom.geometryObjects]

    def distances(joints: np.ndarray) -> np.ndarray:
        pin.forwardKinematics(robot.model, data, robot.configuration(joints))
        pin.updateGeometryPlacements(robot.model, data, geom, gdata)
        tf = [coal.Transform3s(m.rotation, m.translation) for m in gdata.oMg]
        return np.array(
            [
                coal.distance(shapes[a], tf[a], shapes[b], tf[b], request, coal.DistanceResult())
                for a, b in pairs
            ]
        )

    return distances


def bench_hulls(runs: int) -> list[dict[str, object]]:
    """Per servicer: query time per configuration (faces vs hulls), hull build cold and cached."""
    return [_hull_row(name, runs) for name in SCENARIOS]


def _hull_row(name: str, runs: int) -> dict[str, object]:
    s = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / f"{name}.toml")
    srdf = known_srdf(s.robot)
    start, goal = np.asarray(s.start), np.asarray(s.goal)
    configs = [start + u * (goal - start) for u in np.linspace(0, 1, 20)]
    faces = _face_model_distances(s.robot, srdf)
    meshes._HULLS.clear()
    cold = _median_ms(lambda: CollisionModel(s.robot, srdf), 1)
    warm = _median_ms(lambda: CollisionModel(s.robot, srdf), runs)
    hulls = CollisionModel(s.robot, srdf)
    return {
        "robot": name,
        "pairs": hulls.n_pairs,
        "faces_ms": _median_ms(lambda: [faces(q) for q in configs], runs) / len(configs),
        "hulls_ms": _median_ms(lambda: [hulls.distances(q) for q in configs], runs) / len(configs),
        "build_cold_ms": cold,
        "build_cached_ms": warm,
    }


def bench_certificate(runs: int) -> list[dict[str, object]]:
    """Per servicer: sampled hull check vs certificate on meshes, and whole plans with/without."""
    return [_certificate_row(name, runs) for name in SCENARIOS]


def _certificate_row(name: str, runs: int) -> dict[str, object]:
    path = ROOT / "robots" / "scenarios" / f"{name}.toml"
    s = ff.Scenario.from_toml(path)
    plan = ff.plan(s)
    clearance = next(c for c in scenario_constraints(s) if isinstance(c, Clearance))
    paths = file_path(plan)

    def sampled() -> None:
        clearance._smallest_memo.clear()
        clearance._sampled_memo = None
        clearance.excess(s.robot, plan.path())

    cert = clearance_certificate(s.robot, clearance, paths)
    return {
        "robot": name,
        "sampled_hull_ms": _median_ms(sampled, runs),
        "certificate_ms": _median_ms(
            lambda: clearance_certificate(s.robot, clearance, paths), runs
        ),
        "instants": cert.instants,
        "halvings": cert.bisections,
        "measured_m": cert.measured,
        "certified_m": cert.lower_bound,
        "plan_with_ms": _median_ms(lambda: ff.plan(ff.Scenario.from_toml(path)), runs),
        "plan_without_ms": _median_ms(
            lambda: ff.plan(_without_clearance(ff.Scenario.from_toml(path))), runs
        ),
    }


#: Sides of the cylinder meshes of the flat-face table.
FLAT_SIDES = (500, 2000, 8000)


def bench_flat_faces() -> list[dict[str, object]]:
    """Per mesh: its hull today against the triangulated hull tried first (ms, one build).

    The cylinders of :data:`FLAT_SIDES`, and a sphere of 64,000 vertices whose every facet
    is split into 16 triangles (no face of many points, but many planes of several
    triangles: the look for flat faces must stay cheap). The mesh's triangles are read first
    in both (the solvers' model reads them anyway); ``look_ms`` is the look alone.
    """
    meshes_built = [(f"cylinder, {n} sides", _cylinder_object(n)) for n in FLAT_SIDES]
    meshes_built.append(("sphere, 64,000 vertices, 16 triangles a facet", _faceted_sphere()))
    rows = []
    for name, obj in meshes_built:
        triangles = meshes.object_triangles(obj)
        look = _median_ms(lambda t=triangles: meshes.flat_face_points(*t), 1)
        today = _median_ms(lambda o=obj, t=triangles: meshes._hull(o, t), 1)
        first = _median_ms(lambda o=obj: _triangulated_first(o), 1)
        hull = meshes._hull(obj, triangles)
        rows.append(
            {
                "mesh": name,
                "flat_points": meshes.flat_face_points(*triangles),
                "look_ms": look,
                "today_ms": today,
                "triangulated_first_ms": first,
                "hull_points": hull.num_points,
            }
        )
        print(f"  done: flat faces {rows[-1]}", flush=True)
    return rows


def _faceted_sphere() -> pin.GeometryObject:
    """A unit sphere of 4000 random points' hull, each triangle split in 4, twice."""
    points = np.random.default_rng(1).normal(size=(4000, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    from scipy.spatial import ConvexHull

    vertices, triangles = points, ConvexHull(points).simplices
    for _ in range(2):
        vertices, triangles = _split(vertices, triangles)
    return _mesh_object("sphere", vertices, triangles)


def _split(vertices: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each triangle into four by its edges' middles (flat: no new curvature)."""
    edges = np.sort(
        np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1
    )
    unique, index = np.unique(edges, axis=0, return_inverse=True)
    middles = len(vertices) + index.reshape(3, -1).T  # per triangle: ab, bc, ca
    vertices = np.vstack([vertices, 0.5 * (vertices[unique[:, 0]] + vertices[unique[:, 1]])])
    a, b, c = triangles.T
    ab, bc, ca = middles.T
    split = np.concatenate(
        [np.column_stack(t) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]
    )
    return vertices, split


def _cylinder_object(sides: int) -> pin.GeometryObject:
    """A closed cylinder mesh (radius 0.2 m, length 0.5 m), each cap fanned from its centre."""
    angles = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    rim = np.column_stack([0.2 * np.cos(angles), 0.2 * np.sin(angles)])
    ends = [np.column_stack([rim, np.full(sides, z)]) for z in (-0.25, 0.25)]
    vertices = np.vstack([*ends, [[0.0, 0.0, -0.25], [0.0, 0.0, 0.25]]])
    k = np.arange(sides)
    j = (k + 1) % sides
    triangles = np.vstack(
        [
            np.column_stack([k, j, sides + j]),
            np.column_stack([k, sides + j, sides + k]),
            np.column_stack([np.full(sides, 2 * sides), j, k]),
            np.column_stack([np.full(sides, 2 * sides + 1), sides + k, sides + j]),
        ]
    )
    return _mesh_object(f"cylinder{sides}", vertices, triangles)


def _mesh_object(name: str, vertices: np.ndarray, triangles: np.ndarray) -> pin.GeometryObject:
    """A geometry object of a triangle mesh (m)."""
    model = coal.BVHModelOBBRSS()
    model.beginModel(len(triangles), len(vertices))
    model.addVertices(vertices)
    model.addTriangles(triangles)
    model.endModel()
    return pin.GeometryObject(name, 0, pin.SE3.Identity(), model)


def _triangulated_first(obj: pin.GeometryObject) -> coal.ConvexBase | None:
    """The hull as built before: triangulated (``Qt``), joggled (``QJ``) when that fails."""
    for options in ("Qt", "QJ"):
        shape = obj.geometry.clone()
        try:
            shape.buildConvexHull(True, options)
        except (ValueError, RuntimeError):
            continue
        return shape.convex
    return None


def print_flat_faces(rows: list[dict[str, object]]) -> None:
    """The flat-face table as markdown."""
    print("\n### Hulls of meshes with a large flat face (a cylinder's caps)\n")
    print(
        "| mesh | points on one face | look ms | hull today ms | triangulated first ms | "
        "ratio | hull points |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(
            f"| {r['mesh']} | {r['flat_points']} | {r['look_ms']:.1f} | {r['today_ms']:.0f} | "
            f"{r['triangulated_first_ms']:.0f} | "
            f"{r['triangulated_first_ms'] / r['today_ms']:.1f}x | {r['hull_points']} |"  # type: ignore[operator]
        )


def _without_clearance(scenario: ff.Scenario) -> ff.Scenario:
    from dataclasses import replace

    return replace(scenario, safety=replace(scenario.safety, check=False))


def print_clearance(hulls: list[dict[str, object]], certs: list[dict[str, object]]) -> None:
    """Both tables as markdown."""
    print("\n### Clearance: true hulls against the meshes' own faces (per configuration)\n")
    print("| robot | pairs | faces (old) ms | true hulls ms | ratio | hulls cold ms | cached ms |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for r in hulls:
        print(
            f"| {r['robot']} | {r['pairs']} | {r['faces_ms']:.2f} | {r['hulls_ms']:.2f} | "
            f"{r['hulls_ms'] / r['faces_ms']:.2f}x | {r['build_cold_ms']:.0f} | "
            f"{r['build_cached_ms']:.0f} |"
        )
    print("\n### Clearance check: sampled on hulls (old) against certified on meshes\n")
    print(
        "| robot | sampled hull check ms | certificate ms | ratio | instants | halvings | "
        "min clearance m | certified >= m | plan with clearance ms | without ms | ratio |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in certs:
        print(
            f"| {r['robot']} | {r['sampled_hull_ms']:.0f} | {r['certificate_ms']:.0f} | "
            f"{r['certificate_ms'] / r['sampled_hull_ms']:.2f}x | {r['instants']} | "
            f"{r['halvings']} | {r['measured_m']:.5f} | {r['certified_m']:.5f} | "
            f"{r['plan_with_ms']:.0f} | {r['plan_without_ms']:.0f} | "
            f"{r['plan_with_ms'] / r['plan_without_ms']:.2f}x |"
        )


if __name__ == "__main__":
    print_clearance(bench_hulls(5), bench_certificate(3))
    print_flat_faces(bench_flat_faces())
