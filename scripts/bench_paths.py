"""Bench section (issue 23): the orthonormal path basis against the monomial basis before it.

Side by side in one run, each plan made in its own process with ``OPENBLAS_NUM_THREADS=1``:

- the previous code (a git revision, by default the last one with the monomial basis,
  exported to a temporary directory) and this checkout, on real-robot cases (ETS-VII keeping
  its attitude for 60 s and turning it 1.7 deg; Robonaut 2's two arms composed on a 500 kg
  bus keeping its attitude; read from ``../shared/real-arms`` when present) and the shipped
  scenarios, with the default objective: plan time (median of ``runs``), the largest joint
  excursion beyond its start-goal span (deg, from each plan's exact polynomial extremes,
  computed here by this checkout for both), the RMS deviation from the quintic (deg) and
  whether the plan verified;
- ``min_effort`` on the worked example (value against the optimal-control figure 26.6
  N^2 m^2 s) and ``min_length`` on the UR5 servicer (the minimisation stage's time);
- the condition numbers of the L2 Gram matrices of both bases up to degree 25.

Run: python scripts/bench.py --paths-only [--runs N] [--paths-baseline REV]
"""

from __future__ import annotations

import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
#: The real robots, beside the repository (or beside the directory of its worktrees).
REAL_ARMS = next(
    (
        d / "shared" / "real-arms"
        for d in (REPO.parent, REPO.parent.parent)
        if (d / "shared" / "real-arms").is_dir()
    ),
    REPO.parent / "shared" / "real-arms",
)
#: The last revision with the monomial path basis.
BASELINE_REVISION = "a6e46b9"
#: The optimal-control figure quoted by the issue for the worked example (N^2 m^2 s).
PEER_EFFORT = 26.6

_ETS7_JOINTS = (
    "[start]\njoints = { Joint_1 = 0.0, Joint_2 = 0.0, Joint_3 = 0.0, Joint_4 = 0.0, "
    "Joint_5 = 0.0, Joint_6 = 0.0 }\n[goal]\njoints = { Joint_1 = 40.0, Joint_2 = -30.0, "
    "Joint_3 = 60.0, Joint_4 = -45.0, Joint_5 = 30.0, Joint_6 = 20.0 }\n"
)
#: Per joint of each R2 arm: left start, left goal, right start, right goal (deg).
_R2_ARM = [
    ("joint0", 0, 40, 0, -30),
    ("joint1", -40, -20, -40, -60),
    ("joint2", -150, -120, 150, 120),
    ("joint3", -80, -40, -80, -110),
    ("joint4", 0, 30, 0, -30),
    ("joint5", 0, 20, 0, -20),
]


def _r2_joints(index: int) -> str:
    """The R2 case's start (index 1) or goal (index 2) joints, both arms, as a TOML table."""
    items = []
    for name, ls, lg, rs, rg in _R2_ARM:
        items.append(f'"r2/left_arm/{name}" = {float(ls if index == 1 else lg)}')
        items.append(f'"r2/right_arm/{name}" = {float(rs if index == 1 else rg)}')
    return "joints = { " + ", ".join(items) + " }\n"


def real_cases() -> dict[str, str]:
    """Scenario texts of the real-robot cases (empty when the robots are not present)."""
    ets7, r2 = REAL_ARMS / "ets7_satellite.urdf", REAL_ARMS / "r2_dualarm12.urdf"
    out = {}
    if ets7.exists():
        head = f'robot = "{ets7}"\nduration = 60.0\n' + _ETS7_JOINTS
        out["ETS-VII keep attitude, T = 60 s"] = head + "base_zyx_deg = [0.0, 0.0, 0.0]\n"
        out["ETS-VII 1.7 deg three-axis, T = 60 s"] = head + "base_zyx_deg = [1.0, -1.0, 1.0]\n"
    if r2.exists():
        out["Robonaut 2 (12 joints) on a 500 kg bus, keep attitude, T = 30 s"] = (
            f'duration = 30.0\nend_effector = "r2/right_palm"\n[robot]\narm = "{r2}"\n'
            "base_mass = 500.0\n"
            "base_size = [1.0, 1.0, 1.0]\nmount = [0.5, 0.0, 0.0]\n"
            "mount_rpy_deg = [0.0, 90.0, 0.0]\n[start]\n"
            + _r2_joints(1)
            + "[goal]\n"
            + _r2_joints(2)
            + "base_zyx_deg = [0.0, 0.0, 0.0]\n"
        )
    return out


