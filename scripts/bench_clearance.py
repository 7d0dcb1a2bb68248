"""Benchmark section: the cost of true hulls and of the certified clearance check.

Run through ``scripts/bench.py --clearance`` (or alone: ``python scripts/bench_clearance.py``).
Side by side in one run:

- distance queries per configuration on the meshes' own faces (the model before plan format 4,
  built here as the baseline) against true hulls (today), and the hull build, cold and cached;
- verification's clearance check: the sampled check on hulls (401 samples, refined minima;
  the check before plan format 4) against the certificate on the original meshes;
- a whole ``ff.plan`` of each shipped servicer with and without clearance, each a fresh call.
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
from freefloat.robot import geometry
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
    geometry._HULLS.clear()
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
