"""The plan file: typed records and their JSON form (``freefloat.plan/3``).

This module is long because it holds every record of the file format and its reading and
writing in one place (the format is one concept; splitting it would scatter the schema).

This module is the format only: dataclasses for every section of a plan, reading and writing
them, and the schema version. Planning a scenario into a plan lives in
:mod:`freefloat.pipeline`; checking a plan lives in :mod:`freefloat.verify`.

A plan file is written atomically (a temporary file renamed over the target), so a reader never
sees half a plan and a failure leaves nothing behind. Units: seconds, radians (metres for
prismatic joints and positions); Euler angles, marked ``_deg``, in degrees. Positions are in
the inertial frame whose origin is the system centre of mass (docs/method.md section 10).

Schema versions: ``freefloat.plan/3`` (this one) adds the ``objective`` record (what the path
minimises, its value and the freedom levels tried) and, for robots with URDF effort limits,
the ``joint_effort_limits`` check. ``freefloat.plan/2`` files still load and keep their format:
they were minimum-norm plans (no objective record) that promised no effort limits, and
``freefloat verify`` holds them to what they promised. ``freefloat.plan/2`` stores the
verification as a list of typed checks, each with its value, tolerance, unit and the check's
own numerical error estimate. ``freefloat.plan/1`` files (freefloat 0.1) still load: their
path, samples and solver report are read as they are and their verification is dropped
(``Verification.checks`` empty, not passed), so ``freefloat verify`` recomputes it.
"""

from __future__ import annotations

import copy
import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import PlanFileError, excerpt
from ..files import atomic_write_text
from .limits import MAX_PLAN_BYTES, check_plan_file_kind, check_plan_values

__all__ = [
    "FORMAT",
    "FORMAT_2",
    "READABLE_FORMATS",
    "BaseReport",
    "Check",
    "Feasibility",
    "ObstacleRecord",
    "Plan",
    "Request",
    "RobotRef",
    "SafetyReport",
    "Samples",
    "SolutionRecord",
    "SolverReport",
    "Verification",
    "read_plan_json",
]

#: Format tag of plan files written by this version.
FORMAT = "freefloat.plan/3"
#: The format before objectives and effort limits (still read, and kept when re-written).
FORMAT_2 = "freefloat.plan/2"

#: Format tags this version reads (older ones are converted on load).
READABLE_FORMATS = ("freefloat.plan/1", FORMAT_2, FORMAT)


@dataclass(frozen=True)
class RobotRef:
    """The robot a plan is for: URDF path, joint names in order, end-effector frame."""

    urdf: str
    joints: list[str]
    end_effector: str
    joint_kinds: list[str] = field(default_factory=list)


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
    (m, (K, 3)), ``tau`` joint torques (N m, or N for prismatic joints, (K, N)). Lists given
    to the constructor (a plan file's) are turned into float arrays; two records are equal when
    every array is.
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

    def __post_init__(self) -> None:
        for name in _SAMPLE_FIELDS:
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Samples):
            return NotImplemented
        return all(
            np.array_equal(getattr(self, name), getattr(other, name)) for name in _SAMPLE_FIELDS
        )

    __hash__ = None  # type: ignore[assignment]  # arrays: not hashable

    def to_dict(self) -> dict[str, list[Any]]:
        """The samples as the plan file's lists (JSON-ready)."""
        return {name: getattr(self, name).tolist() for name in _SAMPLE_FIELDS}


