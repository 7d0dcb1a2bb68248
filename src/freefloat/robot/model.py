"""Load a spacecraft-plus-arm URDF as a free-floating multibody system.

The URDF's root link is the spacecraft (the *base*); gravity is zero (free flight). Pinocchio
adds a free-flyer joint above it, so the configuration is ``[base position (m), base
quaternion xyzw, joint entries]`` and the velocity ``[base linear (m/s), base angular (rad/s),
both in the base frame; joint rates]``.
Fixed joints are merged into their parent body by Pinocchio's URDF parser.

The public API speaks of one number per movable joint: an angle in rad for ``revolute`` and
``continuous`` joints (Pinocchio stores a continuous joint as ``(cos, sin)``), a displacement
in m for ``prismatic`` joints.

The default end effector is chosen in :mod:`freefloat.robot.end_effectors`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ModelError, UnknownNameError
from ..files import absolute_path, read_text_file
from .locations import example_robot_data_dir, resolve_robot, robots_dir, shipped_robots
from .parsed_urdf import Joint, parsed_urdf

__all__ = [
    "MAX_URDF_BYTES",
    "Joint",
    "Robot",
    "example_robot_data_dir",
    "load_robot",
    "resolve_robot",
    "robots_dir",
    "shipped_robots",
]

#: Largest URDF file read (bytes); meshes are separate files, so a URDF is text of a few
#: hundred kilobytes at most (the composed Panda servicer: 20 kB).
MAX_URDF_BYTES = 50_000_000


@dataclass(eq=False)
class Robot:
    """A free-floating spacecraft-plus-arm model.

    Attributes:
        urdf: absolute path of the URDF file.
        name: the URDF robot name.
        model: Pinocchio model with a free-flyer root joint.
        joints: the movable joints, in Pinocchio's (depth-first) order.
        base_link: name of the URDF root link (the spacecraft body).
        end_effector: name of the (first) end-effector frame.
        package_dirs: folders searched for ``package://`` mesh references.
        link_names: every URDF link, in file order.
        end_effectors: every end-effector frame, the first being ``end_effector`` (a
            two-arm servicer names one per arm); default ``(end_effector,)``.
        urdf_text: the URDF text the robot was loaded from (what a plan carries).
    """

    urdf: Path
    name: str
    model: pin.Model
    joints: tuple[Joint, ...]
    base_link: str
    end_effector: str
    package_dirs: tuple[Path, ...] = ()
    link_names: tuple[str, ...] = field(default_factory=tuple)
    end_effectors: tuple[str, ...] = ()
    urdf_text: str = ""

    def __post_init__(self) -> None:
        if not self.end_effectors:
            self.end_effectors = (self.end_effector,)

    @property
    def n(self) -> int:
        """Number of movable joints N."""
        return len(self.joints)

    @property
    def joint_names(self) -> list[str]:
        """Movable joint names, in order."""
        return [j.name for j in self.joints]

    @property
    def total_mass(self) -> float:
        """Total mass of the system (kg)."""
        return float(sum(inertia.mass for inertia in self.model.inertias))

    @property
    def end_effector_frame(self) -> int:
        """Pinocchio frame index of the end effector."""
        return int(self.model.getFrameId(self.end_effector))

    @property
    def end_effector_frames(self) -> list[int]:
        """Pinocchio frame indices of every end effector, in :attr:`end_effectors` order."""
        return [int(self.model.getFrameId(name)) for name in self.end_effectors]

    def supporting_joints(self, frame: str) -> list[str]:
        """Names of the movable joints that move ``frame`` (its chain from the base), in order."""
        parent = self.model.frames[self.model.getFrameId(frame)].parentJoint
        support = set(self.model.supports[parent])
        return [j.name for j in self.joints if j.index in support]

    def joint(self, name: str, where: str = "") -> Joint:
        """The joint called ``name``; :class:`UnknownNameError` (listing the valid ones) if none.

        ``where``: the place the name was read (``"[path] extra"``), put before the message.
        """
        for joint in self.joints:
            if joint.name == name:
                return joint
        raise self._unknown_joint(name, where)

    def _unknown_joint(self, name: str, where: str = "") -> UnknownNameError:
        """The error for a name that is not a movable joint's (saying when it is a fixed one)."""
        model = self.model
        fixed = model.existFrame(name) and (
            model.frames[model.getFrameId(name)].type == pin.FrameType.FIXED_JOINT
        )
        why = "a fixed joint in the URDF: it does not move" if fixed else ""
        return UnknownNameError("joint", name, self.joint_names, why, where)

    def vector(self, values: Mapping[str, float], what: str = "") -> np.ndarray:
        """Order a ``{joint name: value}`` mapping into an N-vector (rad or m).

        Every joint must be given once; unknown names and missing joints raise errors that list
        the valid names, after ``what`` (where the values were read, e.g. ``"[start] joints"``).
        """
        for name in values:
            if name not in self.joint_names:
                raise self._unknown_joint(name, what)
        missing = [j.name for j in self.joints if j.name not in values]
        if missing:
            raise ModelError(
                f"{what or 'joint values'}: no value for joint(s) {', '.join(missing)}; every "
                f"joint needs one (joints: {', '.join(self.joint_names)})"
            )
        return np.array([float(values[j.name]) for j in self.joints])

    def configuration(
        self,
        joints: Sequence[float] | np.ndarray,
        base_position: Sequence[float] | np.ndarray | None = None,
        base_quaternion_xyzw: Sequence[float] | np.ndarray | None = None,
    ) -> np.ndarray:
        """Pinocchio configuration vector from joint values (rad or m) and the base pose.

        Args:
            joints: N joint values (rad or m).
            base_position: base origin in the inertial frame (m); default the origin.
            base_quaternion_xyzw: base attitude as a unit quaternion ``[x, y, z, w]``; default
                identity.
        """
        q = pin.neutral(self.model)
        if base_position is not None:
            q[0:3] = base_position
        if base_quaternion_xyzw is not None:
            q[3:7] = base_quaternion_xyzw
        self.write_joints(q, joints)
        return q

    def write_joints(self, q: np.ndarray, joints: Sequence[float] | np.ndarray) -> None:
        """Write N joint values (rad or m) into a Pinocchio configuration vector in place."""
        for joint, value in zip(self.joints, joints, strict=True):
            if joint.kind == "continuous":
                angle = math.nan if math.isinf(value) else value  # math.cos(inf) raises
                q[joint.idx_q] = math.cos(angle)
                q[joint.idx_q + 1] = math.sin(angle)
            else:
                q[joint.idx_q] = value

    def joint_values(self, q: np.ndarray) -> np.ndarray:
        """N joint values (rad or m) from a Pinocchio configuration vector."""
        out = np.empty(self.n)
        for i, joint in enumerate(self.joints):
            if joint.kind == "continuous":
                out[i] = math.atan2(q[joint.idx_q + 1], q[joint.idx_q])
            else:
                out[i] = q[joint.idx_q]
        return out


