"""Benchmark section: the bound on the spacecraft's swing on the way (``[constraints.base_swing]``).

Run through ``scripts/bench.py --swing-only`` (or alone: ``python scripts/bench_swing.py``).
Each case is a scenario planned as a user plans it (``ff.plan`` of the scenario read afresh,
one call each), first without a bound and then with each bound listed: the wall time of the
call, the largest turn of the spacecraft from its start attitude on the way (from the plan's
``base_swing`` check: Pinocchio's centroidal map and RK5, independent of the planner; without
a bound, the same check of the plan made), whether the plan verifies, or the refusal.

- the shipped Panda servicer turned 3 deg in yaw with its arm back where it started (a pure
  reorientation: the loop swings the spacecraft beyond its goal);
- the same reorientation with the spacecraft's z axis held to a cone of 3 and 1.5 deg
  (``[constraints.base_pointing]``; its tilt from the plan's check);
- when ``../shared/real-arms/`` is present (real robots nobody here wrote; tests never read
  them): ETS-VII turned 2 deg with its arm back where it started, and Canadarm2 on a 20 t,
  4 m spacecraft holding a 5 t payload, its goal 20 deg in yaw.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import freefloat as ff
from freefloat.physics.attitude import quat_from_zyx
from freefloat.problem.constraints import BasePointing, BaseSwing

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT.parent / "shared" / "real-arms"

#: A bound no case comes near: its check gives the swing of a plan made without one (deg).
_LOOSE_DEG = 179.0


def _panda() -> ff.Scenario:
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "panda_servicer.toml")
    return dataclasses.replace(
        scenario,
        goal_joints=dict(scenario.start_joints),
        goal_attitude=quat_from_zyx(math.radians(3.0)),
        extra=None,
    )


_ETS7 = """robot = "{urdf}"
duration = 60.0
[start]
joints = {{ Joint_1 = 0.0, Joint_2 = 30.0, Joint_3 = 60.0, Joint_4 = 0.0, Joint_5 = 30.0, Joint_6 = 0.0 }}
[goal]
joints = {{ Joint_1 = 0.0, Joint_2 = 30.0, Joint_3 = 60.0, Joint_4 = 0.0, Joint_5 = 30.0, Joint_6 = 0.0 }}
base_zyx_deg = [2.0, 0.0, 0.0]
"""  # noqa: E501

_CANADARM2 = """duration = 600.0
[robot]
arm = "{urdf}"
base_mass = 20000.0
base_size = [4.0, 4.0, 4.0]
mount = [2.0, 0.0, 0.0]
[start.joints]
Shoulder_Roll = 0.0
Shoulder_Yaw = 0.0
Shoulder_Pitch = 0.0
Elbow_Pitch = 0.0
Wrist_Pitch = 0.0
Wrist_Yaw = 0.0
Wrist_Roll = 0.0
[goal]
base_zyx_deg = [20.0, 0.0, 0.0]
[goal.joints]
Shoulder_Roll = 0.0
Shoulder_Yaw = 30.0
Shoulder_Pitch = 20.0
Elbow_Pitch = -40.0
Wrist_Pitch = 20.0
Wrist_Yaw = 0.0
Wrist_Roll = 0.0
[payload]
mass = 5000.0
box = [3.0, 3.0, 3.0]
com_xyz = [2.0, 0.0, 0.0]
[safety]
check = false
"""


def _from_text(text: str, folder: Path, name: str) -> ff.Scenario:
    path = folder / f"{name}.toml"
    path.write_text(text)
    return ff.Scenario.from_toml(path)


def cases(folder: Path) -> list[tuple[str, ff.Scenario, tuple[float, ...]]]:
    """(name, scenario, bounds in deg) of every case this machine can run."""
    found = [("Panda servicer, 3 deg reorientation", _panda(), (5.0, 4.0, 3.2))]
    if (REAL / "ets7_satellite.urdf").exists():
        text = _ETS7.format(urdf=REAL / "ets7_satellite.urdf")
        found.append(("ETS-VII, 2 deg reorientation", _from_text(text, folder, "ets7"), (2.4, 2.1)))
    if (REAL / "canadarm2_arm.urdf").exists():
        text = _CANADARM2.format(urdf=REAL / "canadarm2_arm.urdf")
        scenario = _from_text(text, folder, "canadarm2")
        found.append(("Canadarm2 + 5 t payload, goal 20 deg", scenario, (40.0, 25.0)))
    return found


def _held(scenario: ff.Scenario, constraint: BaseSwing | BasePointing) -> dict[str, object]:
    """One plan with ``constraint`` added, timed.

    Its wall time (s), the largest turn or tilt (deg) from its check, verified or refused.
    """
    bounded = dataclasses.replace(scenario, constraints=(*scenario.constraints, constraint))
    start = time.perf_counter()
    try:
        plan = ff.plan(bounded)
    except ff.FreeFloatError as exc:
        return {"time_s": time.perf_counter() - start, "outcome": type(exc).__name__}
    elapsed = time.perf_counter() - start
    check = next(c for c in plan.verification.checks if c.name == constraint.name)
    bound = constraint.max_angle if isinstance(constraint, BaseSwing) else constraint.half_angle
    largest = math.degrees(check.value + bound)  # each check: the largest angle beyond its bound
    outcome = "verified" if plan.verification.passed else "NOT VERIFIED"
    return {"time_s": elapsed, "swing_deg": largest, "outcome": outcome}


def _planned(scenario: ff.Scenario, bound_deg: float) -> dict[str, object]:
    """One plan with the swing bound (deg)."""
    return _held(scenario, BaseSwing(math.radians(bound_deg)))


def _pointed(scenario: ff.Scenario, half_deg: float) -> dict[str, object]:
    """One plan with the Panda's z axis held to a cone of ``half_deg`` (deg)."""
    return _held(scenario, BasePointing([0.0, 0.0, 1.0], None, math.radians(half_deg)))


def bench_swing(folder: Path) -> list[dict[str, object]]:
    """Every case without a bound (a loose one) and with each of its bounds."""
    ff.plan(_panda())  # imports and first-call costs out of the way
    rows = []
    for name, scenario, bounds in cases(folder):
        free = _planned(scenario, _LOOSE_DEG)
        for bound in (None, *bounds):
            found = free if bound is None else _planned(scenario, bound)
            rows.append({"case": name, "bound_deg": bound, **found})
            print(f"  done: swing {rows[-1]}", flush=True)
    name = "Panda servicer, 3 deg reorientation: z axis tilt (base_pointing)"
    for half in (None, 3.0, 1.5):
        found = _pointed(_panda(), _LOOSE_DEG if half is None else half)
        rows.append({"case": name, "bound_deg": half, **found})
        print(f"  done: pointing {rows[-1]}", flush=True)
    return rows


def print_swing(rows: list[dict[str, object]]) -> None:
    print("\n| case | bound [deg] | largest turn on the way [deg] | plan [s] | outcome |")
    print("|---|---:|---:|---:|---|")
    for r in rows:
        bound = "none" if r["bound_deg"] is None else f"{r['bound_deg']:g}"
        swing = f"{r['swing_deg']:.3f}" if "swing_deg" in r else "-"
        print(f"| {r['case']} | {bound} | {swing} | {r['time_s']:.2f} | {r['outcome']} |")


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        print_swing(bench_swing(Path(tmp)))
