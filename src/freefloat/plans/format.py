"""The plan file: typed records and their JSON form (``freefloat.plan/4``).

This module is the format only: dataclasses for every section of a plan, reading and writing
them, and the schema version. Planning a scenario into a plan lives in
:mod:`freefloat.pipeline`; checking a plan lives in :mod:`freefloat.verify`.

A plan file is written atomically (a temporary file renamed over the target), so a reader never
sees half a plan and a failure leaves nothing behind. Units: seconds, radians (metres for
prismatic joints and positions); Euler angles, marked ``_deg``, in degrees. Positions are in
the inertial frame whose origin is the system centre of mass (docs/method.md section 10).

Schema versions: ``freefloat.plan/4`` (this one) stores the joint paths in the orthonormal
basis of :mod:`freefloat.problem.basis` (``path.basis = "quintic+jacobi66"``: per joint the
coefficients ``beta`` in rad, the quintic between ``request.start_joints`` and
``request.goal_joints`` implied; ``free_parameters`` and each root's are the same ``beta``) and
adds the ``path_quality`` record; it also adds every end effector, makes a plan self-contained
and records its plug-ins: ``robot.end_effectors`` (the frames, the first being
``robot.end_effector``) and ``samples.end_effector_paths`` (each one's positions, by frame;
``samples.end_effector_position`` stays the first one's); ``robot`` carries the text of the URDF
the plan was made with (``urdf_text``) and its SHA-256 (``urdf_sha256``), and a relative
``robot.urdf`` path is read from the plan file's folder; the ``constraints`` record lists every
constraint the plan honours, by registered name with its parameters, so that
``freefloat verify`` rebuilds each from the registry (clearance stays in ``safety``), and the
objective has its ``parameters``; ``safety.note`` says what clearance could not check, and
clearance is verified on the original geometry with a certificate between samples
(``clearance``, ``clearance_hull_agreement``); the optional ``robustness`` record holds the
first-order final attitude error under an uncertainty of the mass properties
(docs/robustness.md). Older files store monomials in seconds (``path.coefficients``: ascending
powers of t; ``free_parameters``: the coefficients of t^6 and up); they load with
``Plan.basis == MONOMIAL_BASIS`` and keep their format when re-written (their one end
effector's path is its only path; they carry no URDF, so they are checked against the file
their path names, as it is now; whatever their format, they are held to every limit their URDF
states, :data:`PROMISED`). ``freefloat.plan/3`` adds the ``objective`` record (what the path
minimises, its value and the freedom levels tried) and, for robots with URDF effort limits, the
``joint_effort_limits`` check. ``freefloat.plan/2`` files were minimum-norm plans (no objective
record). ``freefloat.plan/2`` stores the
verification as a list of typed checks, each with its value, tolerance, unit and the check's
own numerical error estimate. ``freefloat.plan/1`` files (freefloat 0.1) still load: their
path, samples and solver report are read as they are and their verification is dropped
(``Verification.checks`` empty, not passed), so ``freefloat verify`` recomputes it.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import PlanFileError, excerpt
from ..files import atomic_write_text
from ..problem.basis import BASIS_NAME
from ..problem.objectives.base import Level
from ..problem.paths import JointPolynomials, PathFamily
from .limits import MAX_PLAN_BYTES, check_plan_file_kind, check_plan_values

__all__ = [
    "FORMAT",
    "FORMAT_2",
    "FORMAT_3",
    "MONOMIAL_BASIS",
    "PROMISED",
    "READABLE_FORMATS",
    "BaseReport",
    "Check",
    "ConstraintRecord",
    "Feasibility",
    "ObstacleRecord",
    "PathQuality",
    "Plan",
    "Request",
    "RobotRef",
    "RobustnessReport",
    "SafetyReport",
    "Samples",
    "SolutionRecord",
    "SolverReport",
    "Verification",
    "read_plan_json",
    "sha256_hex",
]

#: Format tag of plan files written by this version.
FORMAT = "freefloat.plan/4"
#: The format before plan format 4 (still read, and kept when re-written).
FORMAT_3 = "freefloat.plan/3"
#: The format before objectives and effort limits (still read, and kept when re-written).
FORMAT_2 = "freefloat.plan/2"

#: Format tags this version reads (``/1`` is converted on load).
READABLE_FORMATS = ("freefloat.plan/1", FORMAT_2, FORMAT_3, FORMAT)

#: The constraints a file written before constraint records is held to, by format: every limit
#: its URDF states, whatever its format (a format label never chooses the limits).
PROMISED: dict[str, tuple[str, ...]] = {
    fmt: ("joint_position_limits", "joint_velocity_limits", "joint_effort_limits")
    for fmt in ("freefloat.plan/1", FORMAT_2, FORMAT_3)
}

#: ``Plan.basis`` of files before format 4: ascending monomial coefficients in t (s).
MONOMIAL_BASIS = "monomial"


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

    def to_dict(self) -> dict[str, Any]:
        """The ``robot`` record (without the URDF copy in files of older formats)."""
        record = asdict(self)
        if not self.urdf_text:
            del record["urdf_text"], record["urdf_sha256"]
        return record


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
        for name in _SAMPLE_FIELDS:
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float))
        paths = {str(k): np.asarray(v, dtype=float) for k, v in self.end_effector_paths.items()}
        object.__setattr__(self, "end_effector_paths", paths)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Samples):
            return NotImplemented
        return (
            all(
                np.array_equal(getattr(self, name), getattr(other, name)) for name in _SAMPLE_FIELDS
            )
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

    def to_dict(self) -> dict[str, Any]:
        """The samples as the plan file's lists (JSON-ready)."""
        record: dict[str, Any] = {name: getattr(self, name).tolist() for name in _SAMPLE_FIELDS}
        record["end_effector_paths"] = {k: v.tolist() for k, v in self.end_effector_paths.items()}
        return record


