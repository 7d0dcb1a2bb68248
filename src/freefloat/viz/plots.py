"""Figures of a plan in the style of the reference paper (a visualisation leaf).

One figure per topic and one overview sheet, all against time in seconds:
``end_effector`` (x, y, z in m), ``base_attitude`` (ZYX Euler angles in deg),
``base_rate`` (base angular velocity in the base frame, deg/s), ``joint_positions`` (deg, or m
for prismatic joints), ``joint_rates`` (deg/s or m/s), ``joint_torques`` (N m or N), and
``end_effector_path`` (the path in the inertial x-y plane, m). Every plotted line carries the
plan's samples unchanged apart from the unit conversion named in its axis label.
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


def _draw(plan: Plan, topic: str, ax: Any) -> None:
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
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    elif topic == "base_attitude":
        zyx = np.asarray(s.base_zyx_deg)
        for i, label in enumerate(("yaw", "pitch", "roll")):
            ax.plot(t, zyx[:, i], label=label)
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
            ax.plot(t, values[:, i], label=name)
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
    ax.legend(loc="best", fontsize="small")


def figures(plan: Plan, topics: Sequence[str] = TOPICS) -> dict[str, Any]:
    """Matplotlib figures of the plan, by topic, plus ``overview`` (all topics on one sheet)."""
    plt = _pyplot()
    for topic in topics:
        if topic not in TOPICS:
            raise InputError(f"unknown figure {topic!r}; valid: {', '.join(TOPICS)}")
    title = f"{Path(plan.robot.urdf).stem}, T = {plan.duration:g} s"
    out: dict[str, Any] = {}
    for topic in topics:
        fig, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
        _draw(plan, topic, ax)
        ax.set_title(f"{topic.replace('_', ' ')} ({title})", fontsize="medium")
        out[topic] = fig
    fig, axes = plt.subplots(4, 2, figsize=(12, 14), layout="constrained")
    for topic, ax in zip(topics, axes.flat, strict=False):
        _draw(plan, topic, ax)
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
