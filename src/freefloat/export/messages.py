"""ROS 2 messages of a trajectory, built with the pure-Python ``rosbags`` type store.

No ROS installation is needed: message classes, CDR serialisation and the message
definitions (for MCAP schemas) come from ``rosbags``' built-in ROS 2 Humble type store.

Topics (times relative to the plan's start, which is stamped 0 s):

- ``/joint_trajectory``: ``trajectory_msgs/msg/JointTrajectory``, once at t = 0, every
  sample as a point (positions, velocities, accelerations, effort, ``time_from_start``);
- ``/joint_states``: ``sensor_msgs/msg/JointState`` per sample (position rad or m, velocity
  rad/s or m/s, effort N m or N);
- ``/tf``: ``tf2_msgs/msg/TFMessage`` per sample, the base pose: parent frame ``world``
  (inertial, origin at the system centre of mass), child frame the URDF's root link (m);
- ``/end_effector``: ``geometry_msgs/msg/PointStamped`` per sample, in ``world`` (m);
  further end effectors of the robot on ``/end_effector_2``, ``/end_effector_3``... in the
  plan's end-effector order.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ViewerError
from .trajectory import Trajectory

__all__ = [
    "END_EFFECTOR",
    "JOINT_STATES",
    "JOINT_TRAJECTORY",
    "TF",
    "WORLD_FRAME",
    "Message",
    "messages",
    "root_link",
    "typestore",
]

WORLD_FRAME = "world"
JOINT_TRAJECTORY = ("/joint_trajectory", "trajectory_msgs/msg/JointTrajectory")
JOINT_STATES = ("/joint_states", "sensor_msgs/msg/JointState")
TF = ("/tf", "tf2_msgs/msg/TFMessage")
END_EFFECTOR = ("/end_effector", "geometry_msgs/msg/PointStamped")
#: Every topic with its message type, in writing order.
TOPICS = (JOINT_TRAJECTORY, JOINT_STATES, TF, END_EFFECTOR)


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


def root_link(urdf: str, text: str = "") -> str:
    """The URDF's root link (the spacecraft); ``base`` if the URDF cannot be read.

    Read from ``text`` (a plan's copy of its URDF) when given, else from the file ``urdf``.
    """
    from ..robot.urdf_checks import check_urdf_xml

    try:
        return check_urdf_xml(text or Path(urdf).read_text(encoding="utf-8")).root_link
    except Exception:
        return "base"


@dataclass(frozen=True)
class Message:
    """One message to write: topic, ROS type name, time (ns from the start) and the object."""

    topic: str
    msgtype: str
    time_ns: int
    message: Any


def _ns(t: float) -> int:
    return round(float(t) * 1e9)


def messages(traj: Trajectory, child_frame: str) -> Iterator[Message]:
    """Every message of the export in time order (the trajectory first)."""
    ts = typestore()
    types = ts.types
    Time = types["builtin_interfaces/msg/Time"]
    Duration = types["builtin_interfaces/msg/Duration"]
    Header = types["std_msgs/msg/Header"]

    def stamp(ns: int) -> Any:
        return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)

    def header(ns: int, frame: str = "") -> Any:
        return Header(stamp=stamp(ns), frame_id=frame)

    f64 = np.float64
    Point = types["trajectory_msgs/msg/JointTrajectoryPoint"]
    points = [
        Point(
            positions=traj.q[k].astype(f64),
            velocities=traj.qd[k].astype(f64),
            accelerations=traj.qdd[k].astype(f64),
            effort=traj.tau[k].astype(f64),
            time_from_start=Duration(sec=_ns(t) // 1_000_000_000, nanosec=_ns(t) % 1_000_000_000),
        )
        for k, t in enumerate(traj.t)
    ]
    yield Message(
        *JOINT_TRAJECTORY,
        0,
        types[JOINT_TRAJECTORY[1]](
            header=header(0, WORLD_FRAME), joint_names=list(traj.joints), points=points
        ),
    )
    JointState = types[JOINT_STATES[1]]
    TFMessage = types[TF[1]]
    TransformStamped = types["geometry_msgs/msg/TransformStamped"]
    Transform = types["geometry_msgs/msg/Transform"]
    Vector3 = types["geometry_msgs/msg/Vector3"]
    Quaternion = types["geometry_msgs/msg/Quaternion"]
    PointStamped = types[END_EFFECTOR[1]]
    GeoPoint = types["geometry_msgs/msg/Point"]
    for k, t in enumerate(traj.t):
        ns = _ns(t)
        yield Message(
            *JOINT_STATES,
            ns,
            JointState(
                header=header(ns),
                name=list(traj.joints),
                position=traj.q[k].astype(f64),
                velocity=traj.qd[k].astype(f64),
                effort=traj.tau[k].astype(f64),
            ),
        )
        x, y, z = (float(v) for v in traj.base_position[k])
        qx, qy, qz, qw = (float(v) for v in traj.base_quaternion_xyzw[k])
        yield Message(
            *TF,
            ns,
            TFMessage(
                transforms=[
                    TransformStamped(
                        header=header(ns, WORLD_FRAME),
                        child_frame_id=child_frame,
                        transform=Transform(
                            translation=Vector3(x=x, y=y, z=z),
                            rotation=Quaternion(x=qx, y=qy, z=qz, w=qw),
                        ),
                    )
                ]
            ),
        )
        paths = traj.end_effector_paths[1:]
        for number, point in enumerate([traj.end_effector_position[k], *(p[k] for p in paths)]):
            ex, ey, ez = (float(v) for v in point)
            topic = END_EFFECTOR[0] + ("" if number == 0 else f"_{number + 1}")
            yield Message(
                topic,
                END_EFFECTOR[1],
                ns,
                PointStamped(header=header(ns, WORLD_FRAME), point=GeoPoint(x=ex, y=ey, z=ez)),
            )
