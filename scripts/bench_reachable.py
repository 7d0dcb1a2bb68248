"""Benchmark section of ``freefloat reach`` (issue 28).

Run alone (``python scripts/bench_reachable.py [--runs N] [--goals N] [--kinova-goals N]
[--no-panda] [--jobs N [N ...]] [--markdown FILE]``) or from ``scripts/bench.py
--reachable-only``.

- Time of :func:`freefloat.reachable` on the shipped servicers as they stand (Panda, UR5 and
  dual UR5, clearance on) and on a composed Kinova servicer on a 500 kg, 2 m cube
  (``examples/kinova_servicer.toml``, no clearance): the median over ``runs`` fresh calls (a
  new scenario each, after one loading call) of wall and CPU time (s), for the drift attitude
  and outer bound alone (``budget 0``, median of three) and with the inner set (the default
  budget); residual evaluations. CPU time includes the worker processes' (reaped children).
  Each scenario is timed with each of ``jobs`` worker processes (default: the default jobs,
  then 1), side by side (the runs interleaved: one of each jobs in turn), with the speed-up
  over one job, the median 1-minute load average when each timing started, and whether every
  report is the same as the first one's (it must be: the directions are independent).
- The command a user types, ``freefloat reach SCENARIO -q``, in a fresh process each run (its
  imports included; the default jobs): the median wall time over ``runs`` runs (at least
  three), against the target of 2 s on the shipped servicers.
- Agreement of the inner set with ``plan``: goals sampled inside the reported inner set
  (seeded: a direction with a positive inner turn, a share 0.2-1 of that turn), each planned
  with ``ff.plan`` on the scenario as it stands (the UR5 and dual UR5 servicers with their
  clearance constraint, the dual UR5's end-effector goal replaced by the joints the report
  gives; the Kinova servicer without); counts of planned and refused, refusals quoted.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import freefloat as ff
from freefloat.parallel import default_jobs
from freefloat.physics.attitude import quat_exp, quat_multiply
from freefloat.reachable import DEFAULT_BUDGET
from freefloat.solvers.reach import default_directions

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


def _cpu() -> float:
    """CPU time (s) of this process and of its reaped children (the reach's workers)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def _timed(
    path: Path, budget: int, jobs: int | None = None
) -> tuple[float, float, ff.ReachReport, ff.Scenario]:
    """Wall and CPU time (s) of one fresh ``reachable`` call, its report and scenario."""
    scenario = ff.Scenario.from_toml(path)
    clock, cpu = time.perf_counter(), _cpu()
    report = ff.reachable(scenario, budget=budget, jobs=jobs)
    return time.perf_counter() - clock, _cpu() - cpu, report, scenario


def _same(a: ff.ReachReport, b: ff.ReachReport) -> bool:
    """Whether two reports give the same numbers (inner, outer, goals, evaluations)."""
    return a.evaluations == b.evaluations and all(
        x.inner == y.inner
        and x.outer == y.outer
        and x.stopped_by == y.stopped_by
        and x.breaks == y.breaks
        and np.array_equal(x.goal_quaternion, y.goal_quaternion)
        for x, y in zip(a.directions, b.directions, strict=True)
    )


def bench_reachable(
    goals: int = 50,
    budget: int = DEFAULT_BUDGET,
    panda: bool = True,
    runs: int = 1,
    kinova_goals: int = 20,
    jobs: tuple[int, ...] | None = None,
    dual_goals: int = 20,
) -> dict[str, object]:
    """Reach times (medians of ``runs`` fresh calls) and the inner set's agreement with plan.

    ``goals`` goals inside the UR5 servicer's inner set, ``kinova_goals`` inside the Kinova
    servicer's and ``dual_goals`` inside the dual UR5 servicer's (an end-effector goal: planned
    with the joints the report gives, as reach prints them) are planned. ``panda``: also time
    the Panda servicer (minutes with clearance).
    ``jobs``: the worker processes to time each scenario with (default: the default, then 1).
    """
    if jobs is None:
        jobs = tuple(dict.fromkeys((default_jobs(len(default_directions())), 1)))
    rows, reports = [], {}
    for name, path in _loaders(panda).items():
        _timed(path, 0)  # loads the model and the collision geometry
        drift = [_timed(path, 0)[:2] for _ in range(3)]
        timed: dict[int, list] = {workers: [] for workers in jobs}
        for _ in range(max(1, runs)):  # interleaved: the jobs see the same load drift
            for workers in jobs:
                load = os.getloadavg()[0]
                timed[workers].append((*_timed(path, budget, workers), load))
        first = timed[jobs[0]][0]
        reports[name] = (first[3], first[2])
        for workers, runs_done in timed.items():
            rows.append(_row(name, workers, runs_done, drift, first[2]))
            print(f"  done: {rows[-1]}", flush=True)
        if 1 in timed:
            for row in rows[-len(timed) :]:
                row["speedup"] = statistics.median(r[0] for r in timed[1]) / row["wall_s"]
    commands = [_command(name, path, max(3, runs)) for name, path in _loaders(panda).items()]
    agreement = [
        _agreement(*reports["ur5 servicer (shipped, clearance)"], goals, "ur5 servicer"),
        _agreement(*reports["kinova on 500 kg (no clearance)"], kinova_goals, "kinova"),
        _agreement(
            *reports["dual ur5 servicer (shipped, clearance)"], dual_goals, "dual ur5 servicer"
        ),
    ]
    return {"reach": rows, "commands": commands, "agreement": agreement}