_RUNNER = """
import json, sys, time
import freefloat as ff
scenario_path, objective, runs, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
scenario = ff.Scenario.from_toml(scenario_path)
times, plan, error = [], None, ""
for _ in range(runs):
    clock = time.perf_counter()
    try:
        plan = ff.plan(scenario, objective=None if objective == "default" else objective)
    except ff.FreeFloatError as exc:
        error = str(exc)[:160]
        break
    times.append(time.perf_counter() - clock)
if plan is not None:
    plan.save(out)
stages = {}
if plan is not None:
    stages = {"solve_s": plan.solver.solve_time_s, "verify_s": plan.solver.verify_time_s}
print(json.dumps({"times": times, "error": error, "stages": stages}))
"""


def _run(source: Path, scenario: Path, objective: str, runs: int, out: Path) -> dict:
    env = {**os.environ, "PYTHONPATH": str(source), "OPENBLAS_NUM_THREADS": "1"}
    done = subprocess.run(
        [sys.executable, "-c", _RUNNER, str(scenario), objective, str(runs), str(out)],
        env=env,
        capture_output=True,
        text=True,
        check=False,
        cwd=scenario.parent,
    )
    if done.returncode != 0:
        return {"times": [], "error": done.stderr.strip().splitlines()[-1][:160], "stages": {}}
    return json.loads(done.stdout.strip().splitlines()[-1])


def _measure(plan_file: Path) -> dict[str, float | bool | str]:
    """Excursion beyond the spans (deg) and deviation from the quintic (deg RMS) of a plan."""
    import freefloat as ff
    from freefloat.problem.paths import PathFamily, excursions

    plan = ff.Plan.load(plan_file)
    start = np.asarray(plan.request.start_joints)
    goal = np.asarray(plan.request.goal_joints)
    path = plan.path()
    beyond = np.degrees(excursions(path, start, goal))
    worst = int(np.argmax(beyond))
    degrees = tuple(path.coefficients.shape[1] - 1 for _ in start)
    beta = PathFamily(start, goal, (max(5, degrees[0]),) * len(start)).beta_from_path(path)
    return {
        "largest_excursion_deg": float(beyond[worst]),
        "joint": plan.robot.joints[worst],
        "deviation_rms_deg": math.degrees(math.sqrt(float(beta @ beta))),
        "verified": plan.verification.passed,
        "format": plan.format,
    }


def _export(revision: str, into: Path) -> Path:
    archive = subprocess.run(
        ["git", "-C", str(REPO), "archive", revision, "src", "robots"],
        capture_output=True,
        check=True,
    )
    into.mkdir(parents=True, exist_ok=True)
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive.stdout, check=True)
    return into / "src"


def conditioning(degrees: tuple[int, ...] = (8, 12, 16, 20, 25)) -> list[dict[str, float]]:
    """L2 Gram-matrix condition numbers of the free basis functions, both bases."""
    from freefloat.problem.paths import PathFamily
    from freefloat.verify.path_records import monomial_basis

    x, w = np.polynomial.legendre.leggauss(40)
    s, w = 0.5 * (x + 1.0), 0.5 * w
    rows = []
    for degree in degrees:
        new = PathFamily(np.zeros(1), np.ones(1), (degree,)).affine_samples(s).dq[:, 0, :]
        old = np.stack(
            [np.polynomial.polynomial.polyval(s, monomial_basis(p)) for p in range(6, degree + 1)],
            axis=1,
        )
        rows.append(
            {
                "degree": degree,
                "orthonormal": float(np.linalg.cond((new * w[:, None]).T @ new)),
                "monomial": float(np.linalg.cond((old * w[:, None]).T @ old)),
            }
        )
    return rows


