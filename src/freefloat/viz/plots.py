"""Figures of a plan in the style of the reference paper (a visualisation leaf).

One figure per topic and one overview sheet, all against time in seconds:
``end_effector`` (x, y, z in m), ``base_attitude`` (ZYX Euler angles in deg),
``base_rate`` (base angular velocity in the base frame, deg/s), ``joint_positions`` (deg, or m
for prismatic joints), ``joint_rates`` (deg/s or m/s), ``joint_torques`` (N m or N), and
``end_effector_path`` (the path projected onto the inertial x-y plane, m; the projection is
named in the axis label). Every plotted line carries the plan's samples unchanged apart from
the unit conversion named in its axis label; a robot with both revolute and prismatic joints
draws the prismatic ones on an axis of their own, on the right (m, m/s, N). Legends sit
outside the data, to the right. More than ten joints take twenty colours, then line styles.
Marked: the goal values (joint goals at t = T, the target base attitude; dotted) and the
URDF's finite joint position and velocity limits (dashed, in the joint's colour; read from the
plan's URDF when it loads, else left out). A limit more than
:data:`~freefloat.viz.joint_plots.LIMIT_SPANS` spans of the
figure's data beyond it is not drawn (1000 rad/s would flatten a motion of a few deg/s):
the legend names the joints whose limits lie beyond the axes. Titles name the robot by its
URDF's ``<robot name>`` (:func:`~freefloat.viz.controls.robot_label`).

``clearance`` (only when the plan was kept clear, ``plan.safety.checked``): the smallest signed
distance (m) over the checked pairs, recomputed with the plan's collision model (its SRDF and
keep-out objects) on :data:`~freefloat.viz.clearance_curve.CLEARANCE_SAMPLES` instants of the
plan's polynomials, the margin dashed, and the closest pair named in the legend. Skipped when
not checked, or when the collision model cannot be built (with a warning).
"""

from __future__ import annotations

import logging
import math
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError, ViewerError
from ..excerpts import LABEL_CHARS, shortened
from ..files import check_output
from ..plans.format import Plan
from ..staged import staged_folder
from .clearance_curve import ClearanceCurve, clearance_curve
from .controls import robot_label
from .joint_plots import draw_joints

__all__ = ["OPTIONAL_TOPICS", "TOPICS", "figure_paths", "figures", "save_figures"]

LOGGER = logging.getLogger(__name__)

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
#: Figures drawn only when the plan has what they show (``clearance``: ``safety.checked``).
OPTIONAL_TOPICS = ("clearance",)


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
    from ..plans.robot_copy import plan_robot

    try:
        robot = plan_robot(plan)
    except (FreeFloatError, OSError):
        return {}
    return {j.name: (j.lower, j.upper, j.velocity_limit) for j in robot.joints}


def _draw(
    plan: Plan,
    topic: str,
    ax: Any,
    limits: dict[str, tuple[float, float, float]] | None = None,
    clearance: ClearanceCurve | None = None,
) -> None:
    """Draw figure ``topic`` of ``plan`` on ``ax``, with its axes, grid and legend."""
    twin = None
    if topic in _DRAWERS:
        _DRAWERS[topic](plan, ax)
    elif topic in ("joint_positions", "joint_rates", "joint_torques"):
        scale, kinds = _joint_scale(plan)
        twin = draw_joints(plan, topic, ax, limits or {}, scale, kinds)
    elif topic == "clearance" and clearance is not None:
        _draw_clearance(clearance, ax)
    else:  # pragma: no cover - guarded by the callers
        raise InputError(f"unknown figure {topic!r}; valid: {', '.join(TOPICS)}")
    if topic != "end_effector_path":
        ax.set_xlabel("t [s]")
        ax.set_xlim(0.0, plan.duration)
    ax.grid(True, alpha=0.3)
    handles, labels = ax.get_legend_handles_labels()
    if twin is not None:  # its joints after the others, before the marks; beyond its ticks
        joints = set(plan.robot.joints)
        first = [k for k, label in enumerate(labels) if label in joints]
        marks = [k for k, label in enumerate(labels) if label not in joints]
        more = twin.get_legend_handles_labels()
        handles = [handles[k] for k in first] + more[0] + [handles[k] for k in marks]
        labels = [labels[k] for k in first] + more[1] + [labels[k] for k in marks]
    ax.legend(
        handles,
        labels,
        loc="upper left",
        bbox_to_anchor=(1.02 if twin is None else 1.16, 1.0),
        borderaxespad=0.0,
        fontsize="small",
    )


