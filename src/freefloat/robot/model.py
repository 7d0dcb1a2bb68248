"""Load a spacecraft-plus-arm URDF as a free-floating multibody system.

The URDF's root link is the spacecraft (the *base*); gravity is zero (free flight). Pinocchio
adds a free-flyer joint above it, so the configuration is ``[base position (m), base
quaternion xyzw, joint entries]`` and the velocity ``[base linear (m/s), base angular (rad/s),
both in the base frame; joint rates]``.
Fixed joints are merged into their parent body by Pinocchio's URDF parser.

The public API speaks of one number per movable joint: an angle in rad for ``revolute`` and
``continuous`` joints (Pinocchio stores a continuous joint as ``(cos, sin)``), a displacement
in m for ``prismatic`` joints.
"""

from __future__ import annotations

import importlib.metadata
import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ModelError, UnknownNameError
from ..files import absolute_path, read_text_file
from .urdf_checks import check_masses, check_urdf_xml, parser_messages

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

#: Pinocchio joint model short names, by the kind of joint freefloat exposes.
_KINDS = {
    "JointModelRX": "revolute",
    "JointModelRY": "revolute",
    "JointModelRZ": "revolute",
    "JointModelRevoluteUnaligned": "revolute",
    "JointModelRUBX": "continuous",
    "JointModelRUBY": "continuous",
    "JointModelRUBZ": "continuous",
    "JointModelRevoluteUnboundedUnaligned": "continuous",
    "JointModelPX": "prismatic",
    "JointModelPY": "prismatic",
    "JointModelPZ": "prismatic",
    "JointModelPrismaticUnaligned": "prismatic",
}


@dataclass(frozen=True)
class Joint:
    """One movable joint, as the API sees it.

    Attributes:
        name: URDF joint name.
        kind: ``"revolute"``, ``"continuous"`` or ``"prismatic"``.
        index: Pinocchio joint index.
        idx_q: first index of the joint in Pinocchio's configuration vector.
        idx_v: index of the joint in Pinocchio's velocity vector.
        lower: lower position limit (rad or m; ``-inf`` for a continuous joint).
        upper: upper position limit (rad or m; ``+inf`` for a continuous joint).
        velocity_limit: URDF velocity limit (rad/s or m/s; ``inf`` when not given).
        effort_limit: URDF effort limit (N m or N; ``inf`` when not given).
    """

    name: str
    kind: str
    index: int
    idx_q: int
    idx_v: int
    lower: float
    upper: float
    velocity_limit: float
    effort_limit: float

    @property
    def unit(self) -> str:
        """Unit of the joint's position: ``"rad"`` or ``"m"``."""
        return "m" if self.kind == "prismatic" else "rad"

    @property
    def effort_unit(self) -> str:
        """Unit of the joint's effort: ``"N m"`` (torque) or ``"N"`` (force, prismatic)."""
        return "N" if self.kind == "prismatic" else "N m"

    @property
    def angular(self) -> bool:
        """True for revolute and continuous joints (positions in rad)."""
        return self.kind != "prismatic"


