"""Plans: plan a scenario, and read and write the plan file (JSON, ``freefloat.plan/1``).

A plan file is written atomically (a temporary file renamed over the target), so a reader never
sees half a plan and a failure leaves nothing behind. Units: seconds, radians (metres for
prismatic joints and positions); Euler angles, marked ``_deg``, in degrees. Positions are in
the inertial frame whose origin is the system centre of mass.
"""

from __future__ import annotations

import copy
import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .attitude import geodesic_angle, zyx_from_quat
from .dynamics import inverse_dynamics
from .errors import PlanFileError, SolverError, VerificationError
from .files import atomic_write_text
from .problem import Problem
from .scenario import Scenario
from .search import search, velocity_check
from .solve import DEFAULT_TOLERANCE, Solution, SolveOptions
from .verify import as_dict, boundary_errors, verify_plan

__all__ = [
    "FORMAT",
    "BaseReport",
    "Feasibility",
    "Plan",
    "RobotRef",
    "Samples",
    "SolverReport",
    "plan",
    "plan_from_solution",
]

#: Format tag of plan files written by this version.
FORMAT = "freefloat.plan/1"

#: Boundary conditions must hold to this (rad, rad/s, rad/s^2; relative to the joint travel).
BOUNDARY_TOLERANCE = 1e-9


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


@dataclass(frozen=True)
class Samples:
    """The plan sampled in time; each field is a list with one entry per sample.

    ``t`` (s); ``q`` (rad or m), ``qd`` (per s), ``qdd`` (per s^2), one value per joint;
    ``base_position`` (m), ``base_quaternion_xyzw``, ``base_zyx_deg`` (deg),
    ``base_angular_velocity`` (rad/s, base frame), ``end_effector_position`` (m), ``tau`` joint
    torques (N m, or N for prismatic joints).
    """

    t: list[float]
    q: list[list[float]]
    qd: list[list[float]]
    qdd: list[list[float]]
    base_position: list[list[float]]
    base_quaternion_xyzw: list[list[float]]
    base_zyx_deg: list[list[float]]
    end_effector_position: list[list[float]]
    base_angular_velocity: list[list[float]] = field(default_factory=list)
    tau: list[list[float]] = field(default_factory=list)


@dataclass(frozen=True)
class SolverReport:
    """How the free coefficients were found.

    ``solutions`` lists every root found (the chosen one first) with its free parameters
    (``t^6`` and up, per joint), residual (rad) and summed joint travel (rad or m);
    ``freedom`` the free coefficients per joint the planner used; ``full_turns`` the whole turns
    added to continuous joints' goals; ``tried`` every attempt in order.
    """

    method: str
    iterations: int
    evaluations: int
    residual_rad: float
    wall_time_s: float
    solutions: list[dict[str, Any]]
    integration_steps: int = 0
    integration_error_rad: float = 0.0
    freedom: dict[str, int] = field(default_factory=dict)
    full_turns: dict[str, int] = field(default_factory=dict)
    tried: list[str] = field(default_factory=list)


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
    request: dict[str, list[float]] = field(default_factory=dict)
    verification: dict[str, Any] = field(default_factory=dict)
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
                "samples": asdict(self.samples),
                "solver": asdict(self.solver),
                "request": self.request,
                "verification": self.verification,
            }
        )

    def save(self, path: str | Path) -> Path:
        """Write the plan to ``path`` atomically; return the absolute path."""
        return atomic_write_text(path, json.dumps(self.to_dict(), indent=1, allow_nan=False))

    @classmethod
    def load(cls, path: str | Path) -> Plan:
        """Read a plan file.

        Raises:
            PlanFileError: unreadable, not JSON, another format version, or missing keys.
        """
        path = Path(path).expanduser()
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise PlanFileError(f"plan file not found: {path}") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise PlanFileError(f"cannot read plan file {path}: {exc}") from None
        except json.JSONDecodeError as exc:
            raise PlanFileError(f"{path}: not a plan file, corrupt JSON ({exc})") from None
        return cls.from_dict(data, str(path))

    @classmethod
    def from_dict(cls, data: Any, where: str = "plan") -> Plan:
        """Build a plan from its file dictionary, checking the format and the keys."""
        if not isinstance(data, Mapping):
            raise PlanFileError(f"{where}: not a plan file (top level is not an object)")
        fmt = data.get("format")
        if fmt != FORMAT:
            raise PlanFileError(
                f"{where}: plan format {fmt!r} is not supported; this freefloat reads {FORMAT!r}"
            )
        try:
            return cls(
                robot=RobotRef(**data["robot"]),
                duration=float(data["duration"]),
                coefficients={k: list(v) for k, v in data["path"]["coefficients"].items()},
                free_parameters={k: list(v) for k, v in data["free_parameters"].items()},
                base=BaseReport(**data["base"]),
                feasibility=Feasibility(**data["feasibility"]),
                samples=Samples(**data["samples"]),
                solver=SolverReport(**data["solver"]),
                request={k: list(v) for k, v in data["request"].items()},
                verification=dict(data["verification"]),
            )
        except (KeyError, TypeError, AttributeError, ValueError) as exc:
            raise PlanFileError(f"{where}: corrupt plan file (bad or missing {exc})") from None


def _deg(values: np.ndarray) -> list[float]:
    return [math.degrees(float(v)) for v in values]


