"""Benchmark section (issue 25): speed where users wait, each case a fresh call as a user makes it.

Run through ``scripts/bench.py --speed-only`` (or alone: ``python scripts/bench_speed.py``).
Every timed case is one ``ff.plan`` of a scenario read afresh from its TOML file (new robot
and constraints; only what a user's process keeps between calls is kept: the checked and built
model per URDF text (each robot gets its own copy), the parsed collision geometry and mesh keys
per URDF, the hulls and triangles per mesh file, the checked pairs per SRDF file and kinematic
tree, the solvers' and verification's collision models per source (URDF, tree, mesh and SRDF
files, obstacles), and the imported modules). Rounds are paired: with and without
clearance one after the other in each round (the order alternating), so that both see the same
load; the tables give medians over the rounds and the median of the per-round ratios.

- the shipped servicers with clearance against the same plan without (target <= 1.5x), with
  the stage times of the plan with clearance (solve, sample, verify; from the plan's record);
- the worked example: the whole verified plan against its solve (target <= 2x), and against
  the bare solve of ``scripts/bench.py``'s baseline in the same rounds (target >= 10x faster);
- the Panda servicer's goal turned 1, 3 and 10 deg about each axis from the quintic path's
  attitude, with clearance (target: median <= 0.1 s, worst <= 0.5 s);
- the Panda servicer's goal rolled 65 deg, with clearance (target: refused in <= 1 s; it is
  reachable, so it plans), and rolled 180 deg (beyond the arm's reach: refused);
- ``min_effort`` on the Panda servicer (target <= 0.5 s).
"""

from __future__ import annotations

import dataclasses
import statistics
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

import freefloat as ff
from freefloat.physics import attitude as att

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "robots" / "scenarios"
SERVICERS = ("panda_servicer", "ur5_servicer", "dual_ur5_servicer")


def fresh(name: str, clearance: bool = True) -> ff.Scenario:
    """The shipped scenario read afresh, with or without its clearance check."""
    scenario = ff.Scenario.from_toml(SCENARIOS / f"{name}.toml")
    if clearance:
        return scenario
    return dataclasses.replace(scenario, safety=dataclasses.replace(scenario.safety, check=False))


def _time(call: Callable[[], object]) -> tuple[float, object]:
    """Seconds one call takes, and what it returned (or the error it raised)."""
    start = time.perf_counter()
    try:
        out: object = call()
    except ff.FreeFloatError as exc:
        out = exc
    return time.perf_counter() - start, out


def paired(first: Callable[[], object], second: Callable[[], object], rounds: int) -> dict:
    """Medians (s) of two calls timed side by side in each round, order alternating.

    ``outs``: what the first call returned in every round (its stage times are medians too).
    """
    a, b, ratios, outs = [], [], [], []
    for k in range(rounds):
        if k % 2 == 0:
            ta, out = _time(first)
            tb, _ = _time(second)
        else:
            tb, _ = _time(second)
            ta, out = _time(first)
        a.append(ta)
        b.append(tb)
        ratios.append(ta / tb)
        outs.append(out)
    return {
        "first_s": statistics.median(a),
        "second_s": statistics.median(b),
        "ratio": statistics.median(ratios),
        "outs": outs,
    }


def bench_servicers(rounds: int) -> list[dict[str, object]]:
    """Per shipped servicer: the whole plan with clearance against without, paired rounds."""
    rows = []
    ff.plan(fresh("worked_example"))  # imports and first-call costs out of the way
    for name in SERVICERS:
        ff.plan(fresh(name))  # the hulls of its meshes, as a user's process keeps them
        found = paired(
            lambda n=name: ff.plan(fresh(n)), lambda n=name: ff.plan(fresh(n, False)), rounds
        )
        records = [p.solver for p in found["outs"] if isinstance(p, ff.Plan)]

        def stage(field: str, records: list = records) -> float:
            """Median of one stage's time over the rounds' plans (ms)."""
            if not records:
                return float("nan")
            return 1e3 * statistics.median(getattr(r, field) for r in records)

        rows.append(
            {
                "robot": name,
                "with_ms": 1e3 * found["first_s"],
                "without_ms": 1e3 * found["second_s"],
                "ratio": found["ratio"],
                "solve_ms": stage("solve_time_s"),
                "sample_ms": stage("sample_time_s"),
                "verify_ms": stage("verify_time_s"),
            }
        )
        print(f"  done: servicer {name}: {rows[-1]}", flush=True)
    return rows


def bench_worked(rounds: int, baseline: Callable[[], object] | None = None) -> dict[str, float]:
    """The worked example: whole verified plan, and its stages from the plan's record (ms).

    With ``baseline`` (the bare solve of ``scripts/bench.py``'s baseline: SciPy's secant on
    ``solve_ivp``), that solve is timed in the same rounds, after each plan.
    """
    whole, solve, sample, verify, bare = [], [], [], [], []
    for _ in range(rounds):
        elapsed, plan = _time(lambda: ff.plan(fresh("worked_example")))
        assert isinstance(plan, ff.Plan)
        whole.append(elapsed)
        solve.append(plan.solver.solve_time_s)
        sample.append(plan.solver.sample_time_s)
        verify.append(plan.solver.verify_time_s)
        if baseline is not None:
            bare.append(_time(baseline)[0])
    med = statistics.median
    return {
        "whole_ms": 1e3 * med(whole),
        "solve_ms": 1e3 * med(solve),
        "sample_ms": 1e3 * med(sample),
        "verify_ms": 1e3 * med(verify),
        "baseline_ms": 1e3 * med(bare) if bare else float("nan"),
    }