@dataclass(eq=False)
class Robot:
    """A free-floating spacecraft-plus-arm model.

    Attributes:
        urdf: absolute path of the URDF file.
        name: the URDF robot name.
        model: Pinocchio model with a free-flyer root joint.
        joints: the movable joints, in Pinocchio's (depth-first) order.
        base_link: name of the URDF root link (the spacecraft body).
        end_effector: name of the end-effector frame.
        package_dirs: folders searched for ``package://`` mesh references.
    """

    urdf: Path
    name: str
    model: pin.Model
    joints: tuple[Joint, ...]
    base_link: str
    end_effector: str
    package_dirs: tuple[Path, ...] = ()
    link_names: tuple[str, ...] = field(default_factory=tuple)

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

    def joint(self, name: str) -> Joint:
        """The joint called ``name``; :class:`UnknownNameError` (listing the valid ones) if none."""
        for joint in self.joints:
            if joint.name == name:
                return joint
        raise UnknownNameError("joint", name, self.joint_names)

    def vector(self, values: Mapping[str, float], what: str = "joint values") -> np.ndarray:
        """Order a ``{joint name: value}`` mapping into an N-vector (rad or m).

        Every joint must be given once; unknown names and missing joints raise errors that list
        the valid names.
        """
        for name in values:
            if name not in self.joint_names:
                raise UnknownNameError("joint", name, self.joint_names)
        missing = [j.name for j in self.joints if j.name not in values]
        if missing:
            raise ModelError(
                f"{what}: no value for joint(s) {', '.join(missing)}; every joint needs one "
                f"(joints: {', '.join(self.joint_names)})"
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
                q[joint.idx_q] = math.cos(value)
                q[joint.idx_q + 1] = math.sin(value)
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


def example_robot_data_dir() -> Path | None:
    """The ``share`` folder holding ``example-robot-data`` (its package dir), if installed."""
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    share = Path(str(dist.locate_file("cmeel.prefix/share")))
    return share if (share / "example-robot-data").is_dir() else None


def robots_dir() -> Path:
    """Folder of the shipped robots and scenarios (installed package data or the checkout)."""
    installed = Path(__file__).resolve().parents[1] / "robots"
    if installed.is_dir():
        return installed
    checkout = Path(__file__).resolve().parents[3] / "robots"
    if checkout.is_dir():
        return checkout
    raise ModelError("the shipped robots folder is missing from this installation")


def shipped_robots() -> list[str]:
    """Names of the shipped robots (URDF files in :func:`robots_dir`)."""
    return sorted(p.stem for p in robots_dir().glob("*.urdf"))


def resolve_robot(name_or_path: str | Path, relative_to: Path | None = None) -> Path:
    """Resolve a shipped robot name or a URDF path to an absolute URDF path.

    A plain name without a suffix or separator (``"planar_2dof"``) is a shipped robot; anything
    else is a path, relative to ``relative_to`` (a folder) when not absolute.
    """
    text = str(name_or_path)
    if "/" not in text and "\\" not in text and not text.endswith(".urdf"):
        path = robots_dir() / f"{text}.urdf"
        if not path.is_file():
            raise UnknownNameError("robot", text, shipped_robots())
        return path
    path = Path(text).expanduser()
    if not path.is_absolute() and relative_to is not None:
        path = relative_to / path
    return absolute_path(path, "URDF", ModelError)


_TOOL_NAME = re.compile(r"tcp|end_?effector|eef|tool|(^|_)ee($|_)", re.IGNORECASE)


def _default_end_effector(model: pin.Model) -> str:
    """Name the body frame at the tip of the longest chain of movable joints.

    Among the bodies carried by the deepest joint, a frame named like a tool (``tcp``,
    ``end_effector``, ``eef``, ``tool``, ``ee``) wins; otherwise the latest in tree order. A
    captured payload's link (``captured_payload``) is what the end effector holds, never the
    end effector itself.
    """
    bodies = [
        (
            len(model.supports[frame.parentJoint]),
            bool(_TOOL_NAME.search(frame.name)),
            index,
            frame.name,
        )
        for index, frame in enumerate(model.frames)
        if frame.type == pin.FrameType.BODY and frame.name != "captured_payload"
    ]
    return max(bodies)[3]


def load_robot(
    urdf: str | Path,
    end_effector: str | None = None,
    package_dirs: Sequence[str | Path] = (),
    text: str | None = None,
) -> Robot:
    """Load a URDF as a free-floating system with a free-flyer root joint.

    Args:
        urdf: path of the URDF file; its root link is the spacecraft. With ``text`` the
            path names the robot (and its mesh folder) but is not read; it need not exist.
        end_effector: name of the end-effector frame (a link name); default: the tip of the
            longest chain of movable joints.
        package_dirs: folders for ``package://`` mesh references (the URDF's own folder and
            example-robot-data's share folder are always searched).
        text: the URDF's content, when it is not (yet) in a file.

    Raises:
        ModelError: unreadable or malformed file, closed loop, unsupported joint type, bad
            masses or inertias, or no movable joint.
        UnknownNameError: ``end_effector`` is not a frame of the robot.
    """
    path = absolute_path(urdf, "URDF", ModelError)
    if text is None:
        text = read_text_file(path, "URDF", MAX_URDF_BYTES, ModelError)
    try:
        root_link, links = check_urdf_xml(text)
    except ModelError as exc:
        raise ModelError(str(exc), urdf=str(path)) from None
    error: RuntimeError | ValueError | None
    with parser_messages() as messages:
        try:
            model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
        except (RuntimeError, ValueError) as exc:
            error = exc
        else:
            error = None
    if error is not None:
        said = next((m for m in messages if m.startswith("Error:")), "")
        said = f"; urdfdom: {said.removeprefix('Error:').strip()}" if said else ""
        raise ModelError(f"Pinocchio cannot parse it ({error}{said})", urdf=str(path)) from None

    model.gravity = pin.Motion.Zero()  # free flight: no gravity acts on the system
    joints = _joints(model, path)
    check_masses(model, root_link, path)

    frames = [f.name for f in model.frames if f.type == pin.FrameType.BODY]
    if end_effector is None:
        end_effector = _default_end_effector(model)
    elif end_effector not in frames:
        raise UnknownNameError("end-effector frame", end_effector, frames)

    share = example_robot_data_dir()
    dirs = (path.parent, *(Path(d).resolve() for d in package_dirs), *([share] if share else []))
    return Robot(
        urdf=path,
        name=ET.fromstring(text).get("name", path.stem),
        model=model,
        joints=tuple(joints),
        base_link=root_link,
        end_effector=end_effector,
        package_dirs=dirs,
        link_names=tuple(links),
    )


def _joints(model: pin.Model, path: Path) -> list[Joint]:
    """The movable joints of a free-flyer model, with their limits (rad or m, per s, N m or N).

    Raises:
        ModelError: a joint of unsupported type, inverted limits, or no movable joint.
    """
    joints = []
    for index in range(2, model.njoints):
        jm = model.joints[index]
        kind = _KINDS.get(jm.shortname())
        if kind is None:  # pragma: no cover - filtered by the XML check above
            raise ModelError(f"joint {model.names[index]!r} of unsupported type", urdf=str(path))
        lower, upper = -math.inf, math.inf
        if kind != "continuous":
            lower = float(model.lowerPositionLimit[jm.idx_q])
            upper = float(model.upperPositionLimit[jm.idx_q])
            if not lower < upper:
                raise ModelError(
                    f"joint {model.names[index]!r} has limits [{lower}, {upper}]; lower must "
                    "be below upper",
                    urdf=str(path),
                )
        vel = float(model.velocityLimit[jm.idx_v])
        eff = float(model.effortLimit[jm.idx_v])
        joints.append(
            Joint(
                name=model.names[index],
                kind=kind,
                index=index,
                idx_q=jm.idx_q,
                idx_v=jm.idx_v,
                lower=lower,
                upper=upper,
                velocity_limit=vel if vel > 0 else math.inf,
                effort_limit=eff if eff > 0 else math.inf,
            )
        )
    if not joints:
        raise ModelError(
            "no movable joint (revolute, continuous or prismatic); a manipulator needs at least "
            "one",
            urdf=str(path),
        )
    return joints