def _draw_end_effector(plan: Plan, ax: Any) -> None:
    """Every end effector's x, y (and z when it moves) against time (m)."""
    frames, t = plan.robot.frames, np.asarray(plan.samples.t)
    for number, frame in enumerate(frames):
        ee = np.asarray(plan.samples.path_of(frame))
        tag = "" if len(frames) == 1 else f" {frame}"
        for i, axis in enumerate("xyz"):
            if i < 2 or np.ptp(ee[:, 2]) > 1e-9:
                style = "-" if number == 0 else (0, (4, 2 * number))
                ax.plot(t, ee[:, i], linestyle=style, label=f"${axis}_E${tag}")
    ax.set_ylabel("end effector [m]" if len(frames) == 1 else "end effectors [m]")


def _draw_end_effector_path(plan: Plan, ax: Any) -> None:
    """Every end effector's path in the inertial x-y plane (m), with start, goal and CM."""
    frames = plan.robot.frames
    flat = True
    for frame in frames:
        ee = np.asarray(plan.samples.path_of(frame))
        tag = "" if len(frames) == 1 else f" {frame}"
        (line,) = ax.plot(ee[:, 0], ee[:, 1], label=f"path{tag}")
        color = line.get_color()
        ax.plot(ee[:1, 0], ee[:1, 1], "o", color=color, label=f"start{tag}")
        ax.plot(ee[-1:, 0], ee[-1:, 1], "s", color=color, label=f"goal{tag}")
        flat = flat and np.ptp(ee[:, 2]) <= 1e-9
    ax.plot([0.0], [0.0], "+", color="k", label="system CM")
    ax.set_aspect("equal", adjustable="datalim")
    plane = "inertial x-y plane" if flat else "projection onto the inertial x-y plane"
    ax.set_xlabel(f"x [m] ({plane})")
    ax.set_ylabel("y [m]")