#: The fields of :class:`Samples`, in file order.
_SAMPLE_FIELDS = (
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
        free_parameters: per joint, the coefficients of ``t^6`` and up (rad/s^k or m/s^k).
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
    (``t^6`` and up, per joint), residual (rad) and summed joint travel (rad or m);
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
class Check:
    """One independent check of a plan.

    Attributes:
        name: the check's name (``momentum``, ``replay_attitude``, ``joint_position_limits``...).
        value: what was measured (in ``unit``).
        tolerance: the largest value the physics allows (in ``unit``).
        unit: unit of ``value``, ``tolerance`` and ``error_estimate`` (``rad``, ``m``,
            ``kg m^2/s``, ``1`` for relative figures...).
        error_estimate: the check's own numerical error (same unit): a plan is judged against
            ``tolerance + error_estimate``, so a coarse checker never refuses a valid plan.
        detail: where the worst value occurs (a joint, a time), for the reader.
    """

    name: str
    value: float
    tolerance: float
    unit: str
    error_estimate: float = 0.0
    detail: str = ""

    @property
    def passed(self) -> bool:
        """Whether ``value <= tolerance + error_estimate`` (NaN never passes)."""
        return math.isfinite(self.value) and self.value <= self.tolerance + self.error_estimate


@dataclass(frozen=True)
class Verification:
    """Results of the independent checks of a plan; ``passed`` only if every check holds."""

    checks: tuple[Check, ...] = ()

    @property
    def passed(self) -> bool:
        """True when there are checks and every one passed."""
        return bool(self.checks) and all(c.passed for c in self.checks)

    @property
    def failures(self) -> list[str]:
        """Names of the checks that failed."""
        return [c.name for c in self.checks if not c.passed]

    def __getitem__(self, name: str) -> Check:
        for check in self.checks:
            if check.name == name:
                return check
        raise KeyError(f"no check {name!r}; checks: {', '.join(c.name for c in self.checks)}")

    def __contains__(self, name: object) -> bool:
        return any(c.name == name for c in self.checks)

    def to_dict(self) -> dict[str, Any]:
        """The plan-file ``verification`` section."""
        return {
            "passed": self.passed,
            "checks": [{**asdict(c), "passed": c.passed} for c in self.checks],
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Verification:
        """Read the plan-file ``verification`` section (the ``passed`` flags are recomputed)."""
        checks = []
        for item in data.get("checks", []):
            fields = {k: v for k, v in item.items() if k != "passed"}
            checks.append(
                Check(
                    name=str(fields["name"]),
                    value=float(fields["value"]),
                    tolerance=float(fields["tolerance"]),
                    unit=str(fields["unit"]),
                    error_estimate=float(fields.get("error_estimate", 0.0)),
                    detail=str(fields.get("detail", "")),
                )
            )
        return cls(tuple(checks))


@dataclass(frozen=True)
class Request:
    """What was asked: joint values at start and goal (rad or m), in joint order."""

    start_joints: list[float]
    goal_joints: list[float]


@dataclass(frozen=True)
class ObstacleRecord:
    """A keep-out object fixed to the spacecraft (shape sizes and position in m, rpy in rad)."""

    name: str
    shape: str
    size: list[float]
    xyz: list[float]
    rpy: list[float]


@dataclass(frozen=True)
class SafetyReport:
    """What the plan was kept clear of.

    Attributes:
        checked: whether clearance was a constraint (and so a verification check).
        margin_m: required clearance between checked bodies (m).
        srdf: the SRDF whose disabled pairs were not checked, if any.
        obstacles: keep-out objects fixed to the spacecraft.
    """

    checked: bool = False
    margin_m: float = 0.01
    srdf: str | None = None
    obstacles: list[ObstacleRecord] = field(default_factory=list)


@dataclass(frozen=True)
class ObjectiveLevel:
    """One freedom level the objective was minimised with.

    Attributes:
        freedom: free coefficients per joint.
        value: the objective at that level's best root (the objective's unit).
        iterations: SLSQP iterations spent.
        note: why the level kept its starting path, when it did.
    """

    freedom: dict[str, int]
    value: float
    iterations: int
    note: str = ""


@dataclass(frozen=True)
class ObjectiveReport:
    """Which of the paths that reach the goal the plan is, and how good it is.

    Attributes:
        name: the objective (``min_norm``, ``min_effort``, ``min_acceleration``, ``min_length``).
        unit: unit of the values.
        value: the objective along the plan, at its duration.
        error_estimate: numerical error of ``value`` (0 when exact).
        quadrature_nodes: Gauss-Legendre nodes of ``value`` (0 when exact).
        duration_power: ``p`` in ``value(T) = value(1 s) T^-p``: the value at another
            duration of the same path.
        start_value: the objective along the minimum-norm path the search found first.
        levels: the freedom levels tried, in order.
    """

    name: str = "min_norm"
    unit: str = "rad^2"
    value: float | None = None
    error_estimate: float = 0.0
    quadrature_nodes: int = 0
    duration_power: int = 0
    start_value: float | None = None
    levels: list[ObjectiveLevel] = field(default_factory=list)


@dataclass(frozen=True)
class Plan:
    """A verified point-to-point motion of a free-floating space manipulator."""

    robot: RobotRef
    duration: float
    coefficients: dict[str, list[float]]
    free_parameters: dict[str, list[float]]
    base: BaseReport
    feasibility: Feasibility
    samples: Samples
    solver: SolverReport
    request: Request
    verification: Verification = field(default_factory=Verification)
    safety: SafetyReport = field(default_factory=SafetyReport)
    objective: ObjectiveReport = field(default_factory=ObjectiveReport)
    format: str = FORMAT

    # -- evaluation -------------------------------------------------------------------------

    def joint_positions(self, t: float | np.ndarray) -> np.ndarray:
        """Joint values (rad or m) at times ``t`` (s) from the plan's polynomials."""
        t = np.asarray(t, dtype=float)
        poly = np.polynomial.polynomial
        return np.stack(
            [poly.polyval(t, self.coefficients[name]) for name in self.robot.joints], axis=-1
        )

    # -- file -------------------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """The plan as the JSON-ready dictionary of the file format (a deep copy)."""
        return copy.deepcopy(
            {
                "format": self.format,
                "robot": asdict(self.robot),
                "duration": self.duration,
                "path": {"family": "polynomial", "coefficients": self.coefficients},
                "free_parameters": self.free_parameters,
                "base": asdict(self.base),
                "feasibility": asdict(self.feasibility),
                "samples": self.samples.to_dict(),
                "solver": asdict(self.solver),
                "request": asdict(self.request),
                "verification": self.verification.to_dict(),
                "safety": asdict(self.safety),
                **({} if self.format == FORMAT_2 else {"objective": asdict(self.objective)}),
            }
        )

    def to_json(self) -> str:
        """The plan file's text (JSON, no NaN)."""
        return json.dumps(self.to_dict(), indent=1, allow_nan=False)

    def save(self, path: str | Path) -> Path:
        """Write the plan to ``path`` atomically; return the absolute path."""
        return atomic_write_text(path, self.to_json())

    @classmethod
    def load(cls, path: str | Path) -> Plan:
        """Read a plan file.

        Raises:
            PlanFileError: unreadable, not JSON, another format version, or missing keys.
        """
        path = Path(path).expanduser()
        return cls.from_dict(read_plan_json(path), str(path))

    @classmethod
    def from_dict(cls, data: Any, where: str = "plan") -> Plan:
        """Build a plan from its file dictionary, checking the format and the keys."""
        if not isinstance(data, Mapping):
            raise PlanFileError(f"{where}: not a plan file (top level is not an object)")
        fmt = data.get("format")
        if fmt not in READABLE_FORMATS:
            raise PlanFileError(
                f"{where}: plan format {excerpt(fmt)} is not supported; this freefloat reads "
                + " and ".join(repr(f) for f in READABLE_FORMATS)
            )
        check_plan_values(data, where)
        try:
            verification = (
                Verification()  # format 1: its untyped checks are recomputed by verify
                if fmt == "freefloat.plan/1"
                else Verification.from_dict(data["verification"])
            )
            return cls(
                robot=RobotRef(**data["robot"]),
                duration=float(data["duration"]),
                coefficients={k: list(v) for k, v in data["path"]["coefficients"].items()},
                free_parameters={k: list(v) for k, v in data["free_parameters"].items()},
                base=BaseReport(**data["base"]),
                feasibility=Feasibility(**data["feasibility"]),
                samples=Samples(**data["samples"]),
                solver=SolverReport(
                    **{
                        **data["solver"],
                        "solutions": [SolutionRecord(**s) for s in data["solver"]["solutions"]],
                    }
                ),
                request=Request(
                    start_joints=list(data["request"]["start_joints"]),
                    goal_joints=list(data["request"]["goal_joints"]),
                ),
                verification=verification,
                safety=_safety(data.get("safety")),
                objective=_objective(data.get("objective")),
                format=FORMAT_2 if fmt == FORMAT_2 else FORMAT,
            )
        except (KeyError, TypeError, AttributeError, ValueError) as exc:
            raise PlanFileError(f"{where}: corrupt plan file (bad or missing {exc})") from None


def _safety(data: Any) -> SafetyReport:
    """The ``safety`` section (absent in files written before it existed: not checked)."""
    if data is None:
        return SafetyReport()
    return SafetyReport(
        checked=bool(data["checked"]),
        margin_m=float(data["margin_m"]),
        srdf=None if data.get("srdf") is None else str(data["srdf"]),
        obstacles=[ObstacleRecord(**o) for o in data.get("obstacles", [])],
    )


def _objective(data: Any) -> ObjectiveReport:
    """The ``objective`` section (absent in files written before it existed: minimum norm)."""
    if data is None:
        return ObjectiveReport()
    return ObjectiveReport(
        **{
            **data,
            "levels": [ObjectiveLevel(**level) for level in data.get("levels", [])],
        }
    )


def read_plan_json(path: str | Path) -> Any:
    """The parsed JSON of a plan file.

    The path must name a regular file of at most :data:`~freefloat.plans.limits.MAX_PLAN_BYTES`
    (checked before reading, so a FIFO or ``/dev/zero`` is refused, not read).

    Raises:
        PlanFileError: missing, not a regular file, too large, unreadable, not JSON, or nested
            too deeply to parse.
    """
    path = Path(path).expanduser()
    check_plan_file_kind(path)
    try:
        with open(path, "rb") as handle:
            raw = handle.read(MAX_PLAN_BYTES + 1)
        if len(raw) > MAX_PLAN_BYTES:
            raise PlanFileError(
                f"{path}: larger than the {MAX_PLAN_BYTES // 2**20} MiB a plan file may have"
            )
        return json.loads(raw.decode("utf-8"))
    except FileNotFoundError:
        raise PlanFileError(f"plan file not found: {path}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PlanFileError(f"cannot read plan file {path}: {exc}") from None
    except json.JSONDecodeError as exc:
        raise PlanFileError(f"{path}: not a plan file, corrupt JSON ({exc})") from None
    except RecursionError:
        raise PlanFileError(f"{path}: not a plan file, JSON nested too deeply") from None
    except ValueError as exc:  # an integer of thousands of digits
        raise PlanFileError(f"{path}: not a plan file ({excerpt(str(exc), 80)})") from None
