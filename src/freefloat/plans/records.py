"""The plan's records of the motion: robot, base attitude, samples, solver report, request.

Plain dataclasses, one per section of a plan file (:mod:`freefloat.plans.format` gathers them
into a :class:`~freefloat.plans.format.Plan`; :mod:`freefloat.plans.io` reads and writes them).
Units: seconds, radians (metres for prismatic joints and positions); Euler angles, marked
``_deg``, in degrees. Positions are in the inertial frame whose origin is the system centre of
mass (docs/method.md section 10).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "SAMPLE_ARRAYS",
    "BaseReport",
    "Feasibility",
    "PathQuality",
    "Request",
    "RobotRef",
    "Samples",
    "SolutionRecord",
    "SolverReport",
    "sha256_hex",
]


@dataclass(frozen=True)
class RobotRef:
    """The robot a plan is for.

    Attributes:
        urdf: the URDF's path (absolute, or relative to the plan file's folder).
        joints: joint names, in order.
        end_effector: the (first) end-effector frame.
        joint_kinds: ``revolute``, ``continuous`` or ``prismatic`` per joint.
        end_effectors: every end-effector frame, the first being ``end_effector`` (format 4; a
            file of an older format has its one end effector there).
        urdf_text: the URDF the plan was made with (empty in files before format 4).
        urdf_sha256: SHA-256 of ``urdf_text`` (UTF-8), hexadecimal (empty before format 4).
    """

    urdf: str
    joints: list[str]
    end_effector: str
    joint_kinds: list[str] = field(default_factory=list)
    end_effectors: list[str] = field(default_factory=list)
    urdf_text: str = ""
    urdf_sha256: str = ""

    @property
    def frames(self) -> list[str]:
        """Every end-effector frame (``end_effectors``, or ``[end_effector]`` when empty)."""
        return list(self.end_effectors) or [self.end_effector]


def sha256_hex(text: str) -> str:
    """The SHA-256 of ``text`` encoded as UTF-8, in hexadecimal."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


@dataclass(frozen=True)
class BaseReport:
    """Base attitude at start, wanted and reached (quaternions xyzw; ZYX Euler in deg)."""

    start_quaternion_xyzw: list[float]
    target_quaternion_xyzw: list[float]
    achieved_quaternion_xyzw: list[float]
    start_zyx_deg: list[float]
    target_zyx_deg: list[float]
    achieved_zyx_deg: list[float]
    attitude_error_rad: float


@dataclass(frozen=True)
class Feasibility:
    """Planar bounds check: the reachable yaw-change interval and the request (deg)."""

    planar: bool
    yaw_change_bounds_deg: list[float] | None
    requested_yaw_change_deg: float | None


