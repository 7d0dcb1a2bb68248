"""Figures of a plan in the style of the reference paper (a visualisation leaf).

One figure per topic and one overview sheet, all against time in seconds:
``end_effector`` (x, y, z in m), ``base_attitude`` (ZYX Euler angles in deg),
``base_rate`` (base angular velocity in the base frame, deg/s), ``joint_positions`` (deg, or m
for prismatic joints), ``joint_rates`` (deg/s or m/s), ``joint_torques`` (N m or N), and
``end_effector_path`` (the path projected onto the inertial x-y plane, m; the projection is
named in the axis label). Every plotted line carries the plan's samples unchanged apart from
the unit conversion named in its axis label. Legends sit outside the data, to the right.
Marked: the goal values (joint goals at t = T, the target base attitude; dotted) and the
URDF's finite joint position and velocity limits (dashed, in the joint's colour; read from the
plan's URDF when it loads, else left out).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, ViewerError
from ..files import atomic_write
from ..plans.format import Plan

__all__ = ["TOPICS", "figures", "save_figures"]

#: Figure names, in order (the overview sheet is ``overview``).
TOPICS = (
    "end_effector",
    "end_effector_path",
    "base_attitude",
    "base_rate",
    "joint_positions",
    "joint_rates",
    "joint_torques",
)


def _pyplot() -> Any:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except Exception as exc:
        raise ViewerError(
            f"plots need matplotlib, which failed to import ({type(exc).__name__}: {exc}); "
            "reinstall it with: pip install matplotlib"
        ) from None
    return plt


def _joint_scale(plan: Plan) -> tuple[np.ndarray, list[str]]:
    kinds = plan.robot.joint_kinds or ["revolute"] * len(plan.robot.joints)
    scale = np.array([1.0 if k == "prismatic" else 180.0 / math.pi for k in kinds])
    return scale, kinds


def _limits(plan: Plan) -> dict[str, tuple[float, float, float]]:
    """Per joint ``(lower, upper, velocity)`` limits (rad, rad/s or m, m/s); {} if no URDF."""
    from ..errors import FreeFloatError
    from ..robot.model import load_robot

    try:
        robot = load_robot(plan.robot.urdf, plan.robot.end_effector)
    except (FreeFloatError, OSError):
        return {}
    return {j.name: (j.lower, j.upper, j.velocity_limit) for j in robot.joints}


def _draw(
    plan: Plan, topic: str, ax: Any, limits: dict[str, tuple[float, float, float]] | None = None
) -> None:
    limits = limits or {}
    s = plan.samples
    t = np.asarray(s.t)
    scale, kinds = _joint_scale(plan)
    names = plan.robot.joints
    unit = "deg" if all(k != "prismatic" for k in kinds) else "deg | m"
    if topic == "end_effector":
        ee = np.asarray(s.end_effector_position)
        for i, axis in enumerate("xyz"):
            if i < 2 or np.ptp(ee[:, 2]) > 1e-9:
                ax.plot(t, ee[:, i], label=f"${axis}_E$")
        ax.set_ylabel("end effector [m]")
    elif topic == "end_effector_path":
        ee = np.asarray(s.end_effector_position)
        ax.plot(ee[:, 0], ee[:, 1], label="path")
        ax.plot(ee[:1, 0], ee[:1, 1], "o", label="start")
        ax.plot(ee[-1:, 0], ee[-1:, 1], "s", label="goal")
        ax.plot([0.0], [0.0], "+", color="k", label="system CM")
        ax.set_aspect("equal", adjustable="datalim")
        flat = np.ptp(ee[:, 2]) <= 1e-9
        plane = "inertial x-y plane" if flat else "projection onto the inertial x-y plane"
        ax.set_xlabel(f"x [m] ({plane})")
        ax.set_ylabel("y [m]")
    elif topic == "base_attitude":
        zyx = np.asarray(s.base_zyx_deg)
        for i, label in enumerate(("yaw", "pitch", "roll")):
            (line,) = ax.plot(t, zyx[:, i], label=label)
            ax.axhline(
                plan.base.target_zyx_deg[i],
                color=line.get_color(),
                linestyle=":",
                linewidth=1,
                label="_goal",
            )
        ax.plot([], [], ":", color="0.3", label="goal")
        ax.set_ylabel("base attitude [deg]")
    elif topic == "base_rate":
        omega = np.degrees(np.asarray(s.base_angular_velocity))
        for i, axis in enumerate("xyz"):
            ax.plot(t, omega[:, i], label=f"$\\omega_{axis}$")
        ax.set_ylabel("base angular rate [deg/s]")
    elif topic in ("joint_positions", "joint_rates", "joint_torques"):
        key = {"joint_positions": "q", "joint_rates": "qd", "joint_torques": "tau"}[topic]
        values = np.asarray(getattr(s, key), dtype=float)
        if topic != "joint_torques":
            values = values * scale
        for i, name in enumerate(names):
            (line,) = ax.plot(t, values[:, i], label=name)
            colour = line.get_color()
            if topic == "joint_positions" and i < len(plan.request.goal_joints):
                goal = plan.request.goal_joints[i] * scale[i]
                ax.plot([t[-1]], [goal], "o", mfc="none", color=colour, label="_goal")
            lower, upper, rate = limits.get(name, (-math.inf, math.inf, math.inf))
            marks = (lower, upper) if topic == "joint_positions" else (-rate, rate)
            if topic != "joint_torques":
                for mark in marks:
                    if math.isfinite(mark):
                        ax.axhline(
                            mark * scale[i],
                            color=colour,
                            linestyle="--",
                            linewidth=0.8,
                            label="_limit",
                        )
        if topic == "joint_positions":
            ax.plot([], [], "o", mfc="none", color="0.3", label="goal at T")
        if any(line.get_label() == "_limit" for line in ax.lines):
            ax.plot([], [], "--", color="0.3", label="limit (URDF)")
        ax.set_ylabel(
            {
                "joint_positions": f"joint position [{unit}]",
                "joint_rates": f"joint rate [{unit}/s]",
                "joint_torques": "joint torque [N m | N]"
                if "prismatic" in kinds
                else "joint torque [N m]",
            }[topic]
        )
    else:  # pragma: no cover - guarded by the callers
        raise InputError(f"unknown figure {topic!r}; valid: {', '.join(TOPICS)}")
    if topic != "end_effector_path":
        ax.set_xlabel("t [s]")
        ax.set_xlim(0.0, plan.duration)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, fontsize="small")


def figures(plan: Plan, topics: Sequence[str] = TOPICS) -> dict[str, Any]:
    """Matplotlib figures of the plan, by topic, plus ``overview`` (all topics on one sheet)."""
    plt = _pyplot()
    for topic in topics:
        if topic not in TOPICS:
            raise InputError(f"unknown figure {topic!r}; valid: {', '.join(TOPICS)}")
    title = f"{Path(plan.robot.urdf).stem}, T = {plan.duration:g} s"
    limits = _limits(plan)
    out: dict[str, Any] = {}
    for topic in topics:
        fig, ax = plt.subplots(figsize=(7.6, 4.0), layout="constrained")
        _draw(plan, topic, ax, limits)
        ax.set_title(f"{topic.replace('_', ' ')} ({title})", fontsize="medium")
        out[topic] = fig
    fig, axes = plt.subplots(4, 2, figsize=(12, 14), layout="constrained")
    for topic, ax in zip(topics, axes.flat, strict=False):
        _draw(plan, topic, ax, limits)
        ax.set_title(topic.replace("_", " "), fontsize="medium")
    for ax in list(axes.flat)[len(topics) :]:
        ax.axis("off")
    fig.suptitle(f"freefloat plan: {title}")
    out["overview"] = fig
    return out


def save_figures(plan: Plan, directory: str | Path, svg: bool = False) -> list[Path]:
    """Write PNG (and SVG) files of every figure into ``directory``; return their paths.

    Each file is written atomically (temporary file, then renamed).
    """
    plt = _pyplot()
    folder = Path(directory).expanduser().resolve()
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name, fig in figures(plan).items():
        dpi = 80 if name == "overview" else 110
        for ext in ("png", "svg") if svg else ("png",):

            def save(tmp: Path, fig: Any = fig, ext: str = ext, dpi: int = dpi) -> None:
                fig.savefig(tmp, dpi=dpi, format=ext)

            written.append(atomic_write(folder / f"{name}.{ext}", save, suffix=f".{ext}"))
        plt.close(fig)
    return written