def plan(scenario: Scenario, options: SolveOptions | None = None, samples: int = 201) -> Plan:
    """Plan the scenario's motion and sample it.

    Args:
        scenario: what to plan.
        options: solver settings; the scenario's ``max_deviation`` overrides the default
            bracket.
        samples: number of equally spaced samples in [0, T] (>= 2).

    Raises:
        FreeFloatError: any subclass: bad input, infeasible request, no solution.
    """
    options = options or SolveOptions()
    if scenario.max_deviation is not None:
        options = SolveOptions(**{**asdict(options), "max_deviation": scenario.max_deviation})
    found = search(scenario, options)
    velocity_check(found.problem, found.solution)
    result = plan_from_solution(found.problem, found.solution, samples, options.tolerance)
    report = replace(
        result.solver, freedom=found.freedom, full_turns=found.full_turns, tried=found.tried
    )
    return replace(result, solver=report)


def plan_from_solution(
    problem: Problem,
    solution: Solution,
    samples: int = 201,
    tolerance: float = DEFAULT_TOLERANCE,
    verify: bool = True,
) -> Plan:
    """Sample a solved problem into a verified :class:`Plan`.

    Args:
        problem: the solved problem.
        solution: its solution.
        samples: number of equally spaced samples in [0, T].
        tolerance: attitude tolerance (rad).
        verify: run the independent checks of :mod:`freefloat.verify` (a plan from
            :func:`plan` always is).

    Raises:
        SolverError: the attitude reached (by the solver's grid or by the sampling grid) is
            farther than ``tolerance`` (rad) from the goal, or a boundary condition fails.
        VerificationError: an independent check fails.
    """
    robot, family, T = problem.robot, problem.family, problem.duration
    names = robot.joint_names
    s = np.linspace(0.0, 1.0, max(2, int(samples)))
    t = s * T
    path = family.at_times(solution.beta, t, T)
    quats = problem.attitudes(solution.beta, s)
    mmap = problem.mmap
    base_position, ee_position, omega, tau = [], [], [], []
    for q, qd, qdd, quat in zip(path.q, path.qd, path.qdd, quats, strict=True):
        base_position.append(mmap.base_position(q, quat).tolist())
        ee_position.append(mmap.end_effector_pose(q, quat).translation.tolist())
        omega.append((mmap.f1(q) @ qd).tolist())
        tau.append(inverse_dynamics(mmap, q, qd, qdd).tau.tolist())

    achieved = problem.achieved(solution.beta)
    error = geodesic_angle(achieved, problem.goal_quaternion)
    sampled_error = geodesic_angle(quats[-1], problem.goal_quaternion)
    boundary = boundary_errors(
        family.time_coefficients(solution.beta, T), family.start, family.goal, T
    )["relative_max"]
    if max(error, sampled_error) > tolerance or boundary > BOUNDARY_TOLERANCE:
        raise SolverError(
            "the planned path misses its target (attitude error "
            f"{max(error, sampled_error):.3g} rad, boundary error {boundary:.3g})",
            max(error, sampled_error),
        )

    free = family.free_time_coefficients(solution.beta, T)
    solutions = [
        {
            "free_parameters": dict(
                zip(names, family.free_time_coefficients(root.beta, T), strict=True)
            ),
            "residual_rad": root.residual,
            "path_length": root.path_length,
        }
        for root in solution.roots
    ]
    bounds = problem.bounds_interval
    unverified = Plan(
        robot=RobotRef(
            urdf=str(robot.urdf),
            joints=names,
            end_effector=robot.end_effector,
            joint_kinds=[j.kind for j in robot.joints],
        ),
        duration=T,
        coefficients={
            name: c.tolist()
            for name, c in zip(names, family.time_coefficients(solution.beta, T), strict=True)
        },
        free_parameters=dict(zip(names, free, strict=True)),
        base=BaseReport(
            start_quaternion_xyzw=problem.start_quaternion.tolist(),
            target_quaternion_xyzw=problem.goal_quaternion.tolist(),
            achieved_quaternion_xyzw=achieved.tolist(),
            start_zyx_deg=_deg(zyx_from_quat(problem.start_quaternion)),
            target_zyx_deg=_deg(zyx_from_quat(problem.goal_quaternion)),
            achieved_zyx_deg=_deg(zyx_from_quat(achieved)),
            attitude_error_rad=error,
        ),
        feasibility=Feasibility(
            planar=problem.planar,
            yaw_change_bounds_deg=None if bounds is None else _deg(np.array(bounds)),
            requested_yaw_change_deg=(
                None if problem.yaw_change is None else math.degrees(problem.yaw_change)
            ),
        ),
        samples=Samples(
            t=t.tolist(),
            q=path.q.tolist(),
            qd=path.qd.tolist(),
            qdd=path.qdd.tolist(),
            base_position=base_position,
            base_quaternion_xyzw=quats.tolist(),
            base_zyx_deg=[_deg(zyx_from_quat(qt)) for qt in quats],
            end_effector_position=ee_position,
            base_angular_velocity=omega,
            tau=tau,
        ),
        solver=SolverReport(
            method=solution.method,
            iterations=solution.iterations,
            evaluations=solution.evaluations,
            residual_rad=solution.residual,
            wall_time_s=solution.wall_time,
            solutions=solutions,
            integration_steps=problem.steps,
            integration_error_rad=solution.integration_error,
        ),
        request={"start_joints": family.start.tolist(), "goal_joints": family.goal.tolist()},
    )
    if not verify:
        return unverified
    verification = verify_plan(unverified, robot)
    if not verification.passed:
        raise VerificationError(verification.failures)
    return replace(unverified, verification=as_dict(verification))
