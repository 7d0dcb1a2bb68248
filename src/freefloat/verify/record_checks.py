"""The plan's records recomputed from its rebuilt problem: base, feasibility, samples, solver.

Each check is a function of a :class:`Rebuilt` (the plan, its robot, its problem and free
coefficients rebuilt from the file) that raises :class:`~freefloat.errors.PlanMismatchError`
naming the first field that disagrees; the list of them, in the order of dependence, is
:data:`freefloat.verify.recompute.RECORD_CHECKS` and their tolerances are explained in
:mod:`freefloat.verify.recompute`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import FreeFloatError, PlanMismatchError
from ..physics.attitude import geodesic_angle, quat_from_zyx
from ..plans.format import Plan
from ..plans.sampling import base_report, feasibility_report, sample_solution
from ..plans.versions import FORMAT_4
from ..problem.inertial_sensitivity import attitude_sensitivity
from ..problem.residual import Problem
from ..problem.uncertainty import Uncertainty, spread
from ..robot.model import Robot
from . import agreement
from .agreement import (
    AXES,
    BOUNDS_TOLERANCE_DEG,
    RELATIVE_TOLERANCE,
    RESIDUAL_TOLERANCE,
    ROBUSTNESS_TOLERANCE,
    rotation_angles,
    scale_of,
    unit_of,
)
from .path_records import free_counts, root_beta

__all__ = [
    "Rebuilt",
    "check_base",
    "check_feasibility",
    "check_robustness",
    "check_samples",
    "check_solver",
]


@dataclass
class Rebuilt:
    """A plan with its problem rebuilt from its file.

    Attributes:
        plan: the plan.
        robot: its robot, from its URDF.
        problem: its problem, on its solver's integration grid.
        beta: its free coefficients (rad or m).
    """

    plan: Plan
    robot: Robot
    problem: Problem
    beta: np.ndarray

    @property
    def names(self) -> list[str]:
        """The joints' names, in order."""
        return list(self.plan.robot.joints)

    @property
    def unit(self) -> str:
        """The joints' unit: ``rad``, ``m`` or ``m or rad``."""
        return unit_of([j.kind for j in self.robot.joints], "rad", "m")

    @cached_property
    def estimate(self) -> float:
        """The attitude integration's own error estimate at ``beta`` (rad)."""
        return self.problem.integration_error(self.beta)


def check_base(r: Rebuilt) -> None:
    """The ``base`` record, with the attitude integration's own error estimate."""
    plan = r.plan
    base = base_report(r.problem, r.beta)
    for key in ("start_quaternion_xyzw", "target_quaternion_xyzw"):
        stated, mine = getattr(plan.base, key), getattr(base, key)
        agreement.compare(f"base.{key}", stated, mine, RELATIVE_TOLERANCE)
    attitude_tol = RELATIVE_TOLERANCE + r.estimate
    achieved = np.asarray(plan.base.achieved_quaternion_xyzw, dtype=float)
    agreement.compare(
        "base.achieved_quaternion_xyzw",
        rotation_angles(achieved[None], np.asarray(base.achieved_quaternion_xyzw)[None]),
        np.zeros(1),
        attitude_tol,
        "rad",
    )
    for key, quat, tol in (
        ("start_zyx_deg", base.start_quaternion_xyzw, RELATIVE_TOLERANCE),
        ("target_zyx_deg", base.target_quaternion_xyzw, RELATIVE_TOLERANCE),
        ("achieved_zyx_deg", base.achieved_quaternion_xyzw, attitude_tol),
    ):
        angles = np.radians(getattr(plan.base, key))
        agreement.compare(
            f"base.{key}",
            geodesic_angle(quat_from_zyx(*angles), np.asarray(quat)),
            0.0,
            tol,
            "rad",
        )
    agreement.compare(
        "base.attitude_error_rad",
        plan.base.attitude_error_rad,
        base.attitude_error_rad,
        attitude_tol,
        "rad",
    )


def check_feasibility(r: Rebuilt) -> None:
    """The ``feasibility`` record: the planar bounds and the request."""
    stated = r.plan.feasibility
    feasibility = feasibility_report(r.problem)
    if stated.planar != feasibility.planar:
        raise PlanMismatchError(
            "feasibility.planar",
            math.inf,
            0.0,
            message=f"the file says {stated.planar}, the URDF gives {feasibility.planar}",
        )
    for key, tol in (
        ("yaw_change_bounds_deg", BOUNDS_TOLERANCE_DEG),
        ("requested_yaw_change_deg", math.degrees(RELATIVE_TOLERANCE)),
    ):
        mine, theirs = getattr(feasibility, key), getattr(stated, key)
        if (mine is None) != (theirs is None):
            raise PlanMismatchError(
                f"feasibility.{key}",
                math.inf,
                0.0,
                message=f"the file says {theirs}, the recomputation {mine}",
            )
        if mine is not None:
            agreement.compare(f"feasibility.{key}", theirs, mine, tol, "deg")


