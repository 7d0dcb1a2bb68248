"""ROS 2 bag export (``rosbag2``, SQLite storage) with the pure-Python ``rosbags`` writer.

A ROS 2 bag is a folder (``metadata.yaml`` and one ``.db3`` file); ``ros2 bag play`` and
``rosbags``' reader open it. Topics and frames: :mod:`freefloat.export.messages`. Message
times are nanoseconds from the plan's start. The folder is written next to the target under
a temporary name and renamed into place, so a failure leaves nothing behind; an existing
bag folder at the target is replaced.
"""

from __future__ import annotations

import os
import shutil
import sqlite3
import tempfile
from pathlib import Path
from typing import Any

from ..errors import FileError, InputError
from ..files import default_file_mode
from ..plans.format import Plan
from .messages import (
    END_EFFECTOR_RECORD,
    end_effector_topics,
    export_frames,
    messages,
    typestore,
)
from .trajectory import Trajectory

__all__ = ["write", "write_bag"]


def write(traj: Trajectory, path: str | Path, plan: Plan) -> Path:
    """The export registry's entry: :func:`write_bag` of the plan's trajectory."""
    return write_bag(traj, path, plan.robot.urdf, plan.robot.urdf_text)


def write_bag(traj: Trajectory, path: str | Path, urdf: str, urdf_text: str = "") -> Path:
    """Write the trajectory as a ROS 2 bag folder; return its absolute path.

    Raises:
        InputError: the target exists and is a file, or a folder that is not a bag.
    """
    from rosbags.rosbag2 import Writer

    target = Path(path).expanduser().resolve()
    if target.exists() and not (target.is_dir() and (target / "metadata.yaml").is_file()):
        raise InputError(f"{target} exists and is not a ROS 2 bag folder; choose another -o")
    target.parent.mkdir(parents=True, exist_ok=True)
    ts = typestore()
    frames = export_frames(urdf, urdf_text)
    holder = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
    try:
        bag = holder / target.name
        with Writer(bag, version=8) as writer:  # rosbag2 metadata 8: Iron and newer
            writer.set_custom_data(END_EFFECTOR_RECORD, end_effector_topics(traj))
            connections: dict[str, Any] = {}
            for msg in messages(traj, frames):
                if msg.topic not in connections:
                    connections[msg.topic] = writer.add_connection(
                        msg.topic, msg.msgtype, typestore=ts
                    )
                writer.write(
                    connections[msg.topic],
                    msg.time_ns,
                    ts.serialize_cdr(msg.message, msg.msgtype),
                )
        os.chmod(bag, 0o777 & ~_umask())
        for item in bag.iterdir():
            os.chmod(item, default_file_mode())
        if target.exists():
            shutil.rmtree(target)
        os.replace(bag, target)
    except (sqlite3.Error, OSError) as exc:  # a full disk, say: nothing of the bag is left
        raise FileError(f"cannot write the bag {target}: {exc}", str(target)) from None
    finally:
        shutil.rmtree(holder, ignore_errors=True)
    return target


def _umask() -> int:
    current = os.umask(0)
    os.umask(current)
    return current