def _draw_base_attitude(plan: Plan, ax: Any) -> None:
    """Yaw, pitch and roll of the base (deg) against time, with their goals at T."""
    t, zyx = np.asarray(plan.samples.t), np.asarray(plan.samples.base_zyx_deg)
    # Angles often coincide (pitch and roll both 0 for a planar robot): each has its own
    # line style and marker, and the goals are drawn over the data (open markers at T).
    styles = (("-", "o"), ("--", "s"), ("-.", "^"))
    for i, label in enumerate(("yaw", "pitch", "roll")):
        linestyle, marker = styles[i]
        (line,) = ax.plot(
            t,
            zyx[:, i],
            linestyle=linestyle,
            marker=marker,
            markevery=max(1, len(t) // 8),
            markersize=4,
            label=label,
        )
        goal = plan.base.target_zyx_deg[i]
        ax.axhline(goal, color=line.get_color(), linestyle=":", linewidth=1, label="_goal")
        ax.plot(
            [t[-1]],
            [goal],
            marker=marker,
            markersize=10 - 2 * i,
            mfc="none",
            mew=1.5,
            color=line.get_color(),
            zorder=5,
            label="_goal_at_T",
        )
    ax.plot([], [], ":", marker="o", mfc="none", color="0.3", label="goal (at T)")
    ax.set_ylabel("base attitude [deg]")


def _draw_base_rate(plan: Plan, ax: Any) -> None:
    """The base's angular velocity (deg/s, base frame) against time."""
    t = np.asarray(plan.samples.t)
    omega = np.degrees(np.asarray(plan.samples.base_angular_velocity))
    for i, axis in enumerate("xyz"):
        ax.plot(t, omega[:, i], label=f"$\\omega_{axis}$")
    ax.set_ylabel("base angular rate [deg/s]")


def _draw_clearance(clearance: ClearanceCurve, ax: Any) -> None:
    """The smallest clearance (m) against time, its closest instant and the margin."""
    value, when, pair = clearance.closest
    ax.plot(clearance.t, clearance.smallest, label="smallest clearance")
    closest = f"closest: {shortened(pair, 2 * LABEL_CHARS)}\n{value:.4g} m at {when:.3g} s"
    ax.plot([when], [value], "o", mfc="none", label=closest)
    ax.axhline(clearance.margin, color="C3", linestyle="--", linewidth=1, label="margin")
    ax.set_ylabel("clearance [m]")


#: The figures drawn from the plan alone, by topic.
_DRAWERS: dict[str, Callable[[Plan, Any], None]] = {
    "end_effector": _draw_end_effector,
    "end_effector_path": _draw_end_effector_path,
    "base_attitude": _draw_base_attitude,
    "base_rate": _draw_base_rate,
}


def _clearance(plan: Plan) -> ClearanceCurve | None:
    from ..errors import FreeFloatError

    try:
        return clearance_curve(plan)
    except (FreeFloatError, OSError) as exc:
        LOGGER.warning("no clearance figure: %s", exc)
        return None


def figures(plan: Plan, topics: Sequence[str] = (*TOPICS, *OPTIONAL_TOPICS)) -> dict[str, Any]:
    """Matplotlib figures of the plan, by topic, plus ``overview`` (all topics on one sheet).

    ``clearance`` is left out when the plan was not kept clear (see the module).
    """
    plt = _pyplot()
    valid = (*TOPICS, *OPTIONAL_TOPICS)
    for topic in topics:
        if topic not in valid:
            raise InputError(f"unknown figure {topic!r}; valid: {', '.join(valid)}")
    title = f"{robot_label(plan)}, T = {plan.duration:g} s"
    limits = _limits(plan)
    clearance = _clearance(plan) if "clearance" in topics else None
    if clearance is None:  # not checked (or no model): no clearance figure
        topics = [topic for topic in topics if topic != "clearance"]
    out: dict[str, Any] = {}
    for topic in topics:
        fig, ax = plt.subplots(figsize=(7.6, 4.0), layout="constrained")
        _draw(plan, topic, ax, limits, clearance)
        ax.set_title(f"{topic.replace('_', ' ')} ({title})", fontsize="medium")
        out[topic] = fig
    fig, axes = plt.subplots(4, 2, figsize=(12, 14), layout="constrained")
    for topic, ax in zip(topics, axes.flat, strict=False):
        _draw(plan, topic, ax, limits, clearance)
        ax.set_title(topic.replace("_", " "), fontsize="medium")
    for ax in list(axes.flat)[len(topics) :]:
        ax.axis("off")
    fig.suptitle(f"freefloat plan: {title}")
    out["overview"] = fig
    return out


def figure_paths(folder: Path, svg: bool = False, clearance: bool = False) -> list[Path]:
    """The files :func:`save_figures` writes into ``folder``; ``clearance``: with its figure.

    Each is checked before any is written.
    """
    names = [*TOPICS, *(["clearance"] if clearance else []), "overview"]
    return [
        folder / f"{name}.{ext}" for name in names for ext in (("png", "svg") if svg else ("png",))
    ]


def save_figures(plan: Plan, directory: str | Path, svg: bool = False) -> list[Path]:
    """Write PNG (and SVG) files of every figure into ``directory``; return their paths.

    Every name is checked before the first figure is drawn, and the figures are moved into
    ``directory`` only once all are written (:func:`~freefloat.staged.staged_folder`): a
    full disk or an interruption leaves none of them behind.
    """
    plt = _pyplot()
    folder = Path(directory).expanduser().resolve()
    for path in figure_paths(folder, svg, plan.safety.checked):  # all, before any is drawn
        check_output(path, "a figure")
    written = []
    with (
        warnings.catch_warnings(record=True) as caught,  # matplotlib's, one per glyph
        staged_folder(folder) as stage,
    ):
        warnings.filterwarnings("always", message="Glyph .* missing from", category=UserWarning)
        for name, fig in figures(plan).items():
            dpi = 80 if name == "overview" else 110
            for ext in ("png", "svg") if svg else ("png",):
                fig.savefig(stage / f"{name}.{ext}", dpi=dpi, format=ext)
                written.append(folder / f"{name}.{ext}")
            plt.close(fig)
    if any("missing from" in str(w.message) for w in caught):
        LOGGER.warning(
            "some names use characters the plots' font lacks (joint names in another script, "
            "say); they are drawn as boxes"
        )
    for w in caught:  # anything else, as it was
        if "missing from" not in str(w.message):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return written
