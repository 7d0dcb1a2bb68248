"""ROS 2 messages of a trajectory, built with the pure-Python ``rosbags`` type store.

No ROS installation is needed: message classes, CDR serialisation and the message
definitions (for MCAP schemas) come from ``rosbags``' built-in ROS 2 Humble type store.

Topics (times relative to the plan's start, which is stamped 0 s):

- ``/joint_trajectory``: ``trajectory_msgs/msg/JointTrajectory``, once at t = 0, every
  sample as a point (positions, velocities, accelerations, effort, ``time_from_start``);
- ``/joint_states``: ``sensor_msgs/msg/JointState`` per sample (position rad or m, velocity
  rad/s or m/s, effort N m or N);
- ``/tf``: ``tf2_msgs/msg/TFMessage`` per sample, the base pose: parent frame ``world``
  (inertial, origin at the system centre of mass; ``freefloat_world`` when the robot has a
  link named ``world``), child frame the URDF's root link (m);
- ``/end_effector``: ``geometry_msgs/msg/PointStamped`` per sample, in that inertial frame (m);
  further end effectors of the robot on ``/end_effector_2``, ``/end_effector_3``... in the
  plan's end-effector order. Which frame each topic follows is recorded in the file
  (:func:`end_effector_topics`: a bag's custom data, an MCAP metadata record, both named
  :data:`END_EFFECTOR_RECORD`), since a point's header names the frame it is expressed in.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ViewerError
from .trajectory import Trajectory

__all__ = [
    "END_EFFECTOR",
    "END_EFFECTOR_RECORD",
    "JOINT_STATES",
    "JOINT_TRAJECTORY",
    "TF",
    "WORLD_FRAME",
    "Frames",
    "Message",
    "end_effector_topic",
    "end_effector_topics",
    "export_frames",
    "messages",
    "typestore",
]

WORLD_FRAME = "world"
JOINT_TRAJECTORY = ("/joint_trajectory", "trajectory_msgs/msg/JointTrajectory")
JOINT_STATES = ("/joint_states", "sensor_msgs/msg/JointState")
TF = ("/tf", "tf2_msgs/msg/TFMessage")
END_EFFECTOR = ("/end_effector", "geometry_msgs/msg/PointStamped")
#: Every topic with its message type, in writing order.
TOPICS = (JOINT_TRAJECTORY, JOINT_STATES, TF, END_EFFECTOR)
#: The name under which an export records which frame each end-effector topic follows.
END_EFFECTOR_RECORD = "freefloat.end_effectors"


def end_effector_topic(number: int) -> str:
    """The topic of the plan's end effector ``number`` (0 first): ``/end_effector_2``..."""
    return END_EFFECTOR[0] + ("" if number == 0 else f"_{number + 1}")


def end_effector_topics(traj: Trajectory) -> str:
    """``{"topic": "frame", ...}`` as JSON: the frame each end-effector topic follows."""
    return json.dumps({end_effector_topic(k): f for k, f in enumerate(traj.end_effectors)})


def typestore() -> Any:
    """The ROS 2 (Humble) type store of ``rosbags``.

    Raises:
        ViewerError: rosbags is missing.
    """
    try:
        from rosbags.typesys import Stores, get_typestore
    except ImportError as exc:
        raise ViewerError(
            f"ROS 2 export needs rosbags ({exc}); install it with: pip install rosbags"
        ) from None
    return get_typestore(Stores.ROS2_HUMBLE)


@dataclass(frozen=True)
class Frames:
    """The frames an export names: the inertial one and the robot's root link.

    Attributes:
        inertial: the inertial frame, origin at the system centre of mass: :data:`WORLD_FRAME`,
            or when the robot has a link of that name, ``freefloat_world`` (a frame that is
            its own parent is refused by tf2).
        root: the URDF's root link (the spacecraft), the child of the base pose.
    """

    inertial: str
    root: str