def check_samples(r: Rebuilt) -> None:
    """The ``samples``: t, q, qd, qdd, base pose, end effectors, base rate, torques."""
    samples, names, unit = r.plan.samples, r.names, r.unit
    again = sample_solution(r.problem, r.beta, len(samples.t))
    times = np.asarray(again.t)
    compare = agreement.compare
    compare("samples.t", samples.t, again.t, RELATIVE_TOLERANCE * r.plan.duration, "s", times)
    for key, suffix in (("q", ""), ("qd", "/s"), ("qdd", "/s^2")):
        mine = np.asarray(getattr(again, key))
        tol = RELATIVE_TOLERANCE * scale_of(mine)
        compare(f"samples.{key}", getattr(samples, key), mine, tol, unit + suffix, times, names)
    attitude_tol = RELATIVE_TOLERANCE + r.estimate
    angles = rotation_angles(
        np.asarray(samples.base_quaternion_xyzw, dtype=float),
        np.asarray(again.base_quaternion_xyzw),
    )
    compare("samples.base_quaternion_xyzw", angles, 0.0 * angles, attitude_tol, "rad", times)
    stated = np.radians(np.asarray(samples.base_zyx_deg, dtype=float))
    angles = np.array(
        [
            geodesic_angle(quat_from_zyx(*row), np.asarray(quat))
            for row, quat in zip(stated, again.base_quaternion_xyzw, strict=True)
        ]
    )
    compare("samples.base_zyx_deg", angles, 0.0 * angles, attitude_tol, "rad", times)
    positions = np.asarray(again.base_position), np.asarray(again.end_effector_position)
    size = scale_of(*positions)
    for key, mine in zip(("base_position", "end_effector_position"), positions, strict=True):
        tol = RELATIVE_TOLERANCE * size + r.estimate * scale_of(mine)
        compare(f"samples.{key}", getattr(samples, key), mine, tol, "m", times, AXES)
    for frame, path in again.end_effector_paths.items():  # every end effector (format 4)
        mine = np.asarray(path)
        tol = RELATIVE_TOLERANCE * scale_of(np.asarray(again.base_position), mine)
        tol += r.estimate * scale_of(mine)
        theirs = samples.path_of(frame)
        compare(f"samples.end_effector_paths.{frame}", theirs, mine, tol, "m", times, AXES)
    torque_unit = unit_of([j.kind for j in r.robot.joints], "N m", "N")
    for key, mine, label, columns in (
        ("base_angular_velocity", again.base_angular_velocity, "rad/s", AXES),
        ("tau", again.tau, torque_unit, names),
    ):
        theirs = getattr(samples, key)
        if len(theirs):  # absent from files written before these were recorded
            tol = RELATIVE_TOLERANCE * scale_of(np.asarray(mine))
            compare(f"samples.{key}", theirs, mine, tol, label, times, columns)


def check_solver(r: Rebuilt) -> None:
    """The ``solver`` record, what of it can be recomputed: residuals, roots and freedom."""
    plan, problem, names = r.plan, r.problem, r.names
    solver = plan.solver
    chosen = float(np.linalg.norm(problem.residual(r.beta)))
    compare = agreement.compare
    tolerance = RESIDUAL_TOLERANCE + r.estimate
    compare("solver.residual_rad", solver.residual_rad, chosen, tolerance, "rad")
    compare(
        "solver.integration_error_rad",
        solver.integration_error_rad,
        r.estimate,
        RELATIVE_TOLERANCE + 0.5 * r.estimate,
        "rad",
    )
    for i, root in enumerate(solver.solutions):
        free = [root.free_parameters[name] for name in names]
        if i == 0:
            for name in names:
                field = f"solver.solutions[0].free_parameters.{name}"
                compare(field, root.free_parameters[name], plan.free_parameters[name], 0.0)
        beta_i = root_beta(plan, problem.family, free)
        residual = float(np.linalg.norm(problem.residual(beta_i)))
        tolerance = RESIDUAL_TOLERANCE + problem.integration_error(beta_i)
        compare(
            f"solver.solutions[{i}].residual_rad", root.residual_rad, residual, tolerance, "rad"
        )
        length = problem.path_length(beta_i)
        tolerance = RESIDUAL_TOLERANCE * max(1.0, length)
        compare(f"solver.solutions[{i}].path_length", root.path_length, length, tolerance, r.unit)
    counts = dict(zip(names, free_counts(plan), strict=True))
    for name, count in solver.freedom.items():
        if count != counts.get(name):
            raise PlanMismatchError(
                f"solver.freedom.{name}",
                math.inf,
                0.0,
                message=f"the file says {count!r}, the path has "
                f"{counts.get(name, 'no')} free coefficients there",
            )


def check_robustness(r: Rebuilt) -> None:
    """Recompute the ``robustness`` record (formats 4 and 5, optional) for its uncertainty.

    The figures come from the exact sensitivity on the plan's grid and, for the worst case, a
    vertex search; both are deterministic, so
    :data:`~freefloat.verify.agreement.ROBUSTNESS_TOLERANCE` of the figure is rounding with a
    wide margin.
    """
    record = r.plan.robustness
    if record is None:
        return
    try:
        uncertainty = Uncertainty(record.mass_fraction, record.com_m, record.inertia_fraction)
    except FreeFloatError as exc:
        raise PlanMismatchError("robustness", math.inf, 0.0, message=str(exc)) from None
    apart = r.plan.format != FORMAT_4  # format 4 counted a payload within its holder's body
    found = spread(attitude_sensitivity(r.problem, r.beta, payload_apart=apart), uncertainty)
    for key, value in (("rms_rad", found.rms), ("worst_rad", found.worst)):
        tolerance = ROBUSTNESS_TOLERANCE * value + 1e-15
        agreement.compare(f"robustness.{key}", getattr(record, key), value, tolerance, "rad")