def _row(
    name: str, workers: int, runs_done: list, drift: list, first: ff.ReachReport
) -> dict[str, object]:
    """One table row: medians over the runs of (wall, CPU, report, scenario, load)."""
    report = runs_done[0][2]
    return {
        "scenario": name,
        "jobs": workers,
        "load_1min": statistics.median(r[4] for r in runs_done),
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
        "same_report": all(_same(r[2], first) for r in runs_done),
    }


def _agreement(
    scenario: ff.Scenario, report: ff.ReachReport, goals: int, name: str
) -> dict[str, object]:
    """Plan ``goals`` goals sampled (seeded) inside the report's inner set, as they stand.

    An end-effector goal is planned with the joints the report holds (those reach prints).
    """
    if report.end_effector_goal:
        joints = dict(zip(scenario.robot.joint_names, report.goal_joints.tolist(), strict=True))
        scenario = dataclasses.replace(scenario, goal_joints=joints, goal_poses={})
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
        print(
            f"  done: {name} goal {k + 1}/{goals}: planned {planned}, refused {len(refused)}",
            flush=True,
        )
    return {
        "scenario": name,
        "goals": goals,
        "planned": planned,
        "refused": refused,
        "median_plan_s": float(np.median(times)) if times else math.nan,
    }


def _command(name: str, path: Path, runs: int) -> dict[str, object]:
    """``freefloat reach PATH -q`` in a fresh process, ``runs`` times: median wall time (s)."""
    import subprocess

    command = [sys.executable, "-m", "freefloat.cli", "reach", str(path), "-q"]
    walls = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        walls.append(time.perf_counter() - start)
    row = {"scenario": name, "runs": runs, "wall_s": statistics.median(walls)}
    print(f"  done: command {row}", flush=True)
    return row


def print_reachable(found: dict[str, object]) -> None:
    print(
        "\n| scenario | jobs | load (1 min) | reach wall [s] | speed-up | reach CPU [s] | "
        "drift + bound wall [s] | drift + bound CPU [s] | evaluations | bound [deg] | "
        "largest inner [deg] | directions with reach | same report |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in found["reach"]:  # type: ignore[union-attr]
        speedup = f"{r['speedup']:.2f}x" if "speedup" in r else "-"
        print(
            f"| {r['scenario']} | {r['jobs']} | {r['load_1min']:.2f} | {r['wall_s']:.2f} | "
            f"{speedup} | {r['cpu_s']:.2f} | "
            f"{r['drift_bound_wall_s']:.2f} | {r['drift_bound_cpu_s']:.2f} | "
            f"{r['evaluations']} | {r['bound_deg']:.3g} | {r['largest_inner_deg']:.3g} | "
            f"{r['directions_with_reach']}/{r['directions']} | "
            f"{'yes' if r['same_report'] else 'NO'} |"
        )
    print(
        "\n| `freefloat reach SCENARIO -q`, fresh process | runs | median wall [s] (target <= 2) |"
    )
    print("|---|---:|---:|")
    for c in found["commands"]:  # type: ignore[union-attr]
        print(f"| {c['scenario']} | {c['runs']} | {c['wall_s']:.2f} |")
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
    parser.add_argument("--dual-goals", type=int, default=20, help="dual UR5 goals planned")
    parser.add_argument("--no-panda", action="store_true", help="skip the Panda servicer")
    parser.add_argument(
        "--jobs",
        type=int,
        nargs="+",
        help="worker processes to time each scenario with (default: the default jobs, then 1)",
    )
    parser.add_argument("--markdown", type=Path, help="also write the tables, stamped")
    args = parser.parse_args()
    found = bench_reachable(
        args.goals,
        panda=not args.no_panda,
        runs=args.runs,
        kinova_goals=args.kinova_goals,
        jobs=None if args.jobs is None else tuple(args.jobs),
        dual_goals=args.dual_goals,
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