def turned(name: str, rotvec: np.ndarray, from_quintic: bool = True) -> ff.Scenario:
    """The scenario read afresh with its goal attitude turned by ``rotvec`` (rad, body axes).

    From the attitude the plain quintic path reaches (the reach table's goals), or from the
    scenario's own goal attitude.
    """
    scenario = fresh(name)
    if from_quintic:
        problem = ff.problem_from_scenario(scenario, extra=[1, 1, 1] + [0] * (scenario.robot.n - 3))
        origin = problem.achieved(np.zeros(problem.n_free))
    else:
        origin = scenario.goal_attitude
    return dataclasses.replace(
        scenario, goal_attitude=att.quat_multiply(origin, att.quat_exp(rotvec))
    )


def bench_reach_goals() -> list[dict[str, object]]:
    """The Panda servicer, goals 1, 3, 10 deg about each axis of the quintic attitude."""
    rows = []
    for degrees in (1.0, 3.0, 10.0):
        for k, axis in enumerate("xyz"):
            rotvec = np.zeros(3)
            rotvec[k] = np.radians(degrees)
            elapsed, out = _time(lambda r=rotvec: ff.plan(turned("panda_servicer", r)))
            rows.append(
                {
                    "goal": f"{degrees:g} deg {axis}",
                    "time_s": elapsed,
                    "outcome": "planned" if isinstance(out, ff.Plan) else type(out).__name__,
                }
            )
            print(f"  done: reach {rows[-1]}", flush=True)
    return rows


def bench_roll(degrees: float = 65.0) -> dict[str, object]:
    """The Panda servicer's goal rolled ``degrees`` about x from its stated goal, clearance on."""
    rotvec = np.radians([degrees, 0, 0])
    elapsed, out = _time(lambda: ff.plan(turned("panda_servicer", rotvec, False)))
    outcome = "planned" if isinstance(out, ff.Plan) else f"{type(out).__name__}"
    return {"time_s": elapsed, "outcome": outcome}


def bench_min_effort(rounds: int) -> dict[str, float]:
    """``min_effort`` on the Panda servicer against ``min_norm``, paired rounds (s)."""
    found = paired(
        lambda: ff.plan(fresh("panda_servicer"), objective="min_effort"),
        lambda: ff.plan(fresh("panda_servicer")),
        rounds,
    )
    return {"min_effort_s": found["first_s"], "min_norm_s": found["second_s"]}


def print_speed(found: dict[str, object]) -> None:
    """The section's tables as Markdown."""
    print("\n### Speed where users wait (issue 25): fresh calls, paired rounds\n")
    print(
        "| servicer | plan with clearance ms | without ms | ratio (target <= 1.5) | "
        "solve ms | sample ms | verify ms |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|")
    for r in found["servicers"]:  # type: ignore[attr-defined]
        print(
            f"| {r['robot']} | {r['with_ms']:.0f} | {r['without_ms']:.0f} | {r['ratio']:.2f}x | "
            f"{r['solve_ms']:.0f} | {r['sample_ms']:.0f} | {r['verify_ms']:.0f} |"
        )
    w = found["worked"]
    print(
        "\n| worked example | whole verified plan ms | solve ms | sample ms | verify ms | "
        "whole / solve (target <= 2) | baseline bare solve ms | baseline / whole "
        "(target >= 10) |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    print(
        f"| worked_example | {w['whole_ms']:.1f} | {w['solve_ms']:.1f} | {w['sample_ms']:.1f} | "  # type: ignore[index]
        f"{w['verify_ms']:.1f} | {w['whole_ms'] / w['solve_ms']:.1f}x | "  # type: ignore[index]
        f"{w['baseline_ms']:.0f} | {w['baseline_ms'] / w['whole_ms']:.1f}x |"  # type: ignore[index]
    )
    reach = found["reach"]
    times = [r["time_s"] for r in reach]  # type: ignore[attr-defined]
    print("\n| Panda servicer goal, with clearance | time s | outcome |")
    print("|---|---:|---|")
    for r in reach:  # type: ignore[attr-defined]
        print(f"| {r['goal']} | {r['time_s']:.2f} | {r['outcome']} |")
    print(
        f"| **median / worst (targets 0.1 / 0.5 s)** | {statistics.median(times):.2f} / "
        f"{max(times):.2f} | |"
    )
    roll = found["roll"]
    print(
        f"| rolled 65 deg from the stated goal (target: refused in <= 1 s) | "
        f"{roll['time_s']:.2f} | {roll['outcome']} |"
    )
    far = found["roll_far"]
    print(
        f"| rolled 180 deg from the stated goal (out of reach) | "
        f"{far['time_s']:.2f} | {far['outcome']} |"
    )  # type: ignore[index]
    effort = found["min_effort"]
    print("\n| Panda servicer, with clearance | min_effort s (target <= 0.5) | min_norm s |")
    print("|---|---:|---:|")
    print(f"| panda_servicer | {effort['min_effort_s']:.2f} | {effort['min_norm_s']:.2f} |")  # type: ignore[index]


def bench_speed(
    rounds: int, roll: bool = True, baseline: Callable[[], object] | None = None
) -> dict[str, object]:
    """Every table of the section (``baseline``: the worked example's bare baseline solve)."""
    return {
        "servicers": bench_servicers(rounds),
        "worked": bench_worked(rounds, baseline),
        "reach": bench_reach_goals(),
        "roll": bench_roll() if roll else {"time_s": float("nan"), "outcome": "not run"},
        "roll_far": bench_roll(180.0),
        "min_effort": bench_min_effort(max(1, rounds // 3)),
    }


if __name__ == "__main__":
    print_speed(bench_speed(5))
