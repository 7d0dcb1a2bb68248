"""The reach report as lines for people (degrees), with attitudes to paste into a scenario."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..physics.attitude import geodesic_angle, relative_rotvec
from ..reachable import SMALL_REACH_DEG, ReachReport
from ..robot.model import Robot
from ..solvers.hints import finger_hint
from ..solvers.loop_start import LOOP_TURN
from ..solvers.reach import DEFAULT_MAX_ANGLE, ReachEstimate

__all__ = ["estimate_lines", "goal_joint_lines", "reach_lines", "verdict"]


def _vector(values: np.ndarray, digits: int = 4) -> str:
    return "[" + ", ".join(f"{v:.{digits}f}" for v in values) + "]"


def verdict(report: ReachReport) -> str:
    """One line when the reach is small, naming why (the inertia ratio); "" otherwise."""
    largest = math.degrees(report.largest_outer)
    if report.drift_breaks and not report.loops:
        return (
            f"the drift attitude breaks {report.drift_breaks}: no goal listed above plans; "
            "goals nearer the start may, which this report, measured from the drift attitude, "
            "does not search"
        )
    if report.loops:
        return (
            "the goal joints are the start joints: every motion is a loop, which no simple-"
            "motion bound covers; plan starts each such goal from a loop (docs/reach.md)"
        )
    if len(report.freedom) == 1:
        quaternion = [float(v) for v in report.drift_quaternion]
        return (
            "with one joint every path turns the spacecraft alike: the drift attitude is the "
            f"only goal, base_quaternion_xyzw = {quaternion} (the figures above are rounded)"
        )
    if largest >= SMALL_REACH_DEG:
        return ""
    if report.bound is not None:
        turn = math.degrees(report.bound.bound)
        what = f"at most {turn:.2g} deg from the start attitude per simple motion"
    else:
        what = f"at most {largest:.2g} deg from the drift attitude per simple motion"
    return (
        f"this spacecraft is {report.inertia_ratio:.3g}x the arm's inertia: {what}; "
        "a goal farther away needs joints that go back and forth, which plan may find (with "
        "larger joint excursions) or refuse"
    )


def goal_joint_lines(report: ReachReport, robot: Robot) -> list[str]:
    """For an end-effector goal: the joints it was solved into, as a table to paste (deg, m).

    The goals of the report are reached with these joints; kept as an end-effector goal, the
    joints are solved anew at the attitude pasted and may move far (another branch of the
    arm's inverse kinematics), and the reach with them. Empty for a goal given as joints.
    """
    if not report.end_effector_goal:
        return []
    values = [
        (joint.name, math.degrees(value) if joint.angular else value)
        for joint, value in zip(robot.joints, report.goal_joints.tolist(), strict=True)
    ]
    return [
        "goal joints: solved from the scenario's end-effector goal at its stated attitude; the",
        "  goals below are reached with these joints: paste them in place of the",
        "  [goal.end_effectors.*] tables (kept, they are solved anew at the attitude pasted,",
        "  possibly on another branch of the arm, with another drift attitude and reach):",
        "  [goal.joints]  # deg (m for prismatic joints)",
        *(f"  {name} = {value:.6f}" for name, value in values),
    ]


def _outer_lines(report: ReachReport) -> list[str]:
    """A spatial report's outer bound for simple motions and how the inner estimate ran."""
    assert report.bound is not None
    lines: list[str] = []
    bound = report.bound
    travel = (
        "every joint monotone between start and goal"
        if bound.travel_factor == 1.0
        else f"every joint travelling at most {bound.travel_factor:g}x its start-goal span"
    )
    lines += [
        f"outer bound for simple motions ({travel}):",
        f"  the base turns at most {math.degrees(bound.bound):.4g} deg from the start "
        "attitude (sum over joints of the largest",
        "  |F1 column| over the configurations such a path visits, sampled and refined, times",
        "  the joint's travel);",
        "  a path whose joints go back and forth is not bounded by it: plan may turn further",
    ]
    if report.goal_judged:
        names = ", ".join(f"[constraints.{name}]" for name in report.goal_judged)
        lines.append(f"  a goal attitude is held to {names}: outer and inner stop where it breaks")
    heads = (
        f"from a {math.degrees(LOOP_TURN):g} deg loop about each axis towards "
        f"{math.degrees(DEFAULT_MAX_ANGLE):g} deg (the joints end where they start)"
        if report.loops
        else "from the drift attitude towards the outer bound"
    )
    if report.budget > 0:
        lines += [
            f"inner estimate: continuation {heads}, "
            f"freedom +{max(report.freedom)} per joint, {report.budget} residual evaluations "
            "per continuation pass;",
            "  the goal at 'inner' about a listed axis is solved by plan's own search, and",
            "  nearer goals about it take the same steps (as a rule, not a proof: docs/reach.md)",
        ]
    else:
        lines.append("inner estimate: not computed (--budget 0)")
    return lines


def reach_lines(report: ReachReport, robot: Robot | None = None) -> list[str]:
    """The report: drift attitude, outer bound, inner estimate per direction, verdict.

    With ``robot`` (the report's), an end-effector goal's joints too (:func:`goal_joint_lines`).
    """
    kind = "planar" if report.planar else "spatial"
    drift = report.drift_quaternion
    lines = [
        f"freefloat reach: {report.robot} ({kind})",
        "drift attitude (where the plain quintic path leaves the spacecraft):",
        f"  base_zyx_deg = {_vector(report.drift_zyx_deg)}",
        f"  base_quaternion_xyzw = {_vector(drift, 6)}",
        *([] if robot is None else goal_joint_lines(report, robot)),
        f"spacecraft / arm rotational inertia about the system CM (ratio): "
        f"{report.inertia_ratio:.3g}",
    ]
    if report.bound is not None and len(report.freedom) == 1:  # nothing to bound or trace
        lines.append(
            "one joint: every path between these joints reaches the drift attitude, whatever "
            "its timing or its back-and-forth (docs/reach.md)"
        )
    elif report.bound is not None:
        lines += _outer_lines(report)
    else:
        lines.append(
            "planar bounds (docs/method.md section 6): the yaw changes simple motions reach"
        )
    if not report.planar:
        lines.append("  per axis, turns measured from the drift attitude:")
        away = math.degrees(geodesic_angle(report.start_quaternion, drift))
        within = math.degrees(report.bound.bound) if report.bound is not None else 0.0
        if away < within < 180.0 and len(report.freedom) > 1:  # why the outer column is larger
            lines.append(
                f"  (outer: as far as the attitude stays within {within:.4g} deg of the start; "
                f"the drift lies {away:.3g} deg from it)"
            )
    lines.append(
        f"  {'axis (base frame)':<20}{'inner [deg]':>12}{'outer [deg]':>12}  "
        f"{'goal base_zyx_deg at inner':<30}  stopped by"
    )
    skipped = report.budget == 0 and not report.planar  # no inner estimate: nothing to paste
    for d in report.directions:
        axis = " ".join(f"{x:+.2f}" for x in d.axis)
        headed = f"the {math.degrees(DEFAULT_MAX_ANGLE):g} deg it headed for"
        why = d.stopped_by or (headed if report.loops else "its outer bound (heads no further)")
        if skipped:
            why = "-"
        if d.breaks:
            why += f"; at this duration breaks {d.breaks}"
        inner = f"{'-':>12}" if skipped else f"{math.degrees(d.inner):>12.2f}"
        goal = "-" if skipped else _vector(d.goal_zyx_deg, 4)
        lines.append(f"  {axis:<20}{inner}{math.degrees(d.outer):>12.2f}  {goal:<30}  {why}")
    if report.planar and len(report.freedom) > 1:
        lines.append("  the interval is open: a goal at its very end is not reached")
    if robot is not None:  # a finger's limit stopped some direction: say how to hold them
        fingers = sorted({finger_hint(robot, d.stopped_by) for d in report.directions} - {""})
        lines += [f"note: {fingers[0]}"] if fingers else []
    said = verdict(report)
    if said:
        lines.append(f"verdict: {said}")
    return lines


def estimate_lines(
    estimate: ReachEstimate,
    joint_names: Sequence[str],
    max_angle: float,
    goal: np.ndarray | None = None,
    within: Sequence[str] = ("joint_position_limits",),
) -> list[str]:
    """The estimate as lines for people (degrees), saying plainly that it is an inner one.

    With ``goal`` (``[x, y, z, w]``), a last line gives the rotation it asks for from the
    quintic path's attitude. ``within``: the names of the constraints the paths keep.
    """
    freedom = ", ".join(f"{n}+{k}" for n, k in zip(joint_names, estimate.freedom, strict=True) if k)
    lines = [
        "from the attitude the quintic path reaches, continuation heads up to",
        f"{math.degrees(max_angle):g} deg about each direction within {', '.join(within)}, "
        "with the freedom",
        f"{freedom}; every rotation up to 'reached' is planned by a solved path.",
        "More freedom, or paths continuation does not find, may reach further.",
        f"{'axis (base frame)':<24}{'reached [deg]':>14}  stopped by",
    ]
    for d in estimate.directions:
        axis = " ".join(f"{x:+.2f}" for x in d.axis)
        lines.append(f"{axis:<24}{math.degrees(d.reached):>14.2f}  {d.stopped_by or '-'}")
    if goal is not None:
        wanted = relative_rotvec(estimate.quintic_quaternion, goal)
        angle = float(np.linalg.norm(wanted))
        axis = " ".join(f"{x:+.2f}" for x in wanted / max(angle, 1e-300))
        lines.append(
            f"requested: {math.degrees(angle):.2f} deg about {axis} from the quintic attitude"
        )
    return lines
