"""Benchmark: freefloat against a straightforward baseline, side by side in one run.

Problems: the worked example (planar, one free coefficient), the same motion with three free
coefficients (minimum norm), and a three-axis attitude change for each shipped servicer. Each is
solved two ways:

- freefloat: ``build_problem`` + ``solve`` (exact Jacobians, Gauss/Magnus quadrature, the planar
  cosine-polynomial map);
- baseline, written here as a user following the paper would: the attitude by
  ``scipy.integrate.solve_ivp`` (RK45, rtol 1e-10) with Pinocchio's centroidal map at every
  right-hand-side call, and ``scipy.optimize`` on finite differences (secant for one unknown,
  MINPACK's hybrid method for square systems, SLSQP for minimum norm).

Both use the same free parameters (normalised-time coefficients). Each solution's final attitude
error is then measured by one independent check (DOP853, rtol 1e-13). Times are medians over
several runs after model loading and a warm-up run. Also reported: the cost of one momentum-map
evaluation for serial chains of 2 to 12 joints, and the sweep runner: the 81-job yaw sweep of
the worked example (automatic freedom, 201 samples) on 1 and 2 local worker processes, and the
runner's overhead per job against planning the same jobs one by one in this process.

Run: python scripts/bench.py [--runs N] [--json FILE] [--sweep-only]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import statistics
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp
from scipy.optimize import minimize, newton, root

import freefloat as ff
from freefloat.physics import attitude as att

ROBOTS = Path(ff.default_scenario_path()).parent


@dataclass
class Case:
    name: str
    scenario: ff.Scenario
    extra: list[int]


def cases() -> list[Case]:
    worked = ff.Scenario.from_toml(ROBOTS / "worked_example.toml")
    panda = ff.Scenario.from_toml(ROBOTS / "panda_servicer.toml")
    ur5 = ff.Scenario.from_toml(ROBOTS / "ur5_servicer.toml")
    return [
        Case("worked example (planar, 1 free)", worked, [0, 1]),
        Case("planar, 3 free (min norm)", worked, [2, 1]),
        Case("panda servicer 3-axis (3 free)", panda, [1, 1, 1, 0, 0, 0, 0]),
        Case("ur5 servicer 3-axis (3 free)", ur5, [1, 1, 1, 0, 0, 0]),
    ]


def problem_of(case: Case) -> ff.Problem:
    s = case.scenario
    return ff.build_problem(
        s.robot, s.start, s.goal, s.start_attitude, s.goal_attitude, s.duration, extra=case.extra
    )


# ---- the baseline ---------------------------------------------------------------------------


class Baseline:
    """What a user following the paper would write (see the module docstring)."""

    def __init__(self, case: Case) -> None:
        self.case = case
        s = case.scenario
        self.robot = s.robot
        self.model, self.data = s.robot.model, s.robot.model.createData()
        self.family = ff.PathFamily.with_extra(s.start, s.goal, case.extra)
        self.T = s.duration
        self.planar = ff.is_planar(s.robot)
        self.map_evaluations = 0
        self.evaluations = 0

    def f1(self, joints: np.ndarray) -> np.ndarray:
        q = self.robot.configuration(joints)
        ag = pin.computeCentroidalMap(self.model, self.data, q)
        self.map_evaluations += 1
        return -np.linalg.solve(ag[:, :6], ag[:, 6:])[3:]

    def final_quaternion(self, beta: np.ndarray) -> np.ndarray:
        self.evaluations += 1
        s = self.case.scenario

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            path = self.family.at_times(beta, np.array([t]), self.T)
            omega = self.f1(path.q[0]) @ path.qd[0]
            return 0.5 * att.quat_multiply(y, np.concatenate([omega, [0.0]]))

        sol = solve_ivp(rhs, (0.0, self.T), s.start_attitude, method="RK45", rtol=1e-10, atol=1e-12)
        end = sol.y[:, -1]
        return end / np.linalg.norm(end)

    def residual(self, beta: np.ndarray) -> np.ndarray:
        reached = self.final_quaternion(np.atleast_1d(beta))
        rel = att.quat_log(
            att.quat_multiply(att.quat_conjugate(self.case.scenario.goal_attitude), reached)
        )
        if self.planar:
            return rel[2:3]
        return rel

    def solve(self) -> np.ndarray:
        n = self.family.n_free
        if n == 1:
            return np.array(
                [
                    newton(
                        lambda b: self.residual(np.array([b]))[0],
                        0.0,
                        x1=1.0,
                        tol=1e-12,
                        maxiter=50,
                    )
                ]
            )
        if (1 if self.planar else 3) == n:
            return np.asarray(root(self.residual, np.zeros(n), method="hybr", tol=1e-13).x)
        result = minimize(
            lambda b: 0.5 * float(b @ b),
            np.zeros(n),
            jac=lambda b: b,
            method="SLSQP",
            constraints=[{"type": "eq", "fun": self.residual}],
            options={"ftol": 1e-14, "maxiter": 100},
        )
        return np.asarray(result.x)


# ---- independent check ----------------------------------------------------------------------


def attitude_error(case: Case, beta: np.ndarray) -> float:
    """Final attitude error (rad) of a solution, by DOP853 at rtol 1e-13 (one judge for both)."""
    s = case.scenario
    family = ff.PathFamily.with_extra(s.start, s.goal, case.extra)
    mmap = ff.MomentumMap(s.robot)

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        path = family.at_times(beta, np.array([t]), s.duration)
        omega = mmap.f1(path.q[0]) @ path.qd[0]
        return 0.5 * att.quat_multiply(y, np.concatenate([omega, [0.0]]))

    sol = solve_ivp(
        rhs, (0.0, s.duration), s.start_attitude, method="DOP853", rtol=1e-13, atol=1e-14
    )
    end = sol.y[:, -1] / np.linalg.norm(sol.y[:, -1])
    return att.geodesic_angle(end, s.goal_attitude)


def timed(fn, runs: int) -> tuple[float, object]:  # type: ignore[no-untyped-def]
    fn()  # warm-up
    times, result = [], None
    for _ in range(runs):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def bench_cases(runs: int, baseline_runs: int) -> list[dict[str, object]]:
    rows = []
    for case in cases():

        def run_freefloat(case: Case = case) -> tuple[ff.Problem, ff.Solution]:
            problem = problem_of(case)
            solution = ff.solve(problem)
            return problem, solution

        t_ff, (problem, solution) = timed(run_freefloat, runs)  # type: ignore[misc]
        base = Baseline(case)
        t_base, beta_base = timed(base.solve, baseline_runs)
        per_run_maps = base.map_evaluations / (baseline_runs + 1)
        rows.append(
            {
                "problem": case.name,
                "freefloat_ms": t_ff * 1e3,
                "baseline_ms": t_base * 1e3,
                "ratio": t_base / t_ff,
                "freefloat_map_evaluations": problem.map_evaluations,
                "baseline_map_evaluations": round(per_run_maps),
                "freefloat_error_rad": attitude_error(case, solution.beta),
                "baseline_error_rad": attitude_error(case, np.asarray(beta_base)),
            }
        )
        print(f"  done: {case.name}", flush=True)
    return rows


def chain_urdf(n: int) -> str:
    rng = np.random.default_rng(n)
    parts = [
        '<?xml version="1.0"?><robot name="chain"><link name="base"><inertial>'
        '<mass value="200"/><inertia ixx="30" iyy="30" izz="30" ixy="0" ixz="0" iyz="0"/>'
        "</inertial></link>"
    ]
    parent = "base"
    for i in range(n):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        parts.append(
            f'<joint name="j{i}" type="revolute"><parent link="{parent}"/><child link="l{i}"/>'
            f'<origin xyz="0.4 0.05 0.02"/><axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>'
            '<limit lower="-3" upper="3" effort="10" velocity="2"/></joint>'
            f'<link name="l{i}"><inertial><origin xyz="0.2 0 0"/><mass value="3"/>'
            '<inertia ixx="0.01" iyy="0.05" izz="0.05" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        )
        parent = f"l{i}"
    return "".join(parts) + "</robot>"


def bench_scaling(tmp: Path) -> list[dict[str, float]]:
    rows = []
    for n in range(2, 13):
        path = tmp / f"chain{n}.urdf"
        path.write_text(chain_urdf(n))
        mmap = ff.MomentumMap(ff.load_robot(path))
        rng = np.random.default_rng(0)
        q, qd = rng.uniform(-1, 1, (384, n)), rng.uniform(-1, 1, (384, n))
        t, _ = timed(lambda: mmap.base_rates(q, qd), 5)  # noqa: B023
        t_d, _ = timed(lambda: mmap.base_rates(q, qd, derivatives=True), 5)  # noqa: B023
        rows.append(
            {"joints": n, "map_us": t / 384 * 1e6, "map_and_derivative_us": t_d / 384 * 1e6}
        )
    return rows


def bench_sweep() -> dict[str, float]:
    """Wall time of the 81-job yaw sweep on 1 and 2 workers; runner overhead per job."""
    data = Path(__file__).resolve().parents[1] / "tests" / "data"
    spec = ff.SweepSpec.from_dict(
        {
            "scenario": "worked_example_auto.toml",
            "axis": [
                {"key": "goal.base_zyx_deg.0", "values": {"start": -55.0, "stop": 25.0, "num": 81}}
            ],
        },
        relative_to=data,
    )
    walls = {}
    for workers in (1, 2):
        start = time.perf_counter()
        rows = ff.sweep(spec, workers=workers, progress=False)
        walls[workers] = time.perf_counter() - start
    # the same jobs planned one by one here, with the robot loaded once (the runner's ideal)
    robot = ff.Scenario.from_toml(data / "worked_example_auto.toml").robot
    scenarios = [
        replace(ff.Scenario.from_dict(job.data, relative_to=data), robot=robot)
        for job in spec.jobs()
    ]
    for scenario in scenarios[:3]:  # warm-up
        try_plan(scenario)
    start = time.perf_counter()
    for scenario in scenarios:
        try_plan(scenario)
    direct = time.perf_counter() - start
    worked = ff.Scenario.from_toml(ff.default_scenario_path())
    one_plan = statistics.median(timed_once(lambda: ff.plan(worked)) for _ in range(7))
    n = len(rows)
    overhead = (walls[1] - direct) / n
    return {
        "jobs": n,
        "planned": sum(r.status == "planned" for r in rows),
        "wall_1_worker_s": walls[1],
        "wall_2_workers_s": walls[2],
        "speed_up_2_over_1": walls[1] / walls[2],
        "direct_s": direct,
        "overhead_per_job_ms": 1e3 * overhead,
        "worked_example_plan_ms": 1e3 * one_plan,
        "overhead_per_plan_percent": 100.0 * overhead / one_plan,
    }


def try_plan(scenario: ff.Scenario) -> None:
    with contextlib.suppress(ff.FreeFloatError):
        ff.plan(scenario)


def timed_once(fn) -> float:  # type: ignore[no-untyped-def]
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (
        f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, "
        f"Pinocchio {pin.__version__}, freefloat {ff.__version__}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=9, help="freefloat runs per problem")
    parser.add_argument("--baseline-runs", type=int, default=3, help="baseline runs per problem")
    parser.add_argument("--json", type=Path, help="also write the tables as JSON")
    parser.add_argument("--sweep-only", action="store_true", help="only the sweep section")
    args = parser.parse_args()
    print(f"machine: {machine()}")
    sweep = bench_sweep()
    print(
        f"sweep: {sweep['jobs']} jobs ({sweep['planned']} planned); 1 worker "
        f"{sweep['wall_1_worker_s']:.1f} s, 2 workers {sweep['wall_2_workers_s']:.1f} s "
        f"({sweep['speed_up_2_over_1']:.2f}x); the same jobs planned one by one in this process "
        f"{sweep['direct_s']:.1f} s; runner overhead {sweep['overhead_per_job_ms']:.1f} ms/job "
        f"= {sweep['overhead_per_plan_percent']:.1f} % of a worked example plan "
        f"({sweep['worked_example_plan_ms']:.1f} ms)"
    )
    if args.sweep_only:
        return
    rows = bench_cases(args.runs, args.baseline_runs)
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        scaling = bench_scaling(Path(tmp))

    print()
    print(
        "| problem | freefloat [ms] | baseline [ms] | baseline/freefloat | map evals ff / base "
        "| error ff [rad] | error base [rad] |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(
            f"| {r['problem']} | {r['freefloat_ms']:.1f} | {r['baseline_ms']:.0f} | "
            f"{r['ratio']:.0f}x | {r['freefloat_map_evaluations']} / "
            f"{r['baseline_map_evaluations']} | {r['freefloat_error_rad']:.1e} | "
            f"{r['baseline_error_rad']:.1e} |"
        )
    print()
    print("| joints | map [us/eval] | map + derivative [us/eval] |")
    print("|---:|---:|---:|")
    for r in scaling:
        print(f"| {r['joints']} | {r['map_us']:.2f} | {r['map_and_derivative_us']:.2f} |")
    if args.json:
        args.json.write_text(
            json.dumps(
                {"machine": machine(), "problems": rows, "map_scaling": scaling, "sweep": sweep},
                indent=1,
            )
        )
        print(f"\nwrote {args.json}")


if __name__ == "__main__":
    main()
