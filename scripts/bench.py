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
several runs after model loading and a warm-up run. Also reported: the whole verified
``ff.plan()`` of each shipped scenario as it stands (automatic freedom where the scenario leaves
it open) with its stage times (solve, sample, verify, from the plan's solver report) against
the baseline's solve of the same motion, and the cost of one momentum-map evaluation for serial
chains of 2 to 12 joints.

Reach table (issue 11): for each shipped servicer, goals at the attitude the plain quintic path
reaches turned by 1, 3 and 10 deg about each base axis, and seeded random directions (1-10
deg); each planned by the multistart search (the old default) and by continuation (the new
one), side by side: solved and verified, time of the search over every freedom distribution
tried (s, one run), residual evaluations of the distribution that solved (or the last
tried). Budgets are counts, so the solved column is the same on any machine; only the times
change.


Sweep (issue 17, with --sweep or --sweep-only): the 81-job yaw sweep of the worked example
(automatic freedom, 201 samples) on 1 and 2 local worker processes, and the runner's overhead
per job against planning the same jobs one by one in this process.

Objectives (issue 16, with --objectives or --objectives-only): the worked example planned with
each objective (median plan time, integral of |tau|^2 measured from the plan's polynomials by
a 96-node Gauss rule through the verification's torque function, attitude error, freedom used)
against the optimal-control figure quoted in the issue (26.6 N^2 m^2 s); the same minimisation
at fixed freedom k = 1..4 with exact gradients and with SciPy's finite differences side by
side; and the Panda servicer's scenario with min_norm against min_effort.

Many joints and two arms (issue 24, with --multi-arm-only; scripts/bench_multi_arm.py):
Robonaut 2's 14 joints keeping the torso still, generated chains of 14 to 24 joints, the shipped
dual-arm servicer. True hulls and the certified clearance check (--clearance-only;
scripts/bench_clearance.py).

Paths (issue 23, with --paths or --paths-only): the orthonormal path basis against the monomial
basis before it, side by side (scripts/bench_paths.py).

Speed where users wait (issue 25, with --speed-only; scripts/bench_speed.py): every case a
fresh ff.plan as a user makes it, paired rounds with and without clearance, medians.

freefloat reach (issue 28, with --reachable-only; scripts/bench_reachable.py): its time on the
shipped servicers and a composed Kinova servicer, and 50 goals sampled inside its inner set
planned with ff.plan.

The spacecraft's swing on the way (with --swing-only; scripts/bench_swing.py): a pure
reorientation of the Panda servicer and, where ../shared/real-arms/ is present, of ETS-VII and
Canadarm2 holding a 5 t payload, planned without and with [constraints.base_swing] bounds.

Run: python scripts/bench.py [--runs N] [--json FILE] [--markdown FILE] [--reach-only]
     [--random N] [--sweep] [--sweep-only] [--multi-arm-only] [--clearance-only] [--paths]
     [--paths-only] [--paths-baseline REV] [--reachable-only] [--speed-only [--no-roll]]
     [--swing-only]

``--markdown FILE`` also writes the tables as Markdown, each table preceded by its stamp: the
date, the machine (CPU, cores), the Python, Pinocchio, numpy and freefloat versions, the load
average and the command, so that a reader can tell runs apart and reproduce one
(docs/benchmarks.md).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import io
import json
import math
import os
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp
from scipy.optimize import minimize, newton, root

import freefloat as ff
from bench_paths import BASELINE_REVISION, bench_paths, print_paths
from bench_stamp import machine, stamped_markdown
from freefloat.physics import attitude as att
from freefloat.robot.collision import CollisionModel, known_srdf

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


def bench_whole(runs: int, baseline_ms: dict[str, float]) -> list[dict[str, object]]:
    """Whole verified ``plan()`` per shipped scenario, with its stage times (ms, medians)."""
    rows = []
    for name, case in (
        ("worked example", "worked example (planar, 1 free)"),
        ("panda servicer", "panda servicer 3-axis (3 free)"),
        ("ur5 servicer", "ur5 servicer 3-axis (3 free)"),
    ):
        scenario = ff.Scenario.from_toml(ROBOTS / f"{name.replace(' ', '_')}.toml")
        ff.plan(scenario)  # warm-up
        whole, stages = [], []
        for _ in range(runs):
            start = time.perf_counter()
            p = ff.plan(scenario)
            whole.append(time.perf_counter() - start)
            r = p.solver
            stages.append((r.solve_time_s, r.sample_time_s, r.verify_time_s))
        solve, sample, verify = (statistics.median(c) * 1e3 for c in zip(*stages, strict=True))
        plan_ms = statistics.median(whole) * 1e3
        rows.append(
            {
                "scenario": name,
                "plan_ms": plan_ms,
                "solve_ms": solve,
                "sample_ms": sample,
                "verify_ms": verify,
                "plan_over_solve": plan_ms / solve,
                "baseline_solve_ms": baseline_ms[case],
                "baseline_over_plan": baseline_ms[case] / plan_ms,
            }
        )
        print(f"  done: whole plan, {name}", flush=True)
    return rows


UR5_PAN = """robot = "ur5_servicer"
duration = 10.0
[start]
joints = { shoulder_pan_joint = -90.0, shoulder_lift_joint = -45.0, elbow_joint = 120.0, \
wrist_1_joint = -90.0, wrist_2_joint = 0.0, wrist_3_joint = 0.0 }
[goal]
joints = { shoulder_pan_joint = 90.0, shoulder_lift_joint = -45.0, elbow_joint = 120.0, \
wrist_1_joint = -90.0, wrist_2_joint = 0.0, wrist_3_joint = 0.0 }
base_zyx_deg = [-17.29, 1.5255, -33.449]
"""


def bench_collision(runs: int) -> list[dict[str, object]]:
    """Whole verified plan with clearance (the default) and without it (ms, medians)."""
    import tempfile

    from freefloat.problem.constraints import scenario_constraints

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        pan = Path(tmp) / "ur5_pan.toml"
        pan.write_text(UR5_PAN)
        cases = [
            ("panda servicer (shipped)", ROBOTS / "panda_servicer.toml"),
            ("ur5 servicer (shipped)", ROBOTS / "ur5_servicer.toml"),
            ("ur5 pan past the hull (issue 13)", pan),
        ]
        for label, path in cases:
            scenario = ff.Scenario.from_toml(path)
            aware = scenario_constraints(scenario)
            plain = ff.default_constraints()
            results = {}
            for key, constraints in (("with", aware), ("without", plain)):
                ff.plan(scenario, constraints=constraints)  # warm-up
                times = []
                for _ in range(runs):
                    start = time.perf_counter()
                    p = ff.plan(scenario, constraints=constraints)
                    times.append(time.perf_counter() - start)
                results[key] = (statistics.median(times) * 1e3, p)
            robot = scenario.robot
            model = CollisionModel(robot, known_srdf(robot))
            q = results["without"][1].joint_positions(np.linspace(0.0, scenario.duration, 801))
            unchecked = min(float(model.distances(x).values.min()) for x in q)
            clearance = results["with"][1].verification["clearance"].detail
            rows.append(
                {
                    "case": label,
                    "with_ms": results["with"][0],
                    "without_ms": results["without"][0],
                    "ratio": results["with"][0] / results["without"][0],
                    "clearance_with": clearance,
                    "min_clearance_without_m": unchecked,
                }
            )
            print(f"  done: collision, {label}", flush=True)
    return rows


def print_collision(rows: list[dict[str, object]]) -> None:
    print()
    print(
        "| case | plan with clearance [ms] | without [ms] | with/without "
        "| min clearance without [m] | clearance check with |"
    )
    print("|---|---:|---:|---:|---:|---|")
    for r in rows:
        print(
            f"| {r['case']} | {r['with_ms']:.0f} | {r['without_ms']:.0f} | {r['ratio']:.2f}x "
            f"| {r['min_clearance_without_m']:.4f} | {r['clearance_with']} |"
        )


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


def reach_goals(scenario: ff.Scenario, random_directions: int) -> list[tuple[str, np.ndarray]]:
    """(label, goal quaternion): the quintic attitude turned about axes and random directions."""
    problem = problem_of(Case("", scenario, [1, 1, 1] + [0] * (scenario.robot.n - 3)))
    quintic = problem.achieved(np.zeros(problem.n_free))
    goals = []
    for degrees in (1.0, 3.0, 10.0):
        for k, axis in enumerate("xyz"):
            rotvec = np.zeros(3)
            rotvec[k] = np.radians(degrees)
            goals.append(
                (f"{degrees:g} deg {axis}", att.quat_multiply(quintic, att.quat_exp(rotvec)))
            )
    rng = np.random.default_rng(11)
    for i in range(random_directions):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        degrees = float(rng.uniform(1.0, 10.0))
        rotvec = np.radians(degrees) * axis
        goals.append(
            (f"random {i + 1}: {degrees:.1f} deg", att.quat_multiply(quintic, att.quat_exp(rotvec)))
        )
    return goals


def plan_once(scenario: ff.Scenario, options: ff.SolveOptions) -> dict[str, object]:
    """Search, then sample and verify; the search's time and evaluations."""
    from freefloat.problem.constraints import scenario_constraints
    from freefloat.solvers.search import search

    constraints = scenario_constraints(scenario)  # limits and clearance, as ff.plan does
    start = time.perf_counter()
    try:
        found = search(scenario, options, constraints)
    except ff.FreeFloatError as exc:
        return {"solved": False, "time_s": time.perf_counter() - start, "note": str(exc)[:120]}
    elapsed = time.perf_counter() - start
    evaluations = found.problem.evaluations
    try:
        plan = ff.plan_from_solution(
            found.problem.with_steps(found.solution.steps), found.solution, constraints=constraints
        )
        verified = plan.verification.passed
    except ff.FreeFloatError:
        verified = False
    return {"solved": verified, "time_s": elapsed, "evaluations": evaluations, "note": ""}


def bench_reach(
    random_directions: int, multistart: bool, random_multistart: bool = False
) -> list[dict[str, object]]:
    rows = []
    for name in ("panda_servicer", "ur5_servicer"):
        scenario = ff.Scenario.from_toml(ROBOTS / f"{name}.toml")
        for label, goal in reach_goals(scenario, random_directions):
            case = dataclasses.replace(scenario, goal_attitude=goal)
            row: dict[str, object] = {"robot": name, "goal": label}
            row["continuation"] = plan_once(case, ff.SolveOptions())
            if multistart and (random_multistart or not label.startswith("random")):
                row["multistart"] = plan_once(
                    case, ff.SolveOptions(strategy=ff.Strategy.MULTISTART)
                )
            rows.append(row)
            print(f"  done: {name} {label}: {row}", flush=True)
    return rows


def print_reach(rows: list[dict[str, object]]) -> None:
    def cell(result: object) -> str:
        if not isinstance(result, dict):
            return "- | - | -"
        solved = "yes" if result["solved"] else "no"
        evaluations = result.get("evaluations", "-")
        return f"{solved} | {result['time_s']:.2f} | {evaluations}"

    print()
    print(
        "| robot | goal (from the quintic attitude) | multistart solved | time [s] | evals* "
        "| continuation solved | time [s] | evals* |"
    )
    print("|---|---|---|---:|---:|---|---:|---:|")
    for r in rows:
        print(
            f"| {r['robot']} | {r['goal']} | {cell(r.get('multistart'))} "
            f"| {cell(r['continuation'])} |"
        )
    print("* residual evaluations of the freedom distribution that solved (or the last tried)")
    for key in ("multistart", "continuation"):
        results = [r[key] for r in rows if isinstance(r.get(key), dict)]
        if not results:
            continue
        times = [float(x["time_s"]) for x in results]  # type: ignore[index]
        solved = sum(1 for x in results if x["solved"])  # type: ignore[index]
        print(
            f"{key}: {solved}/{len(results)} planned and verified; time median "
            f"{statistics.median(times):.2f} s, slowest {max(times):.2f} s"
        )


SWEEP_JOBS_IN_ONE_PROCESS = """
import sys, time
from pathlib import Path
import freefloat as ff
from freefloat.sweep.jobs import run_job
data = Path(sys.argv[1])
spec = ff.SweepSpec.from_dict({"scenario": "worked_example_auto.toml", "axis": [{"key":
    "goal.base_zyx_deg.0", "values": {"start": -55.0, "stop": 25.0, "num": 81}}]},
    relative_to=data)
for job in spec.jobs():
    run_job(job)
"""


def bench_sweep(rounds: int = 3) -> dict[str, float]:
    """The 81-job yaw sweep: 1 and 2 workers, and the runner's overhead per job.

    The overhead is measured against the same jobs run one by one by ``run_job`` in a fresh
    process with the workers' settings (one BLAS thread), both as whole processes seen from
    here (start-up, imports and robot loading included on both sides), paired and repeated
    ``rounds`` times (medians): (one-worker sweep - one process) / jobs. The cost of the one
    BLAS thread itself is reported apart (the same process with the default threads).
    """
    import os
    import subprocess
    import sys

    from freefloat.sweep.runner import BLAS_ENV

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

    def one_process(env: dict[str, str]) -> float:
        start = time.perf_counter()
        subprocess.run(
            [sys.executable, "-c", SWEEP_JOBS_IN_ONE_PROCESS, str(data)],
            check=True,
            env={**os.environ, **env},
            capture_output=True,
        )
        return time.perf_counter() - start

    def swept(workers: int) -> float:
        start = time.perf_counter()
        ff.sweep(spec, workers=workers, progress=False)
        return time.perf_counter() - start

    runs: dict[str, list[float]] = {"w1": [], "w2": [], "one": [], "threads": []}
    rows = ff.sweep(spec, workers=1, progress=False)
    for _ in range(rounds):
        runs["w1"].append(swept(1))
        runs["one"].append(one_process(BLAS_ENV))
        runs["w2"].append(swept(2))
        runs["threads"].append(one_process({}))
    med = {k: statistics.median(v) for k, v in runs.items()}
    worked = ff.Scenario.from_toml(ff.default_scenario_path())
    one_plan = statistics.median(timed_once(lambda: ff.plan(worked)) for _ in range(7))
    n = len(rows)
    overhead = (med["w1"] - med["one"]) / n
    return {
        "jobs": n,
        "planned": sum(r.status == "planned" for r in rows),
        "wall_1_worker_s": med["w1"],
        "wall_2_workers_s": med["w2"],
        "speed_up_2_over_1": med["w1"] / med["w2"],
        "one_process_s": med["one"],
        "one_process_default_threads_s": med["threads"],
        "overhead_per_job_ms": 1e3 * overhead,
        "one_blas_thread_per_job_ms": 1e3 * (med["one"] - med["threads"]) / n,
        "worked_example_plan_ms": 1e3 * one_plan,
        "overhead_per_plan_percent": 100.0 * overhead / one_plan,
    }


#: The optimal-control figure the issue quotes for the worked example (N^2 m^2 s).
PEER_EFFORT = 26.6


def effort_of(plan: ff.Plan, robot: ff.Robot) -> float:
    """Integral of |tau|^2 dt (N^2 m^2 s) of a plan, by a 96-node Gauss rule on [0, T]."""
    from freefloat.verify.checks import joint_torque_function

    tau = joint_torque_function(plan, ff.MomentumMap(robot))
    x, w = np.polynomial.legendre.leggauss(96)
    t = 0.5 * plan.duration * (x + 1.0)
    return float(
        0.5
        * plan.duration
        * sum(wi * float(tau(ti) @ tau(ti)) for ti, wi in zip(t, w, strict=True))
    )


def bench_objectives(runs: int = 3) -> dict[str, object]:
    from freefloat.physics.dynamics import inverse_dynamics_batch
    from freefloat.problem.objectives import gauss_legendre
    from freefloat.solvers.optimise import optimise

    worked = ff.Scenario.from_toml(ff.default_scenario_path())
    rows = []
    for name in ff.OBJECTIVES:
        times, plan = [], None
        for _ in range(runs):
            clock = time.perf_counter()
            plan = ff.plan(worked, objective=name)
            times.append(time.perf_counter() - clock)
        assert plan is not None
        rows.append(
            {
                "scenario": "worked_example",
                "objective": name,
                "plan_s": statistics.median(times),
                "effort": effort_of(plan, worked.robot),
                "objective_value": plan.objective.value,
                "attitude_error_rad": plan.base.attitude_error_rad,
                "freedom": dict(plan.solver.freedom),
                "verified": plan.verification.passed,
            }
        )
    panda = ff.Scenario.from_toml(ROBOTS / "panda_servicer.toml")
    for name in ("min_norm", "min_effort"):
        clock = time.perf_counter()
        plan = ff.plan(panda, objective=name)
        rows.append(
            {
                "scenario": "panda_servicer",
                "objective": name,
                "plan_s": time.perf_counter() - clock,
                "effort": effort_of(plan, panda.robot),
                "objective_value": plan.objective.value,
                "attitude_error_rad": plan.base.attitude_error_rad,
                "freedom": dict(plan.solver.freedom),
                "verified": plan.verification.passed,
            }
        )
    # exact gradients against finite differences, same start, same freedom
    gradients = []
    resolved = worked.resolved()
    constraints = ff.default_constraints()
    options = ff.SolveOptions()
    effort = ff.MinEffort()
    s, w = gauss_legendre(effort.nodes)
    for k in (1, 2, 3, 4):
        problem = ff.problem_from_scenario(resolved, extra=[k, k])
        start = ff.solve(problem, options, constraints).beta
        clock = time.perf_counter()
        exact = optimise(problem, start, effort, constraints, options, max_iterations=400)
        exact_s = time.perf_counter() - clock

        def fd_effort(beta: np.ndarray, problem: ff.Problem = problem) -> float:
            path = problem.family.evaluate(beta, s)
            tau = inverse_dynamics_batch(problem.mmap, path.q, path.qd, path.qdd).tau
            return float(w @ (tau**2).sum(axis=1)) / problem.duration**3

        clock = time.perf_counter()
        result = minimize(
            fd_effort,
            start,
            method="SLSQP",
            constraints=[
                {
                    "type": "eq",
                    "fun": lambda b, p=problem: p.residual(b),
                    "jac": lambda b, p=problem: p.jacobian(b),
                }
            ],
            options={"ftol": 1e-12, "maxiter": 400},
        )
        fd_s = time.perf_counter() - clock
        gradients.append(
            {
                "k": k,
                "exact_s": exact_s,
                "exact_effort": exact.value,
                "fd_s": fd_s,
                "fd_effort": float(result.fun),
                "fd_residual_rad": float(np.linalg.norm(problem.residual(result.x))),
            }
        )
    return {"plans": rows, "gradients": gradients}


def print_objectives(found: dict[str, object]) -> None:
    print()
    print(
        "objectives: integral of |tau|^2 [N^2 m^2 s] measured from each plan (96-node Gauss); "
        f"peer figure for the worked example {PEER_EFFORT}"
    )
    print(
        "| scenario | objective | plan [s] | effort | vs min_norm | vs peer | attitude err [rad] "
        "| freedom |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---|")
    plans = found["plans"]
    assert isinstance(plans, list)
    base = {r["scenario"]: r["effort"] for r in plans if r["objective"] == "min_norm"}
    for r in plans:
        peer = (
            f"{100.0 * (r['effort'] / PEER_EFFORT - 1.0):+.1f} %"
            if r["scenario"] == "worked_example"
            else "-"
        )
        used = ", ".join(f"{v}" for v in r["freedom"].values())
        print(
            f"| {r['scenario']} | {r['objective']} | {r['plan_s']:.3f} | {r['effort']:.5g} | "
            f"{100.0 * (r['effort'] / base[r['scenario']] - 1.0):+.1f} % | {peer} | "
            f"{r['attitude_error_rad']:.1e} | {used} |"
        )
    print()
    print("min_effort at fixed freedom k per joint: exact gradients vs finite differences")
    print("| k | exact [s] | effort | finite differences [s] | effort | time ratio |")
    print("|---:|---:|---:|---:|---:|---:|")
    gradients = found["gradients"]
    assert isinstance(gradients, list)
    for g in gradients:
        print(
            f"| {g['k']} | {g['exact_s']:.3f} | {g['exact_effort']:.4f} | {g['fd_s']:.3f} | "
            f"{g['fd_effort']:.4f} | {g['fd_s'] / g['exact_s']:.1f}x |"
        )


def bench_robustness(draws: int = 500) -> dict[str, object]:
    """Robustness (docs/robustness.md): ``sensitivity`` on the Panda servicer plan (target
    <= 1 s) and a replay Monte Carlo of its spacecraft inertia 5 % off (target <= 30 s for 500
    draws on two workers)."""
    import subprocess
    import tempfile

    from freefloat.robust import plan_spread

    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        scenario = ff.Scenario.from_toml(ROBOTS / "panda_servicer.toml")
        plan = ff.plan(scenario)
        path = plan.save(tmp / "panda.plan.json")
        in_process, _ = timed(lambda: plan_spread(plan, scenario.robot), 5)
        command = [sys.executable, "-m", "freefloat.cli", "sensitivity", str(path), "-q"]
        process_time = []

        def run_command() -> None:
            before = os.times()
            subprocess.run(command, check=True, capture_output=True)
            after = os.times()
            process_time.append(
                after.children_user
                + after.children_system
                - before.children_user
                - before.children_system
            )

        whole = timed_once(run_command)
        axes = "".join(
            f'[[axis]]\nkey = "robot.links.spacecraft.inertia.{k}"\n'
            f"values = {{ normal = [6.0, 0.3], samples = {draws}, seed = {seed} }}\n"
            for seed, k in enumerate(("ixx", "iyy", "izz"), start=1)
        )
        sweep_file = tmp / "mc.toml"
        sweep_file.write_text(f'plan = "{path}"\n' + axes)
        rows: list = []
        wall = timed_once(
            lambda: rows.extend(ff.sweep(sweep_file, workers=2, output=tmp / "mc.csv"))
        )
    errors = [r.attitude_error_rad for r in rows if r.status == "replayed"]
    return {
        "sensitivity_in_process_ms": 1000.0 * in_process,
        "sensitivity_command_s": whole,
        "sensitivity_command_cpu_s": process_time[0],
        "monte_carlo_draws": draws,
        "monte_carlo_replayed": len(errors),
        "monte_carlo_2_workers_s": wall,
        "monte_carlo_mean_error_deg": math.degrees(float(np.mean(errors))),
    }


def try_plan(scenario: ff.Scenario) -> None:
    with contextlib.suppress(ff.FreeFloatError):
        ff.plan(scenario)


def timed_once(fn) -> float:  # type: ignore[no-untyped-def]
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main() -> None:
    markdown = next(
        (Path(a.split("=", 1)[1]) for a in sys.argv if a.startswith("--markdown=")), None
    )
    if "--markdown" in sys.argv[1:]:
        at = sys.argv.index("--markdown")
        markdown = Path(sys.argv[at + 1]) if at + 1 < len(sys.argv) else None
    if markdown is None:
        run()
        return
    buffer = io.StringIO()

    class Tee(io.TextIOBase):
        def write(self, text: str) -> int:
            buffer.write(text)
            return sys.__stdout__.write(text) if sys.__stdout__ else len(text)

    with contextlib.redirect_stdout(Tee()):
        run()
    markdown.write_text(stamped_markdown(buffer.getvalue()), encoding="utf-8")
    print(f"wrote {markdown}")


def run() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--markdown",
        type=Path,
        metavar="FILE",
        help="also write the tables as Markdown, each stamped with date, machine, versions "
        "and this command",
    )
    parser.add_argument("--runs", type=int, default=9, help="freefloat runs per problem")
    parser.add_argument("--baseline-runs", type=int, default=3, help="baseline runs per problem")
    parser.add_argument("--json", type=Path, help="also write the tables as JSON")
    parser.add_argument("--reach-only", action="store_true", help="only the reach table")
    parser.add_argument("--no-reach", action="store_true", help="skip the reach table")
    parser.add_argument(
        "--random", type=int, default=20, help="seeded random directions per servicer (reach)"
    )
    parser.add_argument(
        "--no-multistart", action="store_true", help="reach table: continuation only"
    )
    parser.add_argument(
        "--random-multistart",
        action="store_true",
        help="reach table: also the multistart search on the random directions (slow)",
    )
    parser.add_argument("--sweep", action="store_true", help="also the sweep section")
    parser.add_argument(
        "--collision-only", action="store_true", help="only the clearance cost table"
    )
    parser.add_argument("--sweep-only", action="store_true", help="only the sweep section")
    parser.add_argument(
        "--clearance-only",
        action="store_true",
        help="only the true-hull and certified-clearance tables (bench_clearance.py)",
    )
    parser.add_argument(
        "--swing-only",
        action="store_true",
        help="only the spacecraft's swing section ([constraints.base_swing]; bench_swing.py)",
    )
    parser.add_argument(
        "--speed-only",
        action="store_true",
        help="only the speed section (issue 25: fresh calls, paired rounds; bench_speed.py)",
    )
    parser.add_argument(
        "--no-roll", action="store_true", help="speed section without the 65 deg roll (slow)"
    )
    parser.add_argument(
        "--fresh-only",
        action="store_true",
        help="only a user's single call: every case in a fresh process (bench_fresh.py)",
    )
    parser.add_argument(
        "--fresh-baseline",
        type=Path,
        metavar="SRC",
        help="with --fresh-only: a baseline checkout's src folder, run in the same rounds",
    )
    parser.add_argument(
        "--reachable-only",
        action="store_true",
        help="only the freefloat reach section (issue 28: times, inner set against plan)",
    )
    parser.add_argument(
        "--reachable-no-panda",
        action="store_true",
        help="reach section without the Panda servicer (minutes with clearance)",
    )
    parser.add_argument("--objectives", action="store_true", help="also the objectives section")
    parser.add_argument(
        "--objectives-only", action="store_true", help="only the objectives section"
    )
    parser.add_argument(
        "--multi-arm-only", action="store_true", help="only the many-joints, two-arms section"
    )
    parser.add_argument(
        "--robustness-only", action="store_true", help="only the robustness section"
    )
    parser.add_argument("--paths", action="store_true", help="also the path-basis section")
    parser.add_argument("--paths-only", action="store_true", help="only the path-basis section")
    parser.add_argument(
        "--paths-baseline", default=None, help="git revision of the monomial basis to compare"
    )
    args = parser.parse_args()
    print(f"machine: {machine()}")
    if args.multi_arm_only:
        from bench_multi_arm import bench_multi_arm, print_multi_arm

        multi = bench_multi_arm(max(1, args.runs // 3), chain_urdf)
        print_multi_arm(multi, ff.SolveOptions().max_evaluations)
        if args.json:
            args.json.write_text(json.dumps({"machine": machine(), "multi_arm": multi}, indent=1))
        return
    if args.robustness_only:
        found = bench_robustness()
        print(
            "robustness: sensitivity on the Panda servicer plan "
            f"{found['sensitivity_in_process_ms']:.0f} ms in process, "
            f"{found['sensitivity_command_s']:.2f} s the whole command (CPU "
            f"{found['sensitivity_command_cpu_s']:.2f} s; target <= 1 s); replay "
            f"Monte Carlo {found['monte_carlo_replayed']} of {found['monte_carlo_draws']} draws "
            f"on 2 workers {found['monte_carlo_2_workers_s']:.1f} s (target <= 30 s), mean "
            f"error {found['monte_carlo_mean_error_deg']:.3f} deg"
        )
        if args.json:
            args.json.write_text(json.dumps({"machine": machine(), "robustness": found}, indent=1))
        return
    paths = (
        bench_paths(max(1, min(args.runs, 3)), args.paths_baseline or BASELINE_REVISION)
        if args.paths or args.paths_only
        else {}
    )
    if args.paths_only:
        print_paths(paths)
        if args.json:
            args.json.write_text(json.dumps({"machine": machine(), "paths": paths}, indent=1))
        return
    if args.fresh_only:
        from bench_fresh import REPO, bench_fresh, print_fresh

        trees = {"this tree": REPO / "src"}
        if args.fresh_baseline:
            trees = {"baseline": args.fresh_baseline, **trees}
        rounds = max(3, args.runs // 2)
        fresh = bench_fresh(rounds, trees)
        print_fresh(fresh, rounds)
        if args.json:
            args.json.write_text(json.dumps({"machine": machine(), "fresh": fresh}, indent=1))
        return
    if args.swing_only:
        import tempfile

        from bench_swing import bench_swing, print_swing

        with tempfile.TemporaryDirectory() as tmp:
            swing = bench_swing(Path(tmp))
        print_swing(swing)
        if args.json:
            args.json.write_text(json.dumps({"machine": machine(), "swing": swing}, indent=1))
        return
    if args.speed_only:
        from bench_speed import bench_speed, print_speed

        worked = cases()[0]
        speed = bench_speed(
            max(3, args.runs // 2), roll=not args.no_roll, baseline=Baseline(worked).solve
        )
        print_speed(speed)
        if args.json:
            args.json.write_text(
                json.dumps({"machine": machine(), "speed": speed}, indent=1, default=str)
            )
        return
    if args.reachable_only:
        from bench_reachable import bench_reachable, print_reachable

        found = bench_reachable(panda=not args.reachable_no_panda)
        print_reachable(found)
        if args.json:
            args.json.write_text(json.dumps({"machine": machine(), "reachable": found}, indent=1))
        return
    objectives = bench_objectives() if args.objectives or args.objectives_only else {}
    if args.objectives_only:
        print_objectives(objectives)
        if args.json:
            args.json.write_text(
                json.dumps({"machine": machine(), "objectives": objectives}, indent=1)
            )
        return
    if args.collision_only:
        print_collision(bench_collision(args.runs))
        return
    if args.clearance_only:
        from bench_clearance import (
            bench_certificate,
            bench_flat_faces,
            bench_hulls,
            print_clearance,
            print_flat_faces,
        )

        print_clearance(bench_hulls(args.runs), bench_certificate(max(3, args.runs // 3)))
        print_flat_faces(bench_flat_faces())
        return
    sweep = bench_sweep() if args.sweep or args.sweep_only else {}
    if sweep:
        print(
            f"sweep: {sweep['jobs']} jobs ({sweep['planned']} planned); medians of paired "
            f"runs: 1 worker {sweep['wall_1_worker_s']:.2f} s, 2 workers "
            f"{sweep['wall_2_workers_s']:.2f} s ({sweep['speed_up_2_over_1']:.2f}x); the same "
            f"jobs in one process with one BLAS thread {sweep['one_process_s']:.2f} s "
            f"(default threads {sweep['one_process_default_threads_s']:.2f} s); runner "
            f"overhead {sweep['overhead_per_job_ms']:.1f} ms/job = "
            f"{sweep['overhead_per_plan_percent']:.1f} % of a worked example plan "
            f"({sweep['worked_example_plan_ms']:.1f} ms); one BLAS thread costs "
            f"{sweep['one_blas_thread_per_job_ms']:.1f} ms/job"
        )
    if args.sweep_only:
        if args.json:
            args.json.write_text(json.dumps({"machine": machine(), "sweep": sweep}, indent=1))
        return
    reach = (
        []
        if args.no_reach
        else bench_reach(args.random, not args.no_multistart, args.random_multistart)
    )
    if args.reach_only:
        print_reach(reach)
        if args.json:
            args.json.write_text(json.dumps({"machine": machine(), "reach": reach}, indent=1))
        return
    rows = bench_cases(args.runs, args.baseline_runs)
    collision = bench_collision(max(3, args.runs // 3))
    whole = bench_whole(args.runs, {str(r["problem"]): float(r["baseline_ms"]) for r in rows})  # type: ignore[arg-type]
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
    print("whole verified plan vs solve (ms, medians):")
    print(
        "| scenario | whole plan() | solve | sample | verify | plan/solve | baseline solve "
        "| baseline solve / whole plan |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for r in whole:
        print(
            f"| {r['scenario']} | {r['plan_ms']:.1f} | {r['solve_ms']:.1f} | "
            f"{r['sample_ms']:.1f} | {r['verify_ms']:.1f} | {r['plan_over_solve']:.2f}x | "
            f"{r['baseline_solve_ms']:.0f} | {r['baseline_over_plan']:.1f}x |"
        )
    print()
    print("| joints | map [us/eval] | map + derivative [us/eval] |")
    print("|---:|---:|---:|")
    for r in scaling:
        print(f"| {r['joints']} | {r['map_us']:.2f} | {r['map_and_derivative_us']:.2f} |")
    if reach:
        print_reach(reach)
    print_collision(collision)
    if objectives:
        print_objectives(objectives)
    if paths:
        print_paths(paths)
    if args.json:
        args.json.write_text(
            json.dumps(
                {
                    "machine": machine(),
                    "problems": rows,
                    "whole_plan": whole,
                    "map_scaling": scaling,
                    "reach": reach,
                    "sweep": sweep,
                    "collision": collision,
                    "objectives": objectives,
                    "paths": paths,
                },
                indent=1,
            )
        )
        print(f"\nwrote {args.json}")


if __name__ == "__main__":
    main()
