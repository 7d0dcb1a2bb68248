"""Benchmark section of ``freefloat reach`` (issue 28).

Run alone (``python scripts/bench_reachable.py [--runs N] [--goals N] [--kinova-goals N]
[--no-panda] [--markdown FILE]``) or from ``scripts/bench.py --reachable-only``.

- Time of :func:`freefloat.reachable` on the shipped servicers as they stand (Panda, UR5 and
  dual UR5, clearance on) and on a composed Kinova servicer on a 500 kg, 2 m cube
  (``examples/kinova_servicer.toml``, no clearance): the median over ``runs`` fresh calls (a
  new scenario each, after one loading call) of wall and CPU time (s), for the drift attitude
  and outer bound alone (``budget 0``, median of three) and with the inner set (the default
  budget); residual evaluations.
- Agreement of the inner set with ``plan``: goals sampled inside the reported inner set
  (seeded: a direction with a positive inner turn, a share 0.2-1 of that turn), each planned
  with ``ff.plan`` on the scenario as it stands (the UR5 servicer with its clearance
  constraint; the Kinova servicer without); counts of planned and refused, refusals quoted.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import freefloat as ff
from freefloat.physics.attitude import quat_exp, quat_multiply
from freefloat.reachable import DEFAULT_BUDGET

ROBOTS = Path(ff.default_scenario_path()).parent
SHIPPED = ("panda_servicer", "ur5_servicer", "dual_ur5_servicer")

#: The composed Kinova servicer on a 500 kg, 2 m cube (no clearance), shipped as an example.
KINOVA = Path(__file__).resolve().parents[1] / "examples" / "kinova_servicer.toml"


def _loaders(panda: bool) -> dict[str, Path]:
    files = {
        f"{name.replace('_', ' ')} (shipped, clearance)": ROBOTS / f"{name}.toml"
        for name in SHIPPED
        if panda or name != "panda_servicer"
    }
    files["kinova on 500 kg (no clearance)"] = KINOVA
    return files


def _timed(path: Path, budget: int) -> tuple[float, float, ff.ReachReport, ff.Scenario]:
    """Wall and CPU time (s) of one fresh ``reachable`` call, its report and scenario."""
    scenario = ff.Scenario.from_toml(path)
    clock, cpu = time.perf_counter(), time.process_time()
    report = ff.reachable(scenario, budget=budget)
    return time.perf_counter() - clock, time.process_time() - cpu, report, scenario


def bench_reachable(
    goals: int = 50,
    budget: int = DEFAULT_BUDGET,
    panda: bool = True,
    runs: int = 1,
    kinova_goals: int = 20,
) -> dict[str, object]:
    """Reach times (medians of ``runs`` fresh calls) and the inner set's agreement with plan.

    ``goals`` goals inside the UR5 servicer's inner set and ``kinova_goals`` inside the Kinova
    servicer's are planned. ``panda``: also time the Panda servicer (minutes with clearance).
    """
    rows, reports = [], {}
    for name, path in _loaders(panda).items():
        _timed(path, 0)  # loads the model and the collision geometry
        drift = [_timed(path, 0)[:2] for _ in range(3)]
        runs_done = [_timed(path, budget) for _ in range(max(1, runs))]
        report, scenario = runs_done[0][2], runs_done[0][3]
        reports[name] = (scenario, report)
        rows.append(
            {
                "scenario": name,
                "runs": len(runs_done),
                "wall_s": statistics.median(r[0] for r in runs_done),
                "cpu_s": statistics.median(r[1] for r in runs_done),
                "drift_bound_wall_s": statistics.median(d[0] for d in drift),
                "drift_bound_cpu_s": statistics.median(d[1] for d in drift),
                "evaluations": report.evaluations,
                "bound_deg": math.degrees(report.bound.bound) if report.bound else None,
                "largest_inner_deg": max(math.degrees(d.inner) for d in report.directions),
                "directions_with_reach": sum(d.inner > 0 for d in report.directions),
                "directions": len(report.directions),
            }
        )
        print(rows[-1], flush=True)
    agreement = [
        _agreement(*reports["ur5 servicer (shipped, clearance)"], goals, "ur5 servicer"),
        _agreement(*reports["kinova on 500 kg (no clearance)"], kinova_goals, "kinova"),
    ]
    return {"reach": rows, "agreement": agreement}


def _agreement(
    scenario: ff.Scenario, report: ff.ReachReport, goals: int, name: str
) -> dict[str, object]:
    """Plan ``goals`` goals sampled (seeded) inside the report's inner set, as they stand."""
    rng = np.random.default_rng(28)
    pool = [d for d in report.directions if d.inner > 0.0]
    planned, refused, times = 0, [], []
    for k in range(goals if pool else 0):
        d = pool[int(rng.integers(len(pool)))]
        share = float(rng.uniform(0.2, 1.0))
        goal = quat_multiply(report.drift_quaternion, quat_exp(share * d.inner * d.axis))
        clock = time.perf_counter()
        try:
            ff.plan(dataclasses.replace(scenario, goal_attitude=goal))
            planned += 1
        except ff.FreeFloatError as exc:
            refused.append(
                f"axis {np.round(d.axis, 2).tolist()} {share:.3f} x "
                f"{math.degrees(d.inner):.2f} deg: {str(exc)[:200]}"
            )
        times.append(time.perf_counter() - clock)
        print(f"{name} goal {k + 1}/{goals}: planned {planned}, refused {len(refused)}", flush=True)
    return {
        "scenario": name,
        "goals": goals,
        "planned": planned,
        "refused": refused,
        "median_plan_s": float(np.median(times)) if times else math.nan,
    }


