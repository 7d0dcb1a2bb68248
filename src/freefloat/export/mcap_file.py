"""MCAP export (opens in Foxglove): ROS 2 messages, CDR-encoded, with their definitions.

Written with ``mcap``'s writer (profile ``ros2``, zstd chunks, as ``mcap-ros2-support``
writes them); the message classes, their CDR bytes and their definitions come from
``rosbags`` (see :mod:`freefloat.export.messages` for topics and frames), the same bytes a
ROS 2 bag holds. Log and publish times are nanoseconds from the plan's start.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..errors import ViewerError
from ..files import atomic_write
from ..plans.format import Plan
from .messages import (
    END_EFFECTOR_RECORD,
    end_effector_topics,
    export_frames,
    messages,
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
        ViewerError: mcap is missing.
    """
    try:
        from mcap.writer import LIBRARY_IDENTIFIER, CompressionType, Writer
    except ImportError as exc:
        raise ViewerError(
            f"MCAP export needs mcap ({exc}); install it with: pip install mcap"
        ) from None
    ts = typestore()
    frames = export_frames(urdf, urdf_text)

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as handle:
            writer = Writer(handle, compression=CompressionType.ZSTD)
            writer.start(profile="ros2", library=f"{LIBRARY_IDENTIFIER} freefloat")
            writer.add_metadata(END_EFFECTOR_RECORD, {"topics": end_effector_topics(traj)})
            channels: dict[str, int] = {}
            schemas: dict[str, int] = {}
            for msg in messages(traj, frames):
                channel = channels.get(msg.topic)
                if channel is None:
                    channel = channels[msg.topic] = _channel(
                        writer, ts, msg.topic, msg.msgtype, schemas
                    )
                writer.add_message(
                    channel_id=channel,
                    log_time=msg.time_ns,
                    publish_time=msg.time_ns,
                    data=bytes(ts.serialize_cdr(msg.message, msg.msgtype)),
                )
            writer.finish()

    return atomic_write(path, write, suffix=".mcap")


def _channel(writer: Any, ts: Any, topic: str, msgtype: str, schemas: dict[str, int]) -> int:
    """Register ``topic`` (and its type's definition, once per type); its channel id."""
    if msgtype not in schemas:
        text, _ = ts.generate_msgdef(msgtype, ros_version=2)
        schemas[msgtype] = writer.register_schema(msgtype, "ros2msg", text.encode())
    return int(writer.register_channel(topic, "cdr", schemas[msgtype]))