@dataclass(frozen=True, eq=False)
class Samples:
    """The plan sampled in time; each field is a NumPy array with one row per sample.

    ``t`` (s, shape (K,)); ``q`` (rad or m), ``qd`` (per s), ``qdd`` (per s^2), shape (K, N);
    ``base_position`` (m, (K, 3)), ``base_quaternion_xyzw`` ((K, 4)), ``base_zyx_deg`` (deg,
    (K, 3)), ``base_angular_velocity`` (rad/s, base frame, (K, 3)), ``end_effector_position``
    (m, (K, 3), the first end effector), ``tau`` joint torques (N m, or N for prismatic joints,
    (K, N)), ``end_effector_paths`` every end effector's positions (m, (K, 3)) by frame name
    (format 4). Lists given to the constructor (a plan file's) are turned into float arrays; two
    records are equal when every array is.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    base_position: np.ndarray
    base_quaternion_xyzw: np.ndarray
    base_zyx_deg: np.ndarray
    end_effector_position: np.ndarray
    base_angular_velocity: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    tau: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    end_effector_paths: dict[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in SAMPLE_ARRAYS:
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float))
        paths = {str(k): np.asarray(v, dtype=float) for k, v in self.end_effector_paths.items()}
        object.__setattr__(self, "end_effector_paths", paths)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Samples):
            return NotImplemented
        return (
            all(np.array_equal(getattr(self, name), getattr(other, name)) for name in SAMPLE_ARRAYS)
            and self.end_effector_paths.keys() == other.end_effector_paths.keys()
            and all(
                np.array_equal(v, other.end_effector_paths[k])
                for k, v in self.end_effector_paths.items()
            )
        )

    __hash__ = None  # type: ignore[assignment]  # arrays: not hashable

    def path_of(self, frame: str) -> np.ndarray:
        """Positions (m, (K, 3)) of end effector ``frame`` (the first one's in an older file)."""
        if frame in self.end_effector_paths:
            return self.end_effector_paths[frame]
        if not self.end_effector_paths:
            return self.end_effector_position
        raise KeyError(f"no path of end effector {frame!r}; {', '.join(self.end_effector_paths)}")


#: The fields of :class:`Samples` that are arrays, in file order.
SAMPLE_ARRAYS = (
    "t",
    "q",
    "qd",
    "qdd",
    "base_position",
    "base_quaternion_xyzw",
    "base_zyx_deg",
    "end_effector_position",
    "base_angular_velocity",
    "tau",
)


@dataclass(frozen=True)
class SolutionRecord:
    """One root of the attitude equations found by the solver.

    Attributes:
        free_parameters: per joint, the coefficients ``beta`` in the plan's basis (rad or m;
            before format 4: the coefficients of ``t^6`` and up, rad/s^k or m/s^k).
        residual_rad: norm of the attitude residual there (rad).
        path_length: summed joint travel along the path (rad, plus m for prismatic joints).
    """

    free_parameters: dict[str, list[float]]
    residual_rad: float
    path_length: float


@dataclass(frozen=True)
class SolverReport:
    """How the free coefficients were found.

    ``solutions`` lists every root found (the chosen one first) with its free parameters
    (in the plan's basis, per joint), residual (rad) and summed joint travel (rad or m);
    ``freedom`` the free coefficients per joint the planner used; ``full_turns`` the whole turns
    added to continuous joints' goals; ``tried`` every attempt in order. Stage times (s, wall
    clock; 0 when not measured, as in files written before they were recorded): ``solve_time_s``
    the whole search, ``sample_time_s`` sampling the solution with its torques,
    ``verify_time_s`` the independent checks.
    """

    method: str
    iterations: int
    evaluations: int
    residual_rad: float
    wall_time_s: float
    solutions: list[SolutionRecord]
    integration_steps: int = 0
    integration_error_rad: float = 0.0
    strategy: str = ""
    freedom: dict[str, int] = field(default_factory=dict)
    full_turns: dict[str, int] = field(default_factory=dict)
    tried: list[str] = field(default_factory=list)
    solve_time_s: float = 0.0
    sample_time_s: float = 0.0
    verify_time_s: float = 0.0


@dataclass(frozen=True)
class Request:
    """What was asked: joint values at start and goal (rad or m), in joint order."""

    start_joints: list[float]
    goal_joints: list[float]


@dataclass(frozen=True)
class PathQuality:
    """How natural the joint paths are (format 4).

    Attributes:
        excursion_beyond_span: per joint, how far it goes beyond the interval between its
            start and goal values (deg; m for prismatic joints), from the exact extremes.
        largest_excursion: the largest of them (same unit).
        largest_joint: the joint where it occurs.
        deviation_rms_deg: ``sqrt(int_0^1 |q(s) - q_quintic(s)|^2 ds)`` in deg (metres of
            prismatic joints counted as radians): the RMS over normalised time of the
            joint-space distance from the quintic path; equals ``sqrt(|beta|^2)``.
    """

    excursion_beyond_span: dict[str, float] = field(default_factory=dict)
    largest_excursion: float = 0.0
    largest_joint: str = ""
    deviation_rms_deg: float = 0.0