def print_reachable(found: dict[str, object]) -> None:
    print(
        "\n| scenario | reach wall [s] | reach CPU [s] | drift + bound wall [s] | "
        "drift + bound CPU [s] | evaluations | bound [deg] | largest inner [deg] | "
        "directions with reach |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in found["reach"]:  # type: ignore[union-attr]
        print(
            f"| {r['scenario']} | {r['wall_s']:.2f} | {r['cpu_s']:.2f} | "
            f"{r['drift_bound_wall_s']:.2f} | {r['drift_bound_cpu_s']:.2f} | "
            f"{r['evaluations']} | {r['bound_deg']:.3g} | {r['largest_inner_deg']:.3g} | "
            f"{r['directions_with_reach']}/{r['directions']} |"
        )
    print("\n| inner set against plan | goals | planned | refused | median plan [s] |")
    print("|---|---:|---:|---:|---:|")
    for a in found["agreement"]:  # type: ignore[union-attr]
        print(
            f"| {a['scenario']} | {a['goals']} | {a['planned']} | {len(a['refused'])} | "
            f"{a['median_plan_s']:.2f} |"
        )
    for a in found["agreement"]:  # type: ignore[union-attr]
        for line in a["refused"]:
            print(f"  refused ({a['scenario']}): {line}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1, help="fresh reach calls per scenario")
    parser.add_argument("--goals", type=int, default=50, help="UR5 goals planned")
    parser.add_argument("--kinova-goals", type=int, default=20, help="Kinova goals planned")
    parser.add_argument("--no-panda", action="store_true", help="skip the Panda servicer")
    parser.add_argument("--markdown", type=Path, help="also write the tables, stamped")
    args = parser.parse_args()
    found = bench_reachable(
        args.goals, panda=not args.no_panda, runs=args.runs, kinova_goals=args.kinova_goals
    )
    print_reachable(found)
    if args.markdown:
        import contextlib
        import io

        from bench_stamp import stamped_markdown

        buffer = io.StringIO()
        with contextlib.redirect_stdout(buffer):
            print_reachable(found)
        args.markdown.write_text(stamped_markdown(buffer.getvalue()), encoding="utf-8")
        print(f"wrote {args.markdown}", file=sys.stderr)


if __name__ == "__main__":
    main()
