"""The text summary of a plan that ``freefloat plan`` prints (angles in degrees).

A leaf that reads a plan (and its scenario, for the robot's name and a Cartesian goal); it
computes nothing the plan does not hold, but a Cartesian goal's error and the base's swing.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..plans.format import Plan
from ..plans.guarantees import Check, Verification
from ..plans.versions import MONOMIAL_BASIS
from ..problem.constraints import CONSTRAINTS
from ..problem.scenario import Scenario
from ..robot.arm_tips import payload_parent
from ..robot.model import Robot
from ..solvers.optimise import FALLBACK_NOTE
from ..verify.segmented import segment_count
from .base_swing import base_swing_line
from .robustness import robustness_line

__all__ = [
    "cartesian_report",
    "clearance_line",
    "robot_label",
    "summary",
    "unlimited_line",
    "verification_lines",
]

#: Paths with at most this many free parameters in all also show them as the paper's
#: monomial coefficients in t (higher degrees would print large cancelling numbers).
OLD_UNITS_MAX_FREE = 3
#: Excursions beyond a start-goal span smaller than this (deg or m) are the extremes' rounding
#: (a path that stays within its spans gives 1e-14 deg or so): printed as 0.
_RESOLVED_EXCURSION = 1e-9


def _attitude_table(p: Plan) -> list[str]:
    rows = [f"  {'base attitude':<16}{'yaw [deg]':>14}{'pitch [deg]':>14}{'roll [deg]':>14}"]
    for label, angles in (
        ("start", p.base.start_zyx_deg),
        ("target", p.base.target_zyx_deg),
        ("achieved", p.base.achieved_zyx_deg),
    ):
        # rounded first, so a rounding-level negative prints as 0.000000, not -0.000000
        rows.append(f"  {label:<16}" + "".join(f"{round(a, 6) + 0.0:>14.6f}" for a in angles))
    return rows


def _joint_value(value: float, kind: str) -> str:
    return f"{value:.4f} m" if kind == "prismatic" else f"{math.degrees(value):.3f} deg"


def _kinds(p: Plan) -> list[str]:
    kinds = list(p.robot.joint_kinds)
    return kinds if len(kinds) == len(p.robot.joints) else ["revolute"] * len(p.robot.joints)


def summary(
    p: Plan,
    output: Path | None = None,
    *,
    robot_label: str | None = None,
    wall_time_s: float | None = None,
    timings: dict[str, float] | None = None,
    extra_lines: Sequence[str] = (),
    command: str = "plan",
    limit_lines: Sequence[str] = (),
) -> str:
    """The text summary ``freefloat plan`` prints (angles in degrees, units on every figure).

    Args:
        p: the plan.
        output: the plan file written.
        robot_label: how to name the robot (default: the URDF file name).
        wall_time_s: the whole command's wall time (s).
        timings: wall time (s) per stage (``solve``, ``sample and verify``...).
        extra_lines: more lines (a Cartesian goal's report), printed after the attitude.
        command: the command that made the plan, named in the header (``plan``, ``correct``).
        limit_lines: more lines after the constraints' (:func:`unlimited_line`).
    """
    lines = [f"freefloat {command}: {robot_label or Path(p.robot.urdf).name}, T = {p.duration:g} s"]
    lines += _attitude_table(p)
    lines.append(f"  attitude error  {p.base.attitude_error_rad:.3e} rad")
    if p.robustness is not None:
        lines.append(robustness_line(p.robustness))
    lines += list(extra_lines)
    lines += verification_lines(p.verification)
    if constraints := constraints_line(p):
        lines.append(constraints)
    lines += [line for line in limit_lines if line]
    lines.append(clearance_line(p))
    lines += free_parameter_lines(p)
    if p.feasibility.planar and p.feasibility.yaw_change_bounds_deg is not None:
        lo, hi = p.feasibility.yaw_change_bounds_deg
        asked = p.feasibility.requested_yaw_change_deg
        # within rounding (deg) of the interval: a one-joint robot's is a single point
        where = "in" if asked is not None and lo - 1e-6 <= asked <= hi + 1e-6 else "beyond"
        loop = "" if where == "in" else " of simple motions: this path goes back and forth"
        lines.append(
            f"  planar bounds   yaw change {asked:.3f} deg {where} ({lo:.3f}, {hi:.3f}) deg{loop}"
        )
    lines.append(objective_line(p))
    if p.quality is not None:
        lines.append(quality_line(p))
    lines.append(base_swing_line(p))
    s = p.solver
    lines.append(
        f"  solver          {s.method}; {len(s.solutions)} solution(s); {s.evaluations} "
        f"evaluations; final solver call {s.wall_time_s:.3f} s"
    )
    if s.solve_time_s or s.sample_time_s or s.verify_time_s:
        lines.append(
            f"  stage times     solve {1e3 * s.solve_time_s:.1f} ms (every solver stage), sample "
            f"{1e3 * s.sample_time_s:.1f} ms, verify {1e3 * s.verify_time_s:.1f} ms"
        )
    turns = {k: t for k, t in s.full_turns.items() if t}
    for name, count in turns.items():
        j = p.robot.joints.index(name)
        start, goal = p.request.start_joints[j], p.request.goal_joints[j]
        lines.append(
            f"  full turns      {name}: start {math.degrees(start):.3f} deg, goal "
            f"{math.degrees(goal):.3f} deg ({math.degrees(goal - count * 2 * math.pi):.3f} deg "
            f"{count:+d} turn(s)), travels {math.degrees(goal - start):.3f} deg"
        )
    if wall_time_s is not None:
        parts = []
        for name, seconds in (timings or {}).items():
            share = 100.0 * seconds / wall_time_s if wall_time_s > 0 else 0.0
            parts.append(f"{name} {seconds:.3f} s ({share:.0f} %)")
        lines.append(
            f"  wall time       {wall_time_s:.3f} s total"
            + (": " + ", ".join(parts) if parts else "")
        )
    if output is not None:
        lines.append(f"  plan            {output}")
    return "\n".join(lines)


def verification_lines(v: Verification) -> list[str]:
    """The verification line and, when a check could not tell, what it means (none unverified)."""
    if not v.checks:
        return []
    replay = v["replay_attitude"]
    segments = segment_count(replay.detail)
    replayed = (
        f"replay {replay.value:.1e} rad"
        + (f" (in {segments} segments, each from the path's state)" if segments else "")
        if replay.verdict != "no verdict"
        else f"replay no verdict ({replay.detail})"
    )
    lines = [
        f"  verification    {'passed' if v.passed else 'FAILED'}: independent attitude "
        f"{v['attitude_independent'].value:.1e} rad, {replayed}, momentum "
        f"{v['momentum'].value:.1e} kg m^2/s"
    ]
    undecided = [c for c in v.checks if c.verdict == "no verdict"]
    if undecided:
        replays = [c for c in undecided if c.name.startswith("replay")]
        settle = ""
        if any("torques perturbed" in c.detail for c in replays):
            settle = (
                " (the open-loop replay carries its torques' rounding that far: more steps "
                "will not settle it)"
            )
        elif replays:
            settle = " (more steps: freefloat verify --replay-steps)"
        lines.append(
            f"  no verdict      {', '.join(c.name for c in undecided)}: within its own error "
            f"of the tolerance, either side; not refused for it{settle}"
        )
    return lines


def unlimited_line(robot: Robot) -> str:
    """A line naming the joints the URDF gives no velocity or no effort limit; "" if none.

    Plans honour the URDF's limits; where it gives none (no ``<limit>``, or 0), none is
    imposed, and a short duration may ask any rate or torque (ETS-VII in 1 ms: 1e4 rad/s and
    1e10 N m): said beside the constraints, not warned of (the paper's planar model has none).
    """
    missing = []
    for kind, attribute in (("velocity", "velocity_limit"), ("effort", "effort_limit")):
        names = [j.name for j in robot.joints if not math.isfinite(getattr(j, attribute))]
        if names:
            missing.append(f"no {kind} limit for {', '.join(repr(n) for n in names)}")
    if not missing:
        return ""
    return f"  URDF limits     {'; '.join(missing)}: none imposed there"


def constraints_line(p: Plan) -> str:
    """The path constraints verification checked, with how far inside its limit each stays.

    Clearance has its own line. Margins in degrees for angles (rad or rad/s checks; ``a|b``
    units take the revolute one when no joint is prismatic); a check without a physical unit
    (a cosine gap) gives its own detail instead (the end-effector cone: the axis's largest
    angle from its direction, against the half-angle). Empty when there are none.
    """
    checks = [c for c in p.verification.checks if c.name in CONSTRAINTS and c.name != "clearance"]
    if not checks:
        return ""
    prismatic = "prismatic" in _kinds(p)
    each = ", ".join(
        c.name + (_margin(c.value, c.unit, prismatic) or _said(c) if c.passed else " BROKEN")
        for c in checks
    )
    return f"  constraints     held, margin to the limit: {each}"


def _said(check: Check) -> str:
    """`` (its detail)``: how a held check without a physical unit says where it stands."""
    return f" ({check.detail})" if check.unit == "1" and check.detail else ""


def _margin(value: float, unit: str, prismatic: bool) -> str:
    """`` 41 deg``: a held check's margin (``-value``, at least 0) in readable units, or ``""``."""
    if unit == "1":
        return ""
    if "|" in unit and not prismatic:
        unit = unit.split("|")[0]
    margin = max(-value, 0.0) + 0.0
    if unit.startswith("rad"):
        margin, unit = math.degrees(margin), "deg" + unit[3:]
    return f" {margin:.3g} {unit}"


def clearance_line(p: Plan) -> str:
    """What the plan was kept clear of, as verification measured it on the original geometry."""
    safety = p.safety
    if not safety.checked:
        return f"  clearance       {safety.note or 'not checked'}"
    check = next((c for c in p.verification.checks if c.name == "clearance"), None)
    line = f"  clearance       {check.detail if check is not None else 'not verified'}"
    if safety.note:
        line += f"; {safety.note}"
    return line


def free_parameter_lines(p: Plan) -> list[str]:
    """The free parameters in the plan's basis and, for low degrees, as the paper's monomials."""
    kinds = dict(zip(p.robot.joints, _kinds(p), strict=True))
    unit = {name: "m" if kinds.get(name) == "prismatic" else "rad" for name in p.robot.joints}
    if p.basis == MONOMIAL_BASIS:
        free = [
            f"{name}: "
            + ", ".join(f"t^{6 + k} {c:.9e} {unit[name]}/s^{6 + k}" for k, c in enumerate(values))
            for name, values in p.free_parameters.items()
            if values
        ]
        return ["  free parameters " + ("; ".join(free) if free else "(none)")]
    free = [
        f"{name}: " + ", ".join(f"{c:.9g}" for c in values) + f" {unit[name]}"
        for name, values in p.free_parameters.items()
        if values
    ]
    lines = [
        "  free parameters "
        + ("; ".join(free) if free else "(none)")
        + f" (basis {p.basis}: L2 deviation from the quintic)"
    ]
    total = sum(len(v) for v in p.free_parameters.values())
    if 0 < total <= OLD_UNITS_MAX_FREE:
        monomials = p.path().monomials()
        old = [
            f"{name}: "
            + ", ".join(
                f"t^{6 + k} {c:.6e} {unit[name]}/s^{6 + k}"
                for k, c in enumerate(monomials[i, 6 : 6 + len(p.free_parameters[name])])
            )
            for i, name in enumerate(p.robot.joints)
            if p.free_parameters[name]
        ]
        lines.append("  as monomials    " + "; ".join(old))
    return lines


def quality_line(p: Plan) -> str:
    """The largest excursion beyond a start-goal span, and each joint's (deg, m if prismatic)."""
    assert p.quality is not None
    kinds = dict(zip(p.robot.joints, _kinds(p), strict=True))

    def shown(name: str, value: float) -> str:
        value = 0.0 if abs(value) < _RESOLVED_EXCURSION else value  # rounding, not a swing
        return f"{value:.3g} {'m' if kinds.get(name) == 'prismatic' else 'deg'}"

    q = p.quality
    each = ", ".join(f"{k} {shown(k, v)}" for k, v in q.excursion_beyond_span.items())
    largest = shown(q.largest_joint, q.largest_excursion)
    if abs(q.largest_excursion) >= _RESOLVED_EXCURSION:  # named only when it leaves its span
        largest += f" ({q.largest_joint})"
    line = f"  path quality    largest excursion beyond a start-goal span {largest}; {each}"
    if p.feasibility.planar and q.largest_excursion > FAR_EXCURSION_DEG:
        # the search's root, least freedom first: the nearer-root search is spatial only
        line += (
            "; a planar path is kept as the search found it: more free coefficients "
            "([path] extra on every joint) may find one that swings less"
        )
    return line


#: A planar path whose largest excursion exceeds this (deg) gets the hint of more freedom
#: (the spatial planner looks for a nearer root itself beyond the same 60 deg).
FAR_EXCURSION_DEG = 60.0


def objective_line(p: Plan) -> str:
    """The objective, its value and what the freedom bought, in one line."""
    o = p.objective
    if o.value is None:
        return f"  objective       {o.name}"
    line = f"  objective       {o.name} = {o.value:.6g} {o.unit}"
    if o.name == "min_norm" and p.basis != MONOMIAL_BASIS:
        line = (
            f"  objective       {o.name}: deviation from the quintic "
            f"{math.degrees(math.sqrt(max(o.value, 0.0))):.3g} deg RMS ({o.value:.4g} {o.unit})"
        )
    elif p.quality is not None:
        line += f" (deviation from the quintic {p.quality.deviation_rms_deg:.3g} deg RMS)"
    if o.error_estimate:
        line += f" (+- {o.error_estimate:.1g}, {o.quadrature_nodes} Gauss nodes)"
    if o.start_value and o.name != "min_norm":
        change = 100.0 * (o.value - o.start_value) / abs(o.start_value)
        used = ", ".join(f"{k}+{v}" for k, v in p.solver.freedom.items() if v) or "none"
        line += f"; {change:+.1f} % against the minimum-norm path; freedom {used}"
    notes = [level.note for level in o.levels if level.note]
    if o.name != "min_norm" and notes and o.value == o.start_value:  # the start path stood
        line += f"; the minimum-norm path kept: {notes[-1]}"
    elif any(note.startswith(FALLBACK_NOTE) for note in notes):
        line += "; found as " + next(n for n in notes if n.startswith(FALLBACK_NOTE))
    return line


def robot_label(scenario: Scenario) -> str:
    """The robot's name; for an inline servicer, its arm and base (not its cache hash)."""
    spec, robot = scenario.servicer, scenario.robot
    if spec is not None:
        edges = " x ".join(f"{float(x):g}" for x in spec.base_size)
        arms = " + ".join(Path(str(a.arm)).stem for a in spec.arms())
        return (
            f"servicer: {arms} arm{'s' if spec.more_arms else ''} on a {spec.base_mass:g} kg, "
            f"{edges} m base ({robot.n} joints{_held(scenario)})"
        )
    return f"{robot.name} ({Path(robot.urdf).name}, {robot.n} joints{_held(scenario)})"


def _held(scenario: Scenario) -> str:
    """``, a 5 kg payload held by panda_hand``: which end effector holds it ("" if none)."""
    if (payload := scenario.payload) is None:
        return ""
    return f", a {payload.mass:g} kg payload held by {payload_parent(scenario.robot.urdf_text)}"


def rotation_angle(rotation: np.ndarray) -> float:
    """The angle (rad, 0 to pi) of a 3 x 3 rotation matrix, accurate down to rounding.

    From both its sine (half the norm of the skew part) and its cosine (from the trace): the
    arc cosine of the trace alone turns a rounding error of 1e-16 into an angle of 1e-8 rad.
    """
    skew = rotation - rotation.T
    sine = 0.5 * math.sqrt(skew[2, 1] ** 2 + skew[0, 2] ** 2 + skew[1, 0] ** 2)
    cosine = 0.5 * (float(np.trace(rotation)) - 1.0)
    return math.atan2(sine, cosine)


def cartesian_report(scenario: Scenario, p: Plan) -> list[str]:
    """Goal joints chosen by inverse kinematics and each end effector's error at the goal."""
    if not scenario.goal_poses:
        return []
    from ..physics.momentum import MomentumMap

    kinds = _kinds(p)
    chosen = ", ".join(
        f"{name} {_joint_value(value, kind)}"
        for name, value, kind in zip(p.robot.joints, p.request.goal_joints, kinds, strict=True)
    )
    lines = [f"  goal joints     (inverse kinematics) {chosen}"]
    mmap = MomentumMap(scenario.robot)
    for frame, goal in scenario.goal_poses.items():
        pose = mmap.end_effector_pose(
            np.asarray(p.request.goal_joints), np.asarray(p.base.achieved_quaternion_xyzw), frame
        )
        miss = float(np.linalg.norm(pose.translation - goal.position))
        named = "" if len(scenario.goal_poses) == 1 else f" {frame}"
        line = (
            f"  end effector{named}    goal ("
            + ", ".join(f"{x:.4f}" for x in goal.position)
            + f") m, position error {miss:.3e} m"
        )
        if goal.rotation is not None:
            angle = math.degrees(rotation_angle(goal.rotation.T @ pose.rotation))
            line += f", orientation error {angle:.3e} deg"
        lines.append(line)
    return lines