def load_robot(
    urdf: str | Path,
    end_effector: str | Sequence[str] | None = None,
    package_dirs: Sequence[str | Path] = (),
    text: str | None = None,
) -> Robot:
    """Load a URDF as a free-floating system with a free-flyer root joint.

    Args:
        urdf: path of the URDF file; its root link is the spacecraft. With ``text`` the
            path names the robot (and its mesh folder) but is not read; it need not exist.
        end_effector: name of the end-effector frame (a link name), or several names (the
            first is the main one); default: the tip of the longest chain of movable joints
            that is not a gripper finger (:func:`end_effector_candidates`).
        package_dirs: folders for ``package://`` mesh references (the URDF's own folder and
            example-robot-data's share folder are always searched).
        text: the URDF's content, when it is not (yet) in a file.

    Raises:
        ModelError: unreadable or malformed file, closed loop, unsupported joint type, bad
            masses or inertias, or no movable joint.
        UnknownNameError: ``end_effector`` is not a frame of the robot.
        AmbiguousEndEffectorError: no end effector named and several chains are longest.
    """
    path = absolute_path(urdf, "URDF", ModelError)
    if text is None:
        text = read_text_file(path, "URDF", MAX_URDF_BYTES, ModelError)
    parsed = parsed_urdf(text, path)
    if end_effector is None:
        names: tuple[str, ...] = (parsed.default_end_effector(path),)
    else:
        names = (end_effector,) if isinstance(end_effector, str) else tuple(end_effector)
    if not names or len(set(names)) != len(names):
        raise ModelError(f"end effectors must be distinct frame names, got {list(names)}")
    for name in names:
        if name not in parsed.frames:
            raise UnknownNameError("end-effector frame", name, list(parsed.frames))

    share = example_robot_data_dir()
    dirs = (path.parent, *(Path(d).resolve() for d in package_dirs), *([share] if share else []))
    return Robot(
        urdf=path,
        name=parsed.checked.name or path.stem,
        model=parsed.model.copy(),  # the kept model is never handed out
        joints=parsed.joints,
        base_link=parsed.checked.root_link,
        end_effector=names[0],
        package_dirs=dirs,
        link_names=parsed.checked.links,
        end_effectors=names,
        urdf_text=text,
    )