#: The fields of :class:`Samples` that are arrays, in file order.
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
        note: why clearance was not checked (``[safety] check = false``, no collision
            geometry), or the movable bodies it could not check; empty when all were.
    """

    checked: bool = False
    margin_m: float = 0.01
    srdf: str | None = None
    obstacles: list[ObstacleRecord] = field(default_factory=list)
    note: str = ""


@dataclass(frozen=True)
class ConstraintRecord:
    """One constraint a plan honours, as the registry rebuilds it.

    Attributes:
        name: its name in :data:`~freefloat.problem.constraints.CONSTRAINTS`.
        parameters: what its ``to_record()`` wrote (degrees for angles, metres).
    """

    name: str
    parameters: dict[str, Any] = field(default_factory=dict)


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
        parameters: what the objective's ``to_record()`` wrote (``freefloat.plan/4``).
    """

    name: str = "min_norm"
    unit: str = "rad^2"
    value: float | None = None
    error_estimate: float = 0.0
    quadrature_nodes: int = 0
    duration_power: int = 0
    start_value: float | None = None
    levels: list[Level] = field(default_factory=list)
    parameters: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class RobustnessReport:
    """First-order final attitude error under an uncertainty of the mass properties.

    Attributes:
        mass_fraction: uncertainty of every body's mass (fraction, 0.05 = 5 %).
        com_m: of every centre-of-mass coordinate (m).
        inertia_fraction: of every inertia component's scale (fraction).
        rms_rad: RMS final attitude error, the parameters independent with those standard
            deviations (rad).
        worst_rad: largest final attitude error, every parameter within those bounds (rad).
    """

    mass_fraction: float
    com_m: float
    inertia_fraction: float
    rms_rad: float
    worst_rad: float


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
    robustness: RobustnessReport | None = None
    format: str = FORMAT
    constraints: list[ConstraintRecord] = field(default_factory=list)
    basis: str = BASIS_NAME
    quality: PathQuality | None = None

    # -- evaluation -------------------------------------------------------------------------

    def path(self) -> JointPolynomials:
        """The joint paths on [0, T], from the file's basis and coefficients."""
        names = self.robot.joints
        if self.basis == MONOMIAL_BASIS:
            return JointPolynomials.from_monomials(
                [self.coefficients[name] for name in names], self.duration
            )
        family = PathFamily(
            np.asarray(self.request.start_joints, dtype=float),
            np.asarray(self.request.goal_joints, dtype=float),
            tuple(5 + len(self.coefficients[name]) for name in names),
        )
        beta = np.concatenate([np.asarray(self.coefficients[n], dtype=float) for n in names])
        return family.polynomials(beta, self.duration)

    def joint_positions(self, t: float | np.ndarray) -> np.ndarray:
        """Joint values (rad or m) at times ``t`` (s) from the plan's path."""
        t = np.asarray(t, dtype=float)
        return self.path().evaluate(np.atleast_1d(t)).q.reshape(*t.shape, -1)

    # -- file -------------------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """The plan as the JSON-ready dictionary of the file format (a deep copy)."""
        robot, samples = self.robot.to_dict(), self.samples.to_dict()
        if self.format != FORMAT:  # an older file keeps its keys
            robot.pop("end_effectors")
            samples.pop("end_effector_paths")
        objective = asdict(self.objective)
        if self.format != FORMAT:
            del objective["parameters"]
        return copy.deepcopy(
            {
                "format": self.format,
                "robot": robot,
                "duration": self.duration,
                "path": {
                    "family": "polynomial",
                    **({} if self.basis == MONOMIAL_BASIS else {"basis": self.basis}),
                    "coefficients": self.coefficients,
                },
                "free_parameters": self.free_parameters,
                "base": asdict(self.base),
                "feasibility": asdict(self.feasibility),
                "samples": samples,
                "solver": asdict(self.solver),
                "request": asdict(self.request),
                "verification": self.verification.to_dict(),
                "safety": asdict(self.safety),
                **({} if self.format == FORMAT_2 else {"objective": objective}),
                **(
                    {"constraints": [asdict(c) for c in self.constraints]}
                    if self.format == FORMAT
                    else {}
                ),
                **(
                    {"robustness": asdict(self.robustness)}
                    if self.robustness is not None and self.format == FORMAT
                    else {}
                ),
                **({} if self.quality is None else {"path_quality": asdict(self.quality)}),
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
        return cls.from_dict(read_plan_json(path), str(path), path.parent)

    @classmethod
    def from_dict(cls, data: Any, where: str = "plan", folder: Path | None = None) -> Plan:
        """Build a plan from its file dictionary, checking the format and the keys.

        Args:
            data: the parsed file.
            where: the file's name, for messages.
            folder: the plan file's folder: a relative ``robot.urdf`` (or ``safety.srdf``)
                path is read from there (default: the working directory).

        Raises:
            PlanFileError: another format, a bad or missing key, a limit broken, or a URDF
                copy whose SHA-256 is not the one stated.
        """
        if not isinstance(data, Mapping):
            raise PlanFileError(f"{where}: not a plan file (top level is not an object)")
        fmt = data.get("format")
        if fmt not in READABLE_FORMATS:
            raise PlanFileError(
                f"{where}: plan format {excerpt(fmt)} is not supported; this freefloat reads "
                + " and ".join(repr(f) for f in READABLE_FORMATS)
            )
        check_plan_values(data, where)
        section = data.get("path")
        basis = section.get("basis", MONOMIAL_BASIS) if isinstance(section, Mapping) else ""
        if (fmt == FORMAT) != (basis == BASIS_NAME):
            raise PlanFileError(
                f"{where}: path basis {excerpt(basis)} does not belong to format {fmt}; "
                f"format {FORMAT} stores basis {BASIS_NAME!r}, older formats monomials"
            )
        try:
            verification = (
                Verification()  # format 1: its untyped checks are recomputed by verify
                if fmt == "freefloat.plan/1"
                else Verification.from_dict(data["verification"])
            )
            return cls(
                robot=_robot_ref(data["robot"], fmt, folder),
                duration=float(data["duration"]),
                coefficients={k: list(v) for k, v in data["path"]["coefficients"].items()},
                free_parameters={k: list(v) for k, v in data["free_parameters"].items()},
                base=BaseReport(**data["base"]),
                feasibility=Feasibility(**data["feasibility"]),
                samples=_samples(data["samples"], data["robot"]),
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
                safety=_safety(data.get("safety"), folder),
                objective=_objective(data.get("objective")),
                format=fmt if fmt in (FORMAT_2, FORMAT_3, FORMAT) else FORMAT_3,  # /1: as /3
                constraints=_constraints(data, fmt, where),
                robustness=_robustness(data.get("robustness") if fmt == FORMAT else None),
                basis=basis,
                quality=(
                    None
                    if data.get("path_quality") is None
                    else PathQuality(**data["path_quality"])
                ),
            )
        except _CopyError as exc:
            raise PlanFileError(f"{where}: {exc}") from None
        except (KeyError, TypeError, AttributeError, ValueError) as exc:
            raise PlanFileError(f"{where}: corrupt plan file (bad or missing {exc})") from None


def _samples(data: Mapping[str, Any], robot: Mapping[str, Any]) -> Samples:
    """The ``samples`` section; before format 4 the one end effector's path is the only one."""
    samples = Samples(**data)
    if samples.end_effector_paths:
        return samples
    paths = {str(robot["end_effector"]): samples.end_effector_position}
    return replace(samples, end_effector_paths=paths)


class _CopyError(Exception):
    """The URDF copy of a plan does not match its stated SHA-256."""


def _beside(path: str, folder: Path | None) -> str:
    """``path`` read from ``folder`` when relative (``~`` expanded)."""
    expanded = Path(path).expanduser()
    if expanded.is_absolute() or folder is None:
        return str(expanded)
    return str(folder / expanded)


def _robot_ref(data: Mapping[str, Any], fmt: str, folder: Path | None) -> RobotRef:
    """The ``robot`` record: its path read from the plan's folder, its URDF copy checked."""
    ref = RobotRef(**{**data, "urdf": _beside(str(data["urdf"]), folder)})
    if not ref.end_effectors:  # a file before format 4: its one end effector
        ref = replace(ref, end_effectors=[ref.end_effector])
    if fmt == FORMAT and not ref.urdf_text:
        raise _CopyError(
            f"plan field 'robot.urdf_text' is missing or empty; {FORMAT} files carry their URDF"
        )
    if ref.urdf_text and sha256_hex(ref.urdf_text) != ref.urdf_sha256:
        raise _CopyError(
            f"plan field 'robot.urdf_sha256' ({excerpt(ref.urdf_sha256, 20)}) is not the SHA-256 "
            f"of 'robot.urdf_text' ({sha256_hex(ref.urdf_text)[:16]}...): the URDF copy was "
            "changed after the plan was made"
        )
    return ref


def _safety(data: Any, folder: Path | None = None) -> SafetyReport:
    """The ``safety`` section (absent in files written before it existed: not checked)."""
    if data is None:
        return SafetyReport()
    return SafetyReport(
        checked=bool(data["checked"]),
        margin_m=float(data["margin_m"]),
        srdf=None if data.get("srdf") is None else _beside(str(data["srdf"]), folder),
        obstacles=[ObstacleRecord(**o) for o in data.get("obstacles", [])],
        note=str(data.get("note", "")),
    )


def _objective(data: Any) -> ObjectiveReport:
    """The ``objective`` section (absent in files written before it existed: minimum norm)."""
    if data is None:
        return ObjectiveReport()
    return ObjectiveReport(
        **{
            **data,
            "levels": [Level(**level) for level in data.get("levels", [])],
        }
    )


class _DuplicateKeyError(Exception):
    """A key twice in one JSON object (carries the key)."""


def _no_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object as a dict; a key given twice raises (``json`` would keep the last)."""
    result: dict[str, Any] = {}
    for key, value in pairs:
        if key in result:
            raise _DuplicateKeyError(key)
        result[key] = value
    return result


def _constraints(data: Mapping[str, Any], fmt: str, where: str) -> list[ConstraintRecord]:
    """The ``constraints`` record; for older formats, the constraints they promised."""
    if fmt in PROMISED:
        return [ConstraintRecord(name) for name in PROMISED[fmt]]
    records = [
        ConstraintRecord(str(item["name"]), dict(item.get("parameters", {})))
        for item in data["constraints"]
    ]
    names = [r.name for r in records]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise PlanFileError(
                f"{where}: plan field 'constraints[{i}]' names {excerpt(name)} again; each "
                "constraint is recorded once"
            )
    return records


def _robustness(data: Any) -> RobustnessReport | None:
    """The ``robustness`` section (optional; absent before ``freefloat.plan/4``)."""
    if data is None:
        return None
    return RobustnessReport(**{k: float(v) for k, v in data.items()})


def read_plan_json(path: str | Path) -> Any:
    """The parsed JSON of a plan file.

    The path must name a regular file of at most :data:`~freefloat.plans.limits.MAX_PLAN_BYTES`
    (checked before reading, so a FIFO or ``/dev/zero`` is refused, not read).

    A UTF-8 byte-order mark is accepted.

    Raises:
        PlanFileError: missing, not a regular file, too large, unreadable, not JSON, a key
            twice in one object, or nested too deeply to parse.
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
        return json.loads(raw.decode("utf-8-sig"), object_pairs_hook=_no_duplicate_keys)
    except FileNotFoundError:
        raise PlanFileError(f"plan file not found: {path}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PlanFileError(f"cannot read plan file {path}: {exc}") from None
    except json.JSONDecodeError as exc:
        raise PlanFileError(f"{path}: not a plan file, corrupt JSON ({exc})") from None
    except RecursionError:
        raise PlanFileError(f"{path}: not a plan file, JSON nested too deeply") from None
    except _DuplicateKeyError as exc:
        raise PlanFileError(
            f"{path}: key {excerpt(exc.args[0])} appears twice in one object; a plan file "
            "states each field once"
        ) from None
    except ValueError as exc:  # an integer of thousands of digits
        raise PlanFileError(f"{path}: not a plan file ({excerpt(str(exc), 80)})") from None