def bench_paths(runs: int = 3, baseline: str = BASELINE_REVISION) -> dict[str, object]:
    """Every row of the section (see the module docstring)."""
    shipped = REPO / "robots" / "scenarios"
    rows = []
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        old_src = _export(baseline, tmp / "old")
        cases: list[tuple[str, Path, str]] = []
        for name, text in real_cases().items():
            path = tmp / f"case{len(cases)}.toml"
            path.write_text(text)
            cases.append((name, path, "default"))
        for toml in sorted(shipped.glob("*.toml")):
            cases.append((toml.stem, toml, "default"))
        cases.append(("worked_example", shipped / "worked_example.toml", "min_effort"))
        cases.append(("ur5_servicer", shipped / "ur5_servicer.toml", "min_length"))
        for name, scenario, objective in cases:
            row: dict[str, object] = {"case": name, "objective": objective}
            for label, source in (("before", old_src), ("now", REPO / "src")):
                out = tmp / f"{label}.json"
                out.unlink(missing_ok=True)
                found = _run(source, scenario, objective, runs, out)
                entry: dict[str, object] = {
                    "plan_s": statistics.median(found["times"]) if found["times"] else None,
                    "error": found["error"],
                    **found["stages"],
                }
                if out.exists():
                    entry.update(_measure(out))
                    if objective != "default":
                        import freefloat as ff

                        record = ff.Plan.load(out).objective
                        entry["objective_value"] = record.value
                row[label] = entry
            rows.append(row)
            print(f"  paths bench: {name} ({objective}) done", file=sys.stderr)
    return {"baseline": baseline, "plans": rows, "conditioning": conditioning()}


def _cell(entry: dict, key: str, fmt: str) -> str:
    value = entry.get(key)
    return "-" if value is None else format(value, fmt)


def print_paths(found: dict[str, object]) -> None:
    """The section's tables (markdown)."""
    print()
    print(
        f"paths: monomial basis (revision {found['baseline']}) vs orthonormal basis, same "
        "machine, one BLAS thread, medians; excursion = largest joint excursion beyond its "
        "start-goal span [deg]; deviation = RMS distance from the quintic [deg]"
    )
    print(
        "| case | objective | before [s] | now [s] | now/before | excursion before | "
        "excursion now | deviation before | deviation now | value before | value now | "
        "verified before/now |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    plans = found["plans"]
    assert isinstance(plans, list)
    for r in plans:
        b, n = r["before"], r["now"]
        ratio = f"{n['plan_s'] / b['plan_s']:.2f}" if b.get("plan_s") and n.get("plan_s") else "-"
        print(
            f"| {r['case']} | {r['objective']} | {_cell(b, 'plan_s', '.3f')} | "
            f"{_cell(n, 'plan_s', '.3f')} | {ratio} | "
            f"{_cell(b, 'largest_excursion_deg', '.1f')} | "
            f"{_cell(n, 'largest_excursion_deg', '.1f')} | "
            f"{_cell(b, 'deviation_rms_deg', '.1f')} | "
            f"{_cell(n, 'deviation_rms_deg', '.1f')} | {_cell(b, 'objective_value', '.4g')} | "
            f"{_cell(n, 'objective_value', '.4g')} | {b.get('verified', b.get('error'))} / "
            f"{n.get('verified', n.get('error'))} |"
        )
    print()
    print("L2 Gram-matrix condition number of the free basis functions")
    print("| degree | orthonormal | monomial |")
    print("|---:|---:|---:|")
    rows = found["conditioning"]
    assert isinstance(rows, list)
    for c in rows:
        print(f"| {c['degree']} | {c['orthonormal']:.3g} | {c['monomial']:.3g} |")
