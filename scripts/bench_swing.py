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
- the shipped UR5 servicer unfolding to a goal 6 deg in yaw and 3 deg in pitch from its
  start, bounded to that goal's own turn (a goal on the bound; the plain path ends 11.9 deg
  from the start attitude);
- when ``../shared/real-arms/`` is present (real robots nobody here wrote; tests never read
  them): ETS-VII turned 2 deg with its arm back where it started; Canadarm2 on a 20 t,
  4 m spacecraft holding a 5 t payload, its goal 20 deg in yaw; Canadarm2 on a 15 t
  spacecraft holding 8 t, and VISPA on 300 kg holding 200 kg, each bounded to its goal's own
  turn (and Canadarm2 to 12 deg).

A bound ``"goal"`` is the goal attitude's own turn from the start, to full precision.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import freefloat as ff
from freefloat.physics.attitude import quat_from_zyx, quat_multiply
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

_CANADARM2 = """duration = {duration}
[robot]
arm = "{urdf}"
base_mass = {base_mass}
base_size = [4.0, 4.0, 4.0]
mount = [2.0, 0.0, 0.0]
[start]
joints = {{ Shoulder_Roll = 0.0, Shoulder_Yaw = 0.0, Shoulder_Pitch = 0.0, Elbow_Pitch = 0.0, Wrist_Pitch = 0.0, Wrist_Yaw = 0.0, Wrist_Roll = 0.0 }}
[goal]
joints = {{ Shoulder_Roll = {goal[0]}, Shoulder_Yaw = {goal[1]}, Shoulder_Pitch = {goal[2]}, Elbow_Pitch = {goal[3]}, Wrist_Pitch = {goal[4]}, Wrist_Yaw = {goal[5]}, Wrist_Roll = 0.0 }}
base_zyx_deg = {zyx}
[payload]
mass = {payload}
box = [3.0, 3.0, 3.0]
com_xyz = [2.0, 0.0, 0.0]
[safety]
check = false
"""  # noqa: E501
#: Canadarm2 on a 20 t spacecraft holding 5 t, its goal 20 deg in yaw; on 15 t holding 8 t.
_CANADARM2_CASES = (
    ("canadarm2", "Canadarm2 + 5 t payload, goal 20 deg", (40.0, 25.0), {
        "duration": 600.0, "base_mass": 20000.0, "goal": (0.0, 30.0, 20.0, -40.0, 20.0, 0.0),
        "zyx": [20.0, 0.0, 0.0], "payload": 5000.0}),
    ("canadarm2_8t", "Canadarm2 + 8 t payload, goal 11.68 deg", (12.0, "goal"), {
        "duration": 900.0, "base_mass": 15000.0,
        "goal": (20.0, -30.0, 30.0, -60.0, 30.0, 10.0), "zyx": [-10.0, 5.0, 3.0],
        "payload": 8000.0}),
)  # fmt: skip

_VISPA = """duration = 300.0
[robot]
arm = "{urdf}"
base_mass = 300.0
base_size = [1.0, 1.0, 1.0]
mount = [0.5, 0.0, 0.0]
mount_rpy_deg = [0.0, 90.0, 0.0]
[start]
joints = {{ Joint_1 = 0.0, Joint_2 = 30.0, Joint_3 = 60.0, Joint_4 = 0.0, Joint_5 = 30.0, Joint_6 = 0.0 }}
[goal]
joints = {{ Joint_1 = 70.0, Joint_2 = -10.0, Joint_3 = 90.0, Joint_4 = 30.0, Joint_5 = -40.0, Joint_6 = 45.0 }}
base_zyx_deg = [4.0, -3.0, 2.0]
[payload]
mass = 200.0
box = [0.8, 0.8, 0.8]
com_xyz = [0.0, 0.0, 0.6]
[safety]
check = false
"""  # noqa: E501


def _ur5_turned() -> ff.Scenario:
    """The UR5 servicer, its goal 6 deg in yaw and 3 deg in pitch from its start attitude."""
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml")
    turn = quat_from_zyx(math.radians(6.0), math.radians(3.0), 0.0)
    return dataclasses.replace(scenario, goal_attitude=quat_multiply(scenario.start_attitude, turn))


def _from_text(text: str, folder: Path, name: str) -> ff.Scenario:
    path = folder / f"{name}.toml"
    path.write_text(text)
    return ff.Scenario.from_toml(path)


def cases(folder: Path) -> list[tuple[str, ff.Scenario, tuple[float | str, ...]]]:
    """(name, scenario, bounds in deg or ``"goal"``) of every case this machine can run."""
    found: list[tuple[str, ff.Scenario, tuple[float | str, ...]]] = [
        ("Panda servicer, 3 deg reorientation", _panda(), (5.0, 4.0, 3.2)),
        ("UR5 servicer, goal 6.7 deg (6 yaw, 3 pitch)", _ur5_turned(), ("goal",)),
    ]
    if (REAL / "ets7_satellite.urdf").exists():
        text = _ETS7.format(urdf=REAL / "ets7_satellite.urdf")
        found.append(("ETS-VII, 2 deg reorientation", _from_text(text, folder, "ets7"), (2.4, 2.1)))
    if (REAL / "canadarm2_arm.urdf").exists():
        for file, name, bounds, fields in _CANADARM2_CASES:
            text = _CANADARM2.format(urdf=REAL / "canadarm2_arm.urdf", **fields)
            found.append((name, _from_text(text, folder, file), bounds))
    if (REAL / "vispa_arm.urdf").exists():
        text = _VISPA.format(urdf=REAL / "vispa_arm.urdf")
        scenario = _from_text(text, folder, "vispa")
        found.append(("VISPA + 200 kg payload, goal 5.42 deg", scenario, ("goal",)))
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


def _bound_deg(scenario: ff.Scenario, bound: float | str) -> float:
    """A bound in degrees: as given, or ``"goal"``: the goal attitude's own turn."""
    if bound != "goal":
        return float(bound)
    return math.degrees(ff.geodesic_angle(scenario.start_attitude, scenario.goal_attitude))


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
            degrees = None if bound is None else _bound_deg(scenario, bound)
            found = free if degrees is None else _planned(scenario, degrees)
            shown = f"{degrees:.12g} (the goal's)" if bound == "goal" else bound
            rows.append({"case": name, "bound_deg": shown, **found})
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
        bound = r["bound_deg"]
        bound = "none" if bound is None else bound if isinstance(bound, str) else f"{bound:g}"
        swing = f"{r['swing_deg']:.3f}" if "swing_deg" in r else "-"
        print(f"| {r['case']} | {bound} | {swing} | {r['time_s']:.2f} | {r['outcome']} |")


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        print_swing(bench_swing(Path(tmp)))
