"""MCAP export (opens in Foxglove): ROS 2 messages, CDR-encoded, with their definitions.

Written with ``mcap`` and ``mcap-ros2-support``; message classes and definitions come from
``rosbags`` (see :mod:`freefloat.export.messages` for topics and frames). Log and publish
times are nanoseconds from the plan's start.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ViewerError
from ..files import atomic_write
from ..plans.format import Plan
from .messages import (
    END_EFFECTOR_RECORD,
    end_effector_topics,
    messages,
    root_link,
    typestore,
)
from .trajectory import Trajectory

__all__ = ["write", "write_mcap"]


def write(traj: Trajectory, path: str | Path, plan: Plan) -> Path:
    """The export registry's entry: :func:`write_mcap` of the plan's trajectory."""
    return write_mcap(traj, path, plan.robot.urdf, plan.robot.urdf_text)


def write_mcap(traj: Trajectory, path: str | Path, urdf: str, urdf_text: str = "") -> Path:
    """Write the trajectory as an MCAP file atomically; return the absolute path.

    Raises:
        ViewerError: mcap or mcap-ros2-support is missing.
    """
    try:
        from mcap_ros2.writer import Writer
    except ImportError as exc:
        raise ViewerError(
            f"MCAP export needs mcap-ros2-support ({exc}); install it with: "
            "pip install mcap mcap-ros2-support"
        ) from None
    ts = typestore()
    child = root_link(urdf, urdf_text)

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as handle:
            writer = Writer(handle)
            writer.add_metadata(END_EFFECTOR_RECORD, {"topics": end_effector_topics(traj)})
            schemas: dict[str, Any] = {}
            for msg in messages(traj, child):
                if msg.msgtype not in schemas:
                    text, _ = ts.generate_msgdef(msg.msgtype, ros_version=2)
                    schemas[msg.msgtype] = writer.register_msgdef(msg.msgtype, text)
                writer.write_message(
                    msg.topic,
                    schemas[msg.msgtype],
                    _plain(msg.message),
                    log_time=msg.time_ns,
                    publish_time=msg.time_ns,
                )
            writer.finish()

    return atomic_write(path, write, suffix=".mcap")


def _plain(value: Any) -> Any:
    """A rosbags message as the dicts and lists mcap-ros2-support encodes (arrays as lists)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    return value
