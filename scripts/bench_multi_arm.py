"""Benchmark section of scripts/bench.py: many joints and two arms (issue 24).

- Robonaut 2's two 7-joint arms on its floating torso (``../shared/real-arms/r2_dualarm.urdf``
  relative to the repository, when present; 14 joints, none fixed): "keep the torso still",
  both arms move and the torso ends at its start attitude. Two requests: joint goals for both
  arms, and a Cartesian goal for the right palm with the left arm held (inverse kinematics of
  both palms' chains, then the plan). Target: a verified plan in at most 2 s.
- Generated serial chains of 14, 18 and 24 joints (bench.py's chains: random axes, 3 kg links
  on a 200 kg base, with effort limits of 1000 N m instead of 10 so that the motion is within
  them) asked for a 3-axis attitude change in 20 s: planned or refused, with the residual
  evaluations spent against the counted budget (``SolveOptions.max_evaluations`` per freedom
  distribution).
- The shipped dual-arm scenario (two UR5 on one box, clearance between the arms checked).

Times are medians of ``runs`` runs in this process (wall clock, after a warm-up run); the
evaluation counts are the same on any machine. Run: python scripts/bench.py --multi-arm-only
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

import freefloat as ff

#: The real robots, beside the repository (``$FREEFLOAT_REAL_ARMS`` overrides the folder).
REAL_ARMS = Path(
    os.environ.get("FREEFLOAT_REAL_ARMS")
    or Path(__file__).resolve().parents[2] / "shared" / "real-arms"
)
SCENARIOS = Path(__file__).resolve().parents[1] / "robots" / "scenarios"
R2_PALMS = ["r2/left_palm", "r2/right_palm"]


def _median(fn: Any, runs: int) -> tuple[float, Any]:
    fn()  # warm-up (model caches)
    times, result = [], None
    for _ in range(runs):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def _outcome(scenario: ff.Scenario) -> dict[str, Any]:
    try:
        plan = ff.plan(scenario)
    except ff.FreeFloatError as exc:
        return {"result": f"refused: {str(exc)[:90]}", "evaluations": None, "verified": False}
    return {
        "result": "planned",
        "evaluations": plan.solver.evaluations,
        "verified": plan.verification.passed,
        "freedom": sum(plan.solver.freedom.values()),
    }


def _joints(values: dict[str, float]) -> str:
    return "{ " + ", ".join(f'"{k}" = {v!r}' for k, v in values.items()) + " }"


def r2_scenarios(folder: Path) -> dict[str, ff.Scenario]:
    """The two R2 requests, written as scenario files (degrees) and read back."""
    urdf = REAL_ARMS / "r2_dualarm.urdf"
    robot = ff.load_robot(urdf, R2_PALMS)
    start = {j.name: float(np.degrees(0.5 * (j.lower + j.upper))) for j in robot.joints}
    goal = {
        j.name: start[j.name] + float(np.degrees(0.125 * (j.upper - j.lower))) for j in robot.joints
    }
    head = f'duration = 10.0\nend_effectors = {R2_PALMS!r}\n[robot]\nurdf = "{urdf}"\n'
    head = head.replace("'", '"')
    state = f"[start]\njoints = {_joints(start)}\n"
    goal_q = robot.vector({k: np.radians(v) for k, v in goal.items()})
    right = ff.MomentumMap(robot).end_effector_pose(goal_q, ff.quat_from_zyx(0.0), R2_PALMS[1])
    texts = {
        "joint goals": f"{head}{state}[goal]\njoints = {_joints(goal)}\n",
        "right palm Cartesian, left held": (
            f"{head}{state}[goal]\n"
            f'[goal.end_effectors."r2/right_palm"]\nxyz = {right.translation.tolist()!r}\n'
        ),
    }
    scenarios = {}
    for name, text in texts.items():
        path = folder / f"r2_{len(scenarios)}.toml"
        path.write_text(text)
        scenarios[name] = ff.Scenario.from_toml(path)
    return scenarios


def chain_scenario(folder: Path, n: int, chain_urdf: Any) -> ff.Scenario:
    """An n-joint generated chain asked for a 3-axis attitude change of a few degrees."""
    path = folder / f"chain{n}.urdf"
    path.write_text(chain_urdf(n).replace('effort="10"', 'effort="1000"'))
    robot = ff.load_robot(path)
    start = {j: 0.3 * np.sin(i + 1.0) for i, j in enumerate(robot.joint_names)}
    goal = {j: v + 0.4 * np.cos(i + 2.0) for i, (j, v) in enumerate(start.items())}
    return ff.Scenario(
        robot,
        20.0,
        start,
        goal,
        goal_attitude=ff.quat_from_zyx(*np.radians([3.0, -2.0, 2.0])),
    )


def bench_multi_arm(runs: int, chain_urdf: Any) -> list[dict[str, Any]]:
    """The rows of the section (see the module docstring)."""
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if (REAL_ARMS / "r2_dualarm.urdf").is_file():
            for name, scenario in r2_scenarios(folder).items():
                seconds, outcome = _median(lambda s=scenario: _outcome(s), runs)
                rows.append({"case": f"R2 14 joints, torso still: {name}", "s": seconds, **outcome})
        else:
            rows.append({"case": "R2 (../shared/real-arms absent)", "s": None, "result": "skipped"})
        for n in (14, 18, 24):
            scenario = chain_scenario(folder, n, chain_urdf)
            start = time.perf_counter()
            outcome = _outcome(scenario)
            rows.append(
                {"case": f"{n}-joint chain, 3-axis", "s": time.perf_counter() - start, **outcome}
            )
        scenario = ff.Scenario.from_toml(SCENARIOS / "dual_ur5_servicer.toml")
        start = time.perf_counter()
        outcome = _outcome(scenario)
        rows.append(
            {"case": "dual UR5 servicer (shipped)", "s": time.perf_counter() - start, **outcome}
        )
    return rows


def print_multi_arm(rows: list[dict[str, Any]], budget: int) -> None:
    print(f"\nmany joints and two arms (evaluation budget {budget} per freedom distribution)")
    print("| case | time [s] | result | verified | evaluations | free coefficients |")
    print("|---|---|---|---|---|---|")
    for row in rows:
        seconds = "-" if row.get("s") is None else f"{row['s']:.2f}"
        print(
            f"| {row['case']} | {seconds} | {row['result']} | {row.get('verified', '-')} | "
            f"{row.get('evaluations') or '-'} | {row.get('freedom', '-')} |"
        )