def export_frames(urdf: str, text: str = "") -> Frames:
    """The frames of an export of the robot (root link ``base`` if the URDF cannot be read).

    Read from ``text`` (a plan's copy of its URDF) when given, else from the file ``urdf``.
    """
    from ..robot.urdf_checks import check_urdf_xml

    try:
        parsed = check_urdf_xml(text or Path(urdf).read_text(encoding="utf-8"))
    except Exception:
        return Frames(WORLD_FRAME, "base")
    inertial = WORLD_FRAME
    while inertial in parsed.links:
        inertial = "freefloat_" + inertial
    return Frames(inertial, parsed.root_link)


@dataclass(frozen=True)
class Message:
    """One message to write: topic, ROS type name, time (ns from the start) and the object."""

    topic: str
    msgtype: str
    time_ns: int
    message: Any


def _ns(t: float) -> int:
    return round(float(t) * 1e9)


def messages(traj: Trajectory, frames: Frames) -> Iterator[Message]:
    """Every message of the export in time order (the trajectory first)."""
    types = typestore().types
    yield Message(*JOINT_TRAJECTORY, 0, _trajectory(traj, types, frames.inertial))
    for k in range(len(traj.t)):
        yield from _instant(traj, k, frames, types)


def _stamp(ns: int, types: Any) -> Any:
    """``builtin_interfaces/msg/Time`` of ``ns`` nanoseconds."""
    return types["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def _header(ns: int, types: Any, frame: str = "") -> Any:
    """``std_msgs/msg/Header`` stamped ``ns`` nanoseconds, in ``frame``."""
    return types["std_msgs/msg/Header"](stamp=_stamp(ns, types), frame_id=frame)


def _trajectory(traj: Trajectory, types: Any, inertial: str) -> Any:
    """The ``trajectory_msgs/msg/JointTrajectory`` of every sample (SI units, rad)."""
    f64 = np.float64
    point = types["trajectory_msgs/msg/JointTrajectoryPoint"]
    duration = types["builtin_interfaces/msg/Duration"]
    points = [
        point(
            positions=traj.q[k].astype(f64),
            velocities=traj.qd[k].astype(f64),
            accelerations=traj.qdd[k].astype(f64),
            effort=traj.tau[k].astype(f64),
            time_from_start=duration(sec=_ns(t) // 1_000_000_000, nanosec=_ns(t) % 1_000_000_000),
        )
        for k, t in enumerate(traj.t)
    ]
    return types[JOINT_TRAJECTORY[1]](
        header=_header(0, types, inertial), joint_names=list(traj.joints), points=points
    )


def _instant(traj: Trajectory, k: int, frames: Frames, types: Any) -> Iterator[Message]:
    """Sample ``k``'s joint state, base pose and end-effector points."""
    f64, ns = np.float64, _ns(traj.t[k])
    yield Message(
        *JOINT_STATES,
        ns,
        types[JOINT_STATES[1]](
            header=_header(ns, types),
            name=list(traj.joints),
            position=traj.q[k].astype(f64),
            velocity=traj.qd[k].astype(f64),
            effort=traj.tau[k].astype(f64),
        ),
    )
    x, y, z = (float(v) for v in traj.base_position[k])
    qx, qy, qz, qw = (float(v) for v in traj.base_quaternion_xyzw[k])
    transform = types["geometry_msgs/msg/Transform"](
        translation=types["geometry_msgs/msg/Vector3"](x=x, y=y, z=z),
        rotation=types["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw),
    )
    stamped = types["geometry_msgs/msg/TransformStamped"](
        header=_header(ns, types, frames.inertial), child_frame_id=frames.root, transform=transform
    )
    yield Message(*TF, ns, types[TF[1]](transforms=[stamped]))
    paths = traj.end_effector_paths[1:]
    for number, point in enumerate([traj.end_effector_position[k], *(p[k] for p in paths)]):
        ex, ey, ez = (float(v) for v in point)
        topic = end_effector_topic(number)
        position = types["geometry_msgs/msg/Point"](x=ex, y=ey, z=ez)
        yield Message(
            topic,
            END_EFFECTOR[1],
            ns,
            types[END_EFFECTOR[1]](header=_header(ns, types, frames.inertial), point=position),
        )
