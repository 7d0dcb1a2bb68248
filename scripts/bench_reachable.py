"""Benchmark section of ``freefloat reach`` (issue 28), run by ``scripts/bench.py --reachable``.

- Time of :func:`freefloat.reachable` on the shipped servicers as they stand (clearance on)
  and on a composed Kinova servicer on a 500 kg, 2 m cube (no clearance): wall and CPU time
  (s, one run after loading), the drift and bound part alone, residual evaluations.
- Agreement of the inner set with ``plan``: goals sampled inside the reported inner set
  (seeded: a direction with a positive inner turn, a share 0.2-1 of that turn), each planned
  with ``ff.plan``; counts of planned and refused.
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
import time
from pathlib import Path

import numpy as np

import freefloat as ff
from freefloat.physics.attitude import quat_exp, quat_multiply
from freefloat.problem.simple_bound import simple_motion_bound

ROBOTS = Path(ff.default_scenario_path()).parent

KINOVA = """
duration = 20.0
[robot]
arm = "kinova"
base_mass = 500.0
base_size = [2.0, 2.0, 2.0]
mount = [1.0, 0.0, 0.0]
mount_rpy_deg = [0.0, 90.0, 0.0]
[start]
joints = START
[goal]
joints = GOALJOINTS
[safety]
check = false
""".replace(
    "START",
    "{ "
    + ", ".join(f"j2s6s200_joint_{i} = {v}" for i, v in enumerate((0, 180, 180, 0, 180, 0), 1))
    + " }",
).replace(
    "GOALJOINTS",
    "{ "
    + ", ".join(f"j2s6s200_joint_{i} = {v}" for i, v in enumerate((40, 150, 200, 30, 150, 20), 1))
    + " }",
)


def _scenarios(folder: Path) -> dict[str, ff.Scenario]:
    kinova = folder / "kinova.toml"
    kinova.write_text(KINOVA)
    return {
        "panda servicer (shipped, clearance)": ff.Scenario.from_toml(
            ROBOTS / "panda_servicer.toml"
        ),
        "ur5 servicer (shipped, clearance)": ff.Scenario.from_toml(ROBOTS / "ur5_servicer.toml"),
        "kinova on 500 kg (no clearance)": ff.Scenario.from_toml(kinova),
    }


def bench_reachable(goals: int = 50, budget: int = 60, panda: bool = True) -> dict[str, object]:
    """Reach times and the inner set's agreement with ``plan`` on ``goals`` sampled goals.

    ``panda``: also time the Panda servicer (the slowest: minutes with clearance).
    """
    rows, reports = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, scenario in _scenarios(Path(tmp)).items():
            if not panda and "panda" in name:
                continue
            resolved = scenario.resolved()
            resolved.write_robot()
            clock = time.perf_counter()
            simple_motion_bound(ff.MomentumMap(resolved.robot), resolved.start, resolved.goal)
            bound_s = time.perf_counter() - clock
            clock, cpu = time.perf_counter(), time.process_time()
            report = ff.reachable(scenario, budget=budget)
            reports[name] = (scenario, report)
            rows.append(
                {
                    "scenario": name,
                    "wall_s": time.perf_counter() - clock,
                    "cpu_s": time.process_time() - cpu,
                    "bound_s": bound_s,
                    "evaluations": report.evaluations,
                    "bound_deg": math.degrees(report.bound.bound) if report.bound else None,
                    "largest_inner_deg": max(math.degrees(d.inner) for d in report.directions),
                    "directions_with_reach": sum(d.inner > 0 for d in report.directions),
                }
            )
            print(rows[-1], flush=True)
        agreement = _agreement(reports, goals)
    return {"reach": rows, "agreement": agreement}


def _agreement(reports: dict, goals: int) -> dict[str, object]:
    """Plan goals sampled inside the inner sets of the scenarios without clearance."""
    rng = np.random.default_rng(28)
    kinova = reports["kinova on 500 kg (no clearance)"]
    ur5 = reports["ur5 servicer (shipped, clearance)"]
    unchecked = dataclasses.replace(ur5[0], safety=dataclasses.replace(ur5[0].safety, check=False))
    pool = [(kinova[0], kinova[1], d) for d in kinova[1].directions if d.inner > 0.0]
    pool += [(unchecked, ur5[1], d) for d in ur5[1].directions if d.inner > 0.0]
    planned, refused, times = 0, [], []
    for k in range(goals):
        scenario, report, d = pool[int(rng.integers(len(pool)))]
        share = float(rng.uniform(0.2, 1.0))
        goal = quat_multiply(report.drift_quaternion, quat_exp(share * d.inner * d.axis))
        clock = time.perf_counter()
        try:
            ff.plan(dataclasses.replace(scenario, goal_attitude=goal))
            planned += 1
        except ff.FreeFloatError as exc:
            refused.append(
                f"{report.robot} axis {np.round(d.axis, 2).tolist()} "
                f"{share:.2f} x {math.degrees(d.inner):.2f} deg: {str(exc)[:160]}"
            )
        times.append(time.perf_counter() - clock)
        print(f"goal {k + 1}/{goals}: planned {planned}, refused {len(refused)}", flush=True)
    return {
        "goals": goals,
        "planned": planned,
        "refused": refused,
        "median_plan_s": float(np.median(times)),
        "note": "the UR5's inner set was computed with clearance; its goals are planned "
        "without (the constraint only removes paths)",
    }


def print_reachable(found: dict[str, object]) -> None:
    print(
        "\n| scenario | reach wall [s] | CPU [s] | drift + bound [s] | evaluations | bound [deg] "
        "| largest inner [deg] | directions with reach |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for r in found["reach"]:  # type: ignore[union-attr]
        print(
            f"| {r['scenario']} | {r['wall_s']:.2f} | {r['cpu_s']:.2f} | {r['bound_s']:.2f} | "
            f"{r['evaluations']} | {r['bound_deg']:.3g} | {r['largest_inner_deg']:.3g} | "
            f"{r['directions_with_reach']}/14 |"
        )
    a = found["agreement"]
    print(
        f"\ninner set vs plan: {a['planned']}/{a['goals']} sampled goals planned "  # type: ignore[index]
        f"(median plan {a['median_plan_s']:.2f} s)"
    )  # type: ignore[index]
    for line in a["refused"]:  # type: ignore[index]
        print(f"  refused: {line}")
