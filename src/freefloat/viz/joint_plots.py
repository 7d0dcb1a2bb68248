"""The joint figures of a plan: positions, rates or torques, with goals and URDF limits.

A leaf of :mod:`freefloat.viz.plots`: joint values in deg (m for prismatic joints, on an axis
of their own when the robot has revolute joints too), rates in deg/s or m/s, torques in N m
or N; the goals at T and the URDF's finite position and velocity limits dashed in each joint's
colour, unless far beyond the data (:data:`LIMIT_SPANS`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..excerpts import shortened
from ..plans.format import Plan

__all__ = ["LIMIT_SPANS", "draw_joints"]


#: A limit is drawn when it lies within this many spans of the figure's data beyond the data
#: (a limit far beyond, 1000 rad/s against motions of a few deg/s, would flatten every line);
#: the others are named in the legend.
LIMIT_SPANS = 2.0


def _joint_styles(count: int) -> list[tuple[Any, Any]]:
    """(colour, line style) per joint: ten colours, twenty beyond ten joints, then dashes."""
    import matplotlib

    if count <= 10:
        return [(f"C{i}", "-") for i in range(count)]
    colours = matplotlib.colormaps["tab20"]
    dashes = ("-", "--", "-.", ":")
    return [(colours(i % 20), dashes[(i // 20) % 4]) for i in range(count)]


def draw_joints(
    plan: Plan,
    topic: str,
    ax: Any,
    limits: dict[str, tuple[float, float, float]],
    scale: np.ndarray,
    kinds: list[str],
) -> Any:
    """Joint positions, rates or torques (deg, m, N m, N) with their goals and URDF limits.

    Prismatic joints of a robot with revolute ones too get an axis of their own on the right
    (m, m/s, N), returned (None when every joint shares one axis).
    """
    s = plan.samples
    t = np.asarray(s.t)
    key = {"joint_positions": "q", "joint_rates": "qd", "joint_torques": "tau"}[topic]
    values = np.asarray(getattr(s, key), dtype=float)
    if topic != "joint_torques":
        values = values * scale
    sliding = np.array([k == "prismatic" for k in kinds], dtype=bool)
    twin = ax.twinx() if sliding.any() and not sliding.all() else None
    styles = _joint_styles(len(plan.robot.joints))
    beyond: list[str] = []
    for group, axis in ((~sliding, ax), (sliding, twin)) if twin is not None else ((None, ax),):
        chosen = range(len(kinds)) if group is None else np.flatnonzero(group).tolist()
        beyond += _draw_group(plan, topic, axis, t, values, scale, limits, styles, chosen)
    if topic == "joint_positions":
        ax.plot([], [], "o", mfc="none", color="0.3", label="goal at T")
    if any(line.get_label() == "_limit" for a in (ax, twin) if a for line in a.lines):
        ax.plot([], [], "--", color="0.3", label="limit (URDF)")
    if beyond:  # named in a narrow legend entry: a long one would squeeze the axes
        which = "\n".join(beyond) if len(beyond) <= 3 else f"{len(beyond)} joints"
        ax.plot([], [], " ", label=f"limits beyond the axes\n(not drawn): {which}")
    quantity = {"joint_positions": "position", "joint_rates": "rate", "joint_torques": "torque"}
    units = {"joint_positions": ("deg", "m"), "joint_rates": ("deg/s", "m/s")}
    turning, moving = units.get(topic, ("N m", "N"))
    ax.set_ylabel(f"joint {quantity[topic]} [{moving if sliding.all() else turning}]")
    if twin is not None:
        twin.set_ylabel(f"prismatic joint {quantity[topic]} [{moving}]")
    return twin


def _draw_group(
    plan: Plan,
    topic: str,
    ax: Any,
    t: np.ndarray,
    values: np.ndarray,
    scale: np.ndarray,
    limits: dict[str, tuple[float, float, float]],
    styles: list[tuple[Any, Any]],
    chosen: Sequence[int],
) -> list[str]:
    """The ``chosen`` joints' lines, goals and limits on ``ax``.

    Returns the joints whose limits lie beyond the axes (:data:`LIMIT_SPANS`): not drawn.
    """
    names = plan.robot.joints
    data = values[:, list(chosen)]
    low, high = (float(data.min()), float(data.max())) if data.size else (0.0, 0.0)
    reach = LIMIT_SPANS * max(high - low, 1e-9 + 1e-3 * max(abs(low), abs(high)))
    beyond = []
    for i in chosen:
        colour, style = styles[i]
        ax.plot(t, values[:, i], color=colour, linestyle=style, label=shortened(names[i]))
        if topic == "joint_positions" and i < len(plan.request.goal_joints):
            goal = plan.request.goal_joints[i] * scale[i]
            ax.plot([t[-1]], [goal], "o", mfc="none", color=colour, label="_goal")
        if topic == "joint_torques":
            continue
        lower, upper, rate = limits.get(names[i], (-math.inf, math.inf, math.inf))
        marks = [
            m * scale[i] for m in ((lower, upper) if topic == "joint_positions" else (-rate, rate))
        ]
        marks = [m for m in marks if math.isfinite(m)]
        shown = [m for m in marks if low - reach <= m <= high + reach]
        for mark in shown:
            ax.axhline(mark, color=colour, linestyle="--", linewidth=0.8, label="_limit")
        if len(shown) < len(marks):
            beyond.append(shortened(names[i]))
    return beyond
