"""Every number of a plan file, recomputed from its URDF, duration and coefficients.

A plan file vouches for every number in it, so ``freefloat verify`` trusts none of them: it
rebuilds the plan's problem from the URDF, the duration, the path coefficients and the stated
start and goal attitudes, recomputes each record with the functions that wrote it
(:mod:`freefloat.plans.sampling`), and raises :class:`~freefloat.errors.PlanMismatchError`
naming the first field that disagrees beyond its tolerance. The order is that of dependence:
``robot``, ``path.coefficients``, ``free_parameters``, ``request``, ``path_quality``, ``base``,
``feasibility``, ``samples`` (t, q, qd, qdd, base pose, end effector, base rate, torques),
``solver`` (residual, integration error, roots, freedom), ``objective``, ``robustness`` (when
present); the verification figures are compared after the checks have run
(:func:`compare_verification`).

Tolerances. The recomputation runs the same deterministic code on the same numbers (the
coefficients round-trip through JSON exactly), so a genuine plan disagrees with it by
rounding alone: about 1e-15 of each quantity's scale (observed up to ~1e-13 for the integrated
attitude, which chains thousands of steps). :data:`RELATIVE_TOLERANCE` = 1e-10 of the scale
leaves a thousandfold margin over that, on any machine, and still catches a 1e-6 N m change
in any torque of a plan whose peak torque is below 1e4 N m. The scale of a field is its
largest recomputed magnitude (positions share the robot's: the largest of base and end
effector). Numbers that depend on the attitude integration also allow the recomputation's own
error estimate (the Magnus scheme on the same grid against twice as many steps), and the
planar bounds their optimiser's accuracy (:data:`BOUNDS_TOLERANCE_DEG`). Attitude residuals of
the solver's roots were computed on the solver's grid before the last refinement, so they are
held to :data:`RESIDUAL_TOLERANCE` (the planner's default attitude tolerance) plus that
estimate. A verification figure must agree with its recomputation to
:data:`FIGURE_FRACTION` of its check's tolerance plus twice the recomputed error estimate.

Not recomputable, and so not checked: the solver's history (method, iterations, evaluations,
wall and stage times, strategy, attempts, whole turns added), the checks' ``detail`` text, and
the safety record, which is input (it changes the clearance check's figure when it matters).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import FreeFloatError, InfeasibleError, PlanFileError, PlanMismatchError
from ..physics.attitude import geodesic_angle, quat_from_zyx
from ..plans.format import Plan
from ..plans.guarantees import Verification
from ..plans.sampling import base_report, feasibility_report, sample_solution
from ..plans.versions import MONOMIAL_BASIS
from ..problem.build import build_problem
from ..problem.inertial_sensitivity import attitude_sensitivity
from ..problem.residual import Problem
from ..problem.uncertainty import Uncertainty, spread
from ..robot.model import Robot
from .objective import check_objective
from .path_records import check_quality, free_counts, root_beta

__all__ = [
    "BOUNDS_TOLERANCE_DEG",
    "FIGURE_FRACTION",
    "RELATIVE_TOLERANCE",
    "RESIDUAL_TOLERANCE",
    "check_plan_numbers",
    "compare_verification",
    "problem_from_plan",
]

#: Allowed disagreement of a recomputed number, relative to its field's scale.
RELATIVE_TOLERANCE = 1e-10
#: Allowed disagreement of the planar bounds (deg): L-BFGS-B refines the gain extremes to about
#: 1e-10, times a joint travel of a few radians, with a hundredfold margin.
BOUNDS_TOLERANCE_DEG = 1e-6
#: Allowed disagreement of a root's attitude residual (rad), plus the integration estimate.
RESIDUAL_TOLERANCE = 1e-9
#: Allowed disagreement of the robustness record's figures, relative to the figure.
ROBUSTNESS_TOLERANCE = 1e-8
#: A verification figure agrees when within this fraction of its check's tolerance (plus twice
#: the recomputed error estimate).
FIGURE_FRACTION = 1e-3

_AXES = ("x", "y", "z", "w")


def _unit(kinds: Sequence[str], angular: str, linear: str) -> str:
    units = {linear if k == "prismatic" else angular for k in kinds}
    return " or ".join(sorted(units)) if units else angular


def _scale(*arrays: np.ndarray) -> float:
    """The largest magnitude in ``arrays`` (at least 1e-300, so a tolerance is never 0)."""
    return max([1e-300, *(float(np.max(np.abs(a))) for a in arrays if np.size(a))])


def _compare(
    field: str,
    stored: object,
    recomputed: object,
    tolerance: float | np.ndarray,
    unit: str = "",
    times: np.ndarray | None = None,
    columns: Sequence[str] | None = None,
) -> None:
    """Raise :class:`PlanMismatchError` where ``stored`` and ``recomputed`` differ too much."""
    a = np.asarray(stored, dtype=float)
    b = np.asarray(recomputed, dtype=float)
    if a.shape != b.shape:
        raise PlanMismatchError(
            field,
            math.inf,
            0.0,
            message=f"{a.shape} values stored, {b.shape} recomputed",
        )
    diff = np.abs(a - b)
    tol = np.broadcast_to(np.asarray(tolerance, dtype=float), diff.shape)
    bad = ~(diff <= tol)  # NaN is bad
    if not bad.any():
        return
    ratio = np.where(bad, np.nan_to_num(diff, nan=np.inf) / np.maximum(tol, 1e-300), -1.0)
    index = tuple(int(i) for i in np.unravel_index(int(np.argmax(ratio)), diff.shape))
    raise PlanMismatchError(
        field, float(diff[index]), float(tol[index]), unit, _where(index, times, columns)
    )


def _where(index: tuple[int, ...], times: np.ndarray | None, columns: Sequence[str] | None) -> str:
    parts = []
    rest = list(index)
    if times is not None and rest:
        parts.append(f"at t = {float(times[rest.pop(0)]):.6g} s")
    if columns is not None and rest:
        parts.append(f"({columns[rest.pop(0)]})")
    elif rest:
        parts.append(f"(entry {', '.join(str(i) for i in index)})")
    return " ".join(parts)


def _compare_terms(
    field: str,
    stored: Sequence[float] | np.ndarray,
    coefficients: Sequence[float] | np.ndarray,
    first: int,
    duration: float,
    scale: float,
    unit: str,
) -> None:
    """Compare polynomial coefficients ``c_k`` (rad/s^k or m/s^k) from ``k = first`` on.

    Each term ``c_k T^k`` is held to :data:`RELATIVE_TOLERANCE` of the joint's largest term
    ``scale`` (rad or m).
    """
    want = np.asarray(coefficients, dtype=float)[first:]
    powers = np.arange(first, first + len(want))
    _compare(
        field,
        stored,
        want,
        RELATIVE_TOLERANCE * scale / duration**powers,
        f"{unit}/s^k",
        None,
        [f"k = {k}" for k in powers],
    )


def _rotation_angles(stored: np.ndarray, recomputed: np.ndarray) -> np.ndarray:
    """Per row, the angle (rad) between two attitudes, and any difference in norm."""
    angles = np.array([geodesic_angle(a, b) for a, b in zip(stored, recomputed, strict=True)])
    norms = np.abs(np.linalg.norm(stored, axis=-1) - np.linalg.norm(recomputed, axis=-1))
    out: np.ndarray = angles + norms
    return out


def problem_from_plan(plan: Plan, robot: Robot) -> tuple[Problem, np.ndarray]:
    """The plan's problem (on its solver's integration grid) and its free coefficients beta.

    The path family's degrees come from the coefficient lists, beta from them (format 4) or
    from the monomials (older formats, :mod:`.path_records`), the start and goal joints from
    the request (checked against an older format's path first by :func:`check_plan_numbers`).

    Raises:
        PlanFileError: the plan's request cannot be a problem (joints beyond their limits, a
            goal a planar robot cannot reach).
        PlanMismatchError: the requested yaw change lies outside the planar bounds.
    """
    try:
        problem = build_problem(
            robot,
            np.asarray(plan.request.start_joints, dtype=float),
            np.asarray(plan.request.goal_joints, dtype=float),
            np.asarray(plan.base.start_quaternion_xyzw, dtype=float),
            np.asarray(plan.base.target_quaternion_xyzw, dtype=float),
            plan.duration,
            extra=free_counts(plan),
        )
    except InfeasibleError as exc:
        raise PlanMismatchError(
            "feasibility.requested_yaw_change_deg", math.inf, 0.0, message=str(exc)
        ) from None
    except FreeFloatError as exc:
        raise PlanFileError(f"the plan's request is not a valid problem: {exc}") from None
    if plan.solver.integration_steps > 0:
        problem = problem.with_steps(plan.solver.integration_steps)
    if plan.basis == MONOMIAL_BASIS:
        beta = problem.family.beta_from_path(plan.path())
    else:
        beta = root_beta(plan, problem.family, [plan.coefficients[n] for n in plan.robot.joints])
    return problem, beta


def check_plan_numbers(plan: Plan, robot: Robot) -> Problem:
    """Recompute every number of ``plan`` and compare (see the module docstring).

    Returns:
        The plan's problem, rebuilt.

    Raises:
        PlanMismatchError: the first field that disagrees beyond its tolerance, named.
        PlanFileError: a plan whose request cannot be rebuilt.
    """
    names = list(plan.robot.joints)
    kinds = [j.kind for j in robot.joints]
    if plan.robot.joint_kinds and list(plan.robot.joint_kinds) != kinds:
        raise PlanMismatchError(
            "robot.joint_kinds",
            math.inf,
            0.0,
            message=f"the file says {plan.robot.joint_kinds}, the URDF has {kinds}",
        )
    unit = _unit(kinds, "rad", "m")
    T = plan.duration

    # The path: boundary structure, free parameters, request.
    stored = [np.asarray(plan.coefficients[name], dtype=float) for name in names]
    if plan.basis == MONOMIAL_BASIS:
        term_scale = [max(1.0, float(np.max(np.abs(c) * T ** np.arange(len(c))))) for c in stored]
        start = np.array([c[0] for c in stored])
        goal = np.array([np.polynomial.polynomial.polyval(T, c) for c in stored])
        joint_tol = RELATIVE_TOLERANCE * np.array(term_scale)
        for name, c, scale in zip(names, stored, term_scale, strict=True):
            stated_free = plan.free_parameters[name]
            _compare_terms(f"free_parameters.{name}", stated_free, c, 6, T, scale, unit)
        for key, value in (("start_joints", start), ("goal_joints", goal)):
            stated = getattr(plan.request, key)
            _compare(f"request.{key}", stated, value, joint_tol, unit, None, names)
    else:  # format 4: the path is the free parameters (the quintic is the request's)
        for name, c in zip(names, stored, strict=True):
            tol = RELATIVE_TOLERANCE * max(1.0, float(np.abs(c).max(initial=0.0)))
            _compare(f"free_parameters.{name}", plan.free_parameters[name], c, tol, unit)
    problem, beta = problem_from_plan(plan, robot)
    if plan.basis == MONOMIAL_BASIS:
        rebuilt = problem.polynomials(beta).monomials()
        for name, c, again, scale in zip(names, stored, rebuilt, term_scale, strict=True):
            _compare_terms(f"path.coefficients.{name}", c, again[: len(c)], 0, T, scale, unit)
    check_quality(plan, problem, beta, RELATIVE_TOLERANCE)

    # The base report, with the attitude integration's own error estimate.
    estimate = problem.integration_error(beta)
    base = base_report(problem, beta)
    for key in ("start_quaternion_xyzw", "target_quaternion_xyzw"):
        _compare(f"base.{key}", getattr(plan.base, key), getattr(base, key), RELATIVE_TOLERANCE)
    attitude_tol = RELATIVE_TOLERANCE + estimate
    achieved = np.asarray(plan.base.achieved_quaternion_xyzw, dtype=float)
    _compare(
        "base.achieved_quaternion_xyzw",
        _rotation_angles(achieved[None], np.asarray(base.achieved_quaternion_xyzw)[None]),
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
        _compare(
            f"base.{key}",
            geodesic_angle(quat_from_zyx(*angles), np.asarray(quat)),
            0.0,
            tol,
            "rad",
        )
    _compare(
        "base.attitude_error_rad",
        plan.base.attitude_error_rad,
        base.attitude_error_rad,
        attitude_tol,
        "rad",
    )

    # Feasibility: the planar bounds and the request.
    feasibility = feasibility_report(problem)
    if plan.feasibility.planar != feasibility.planar:
        raise PlanMismatchError(
            "feasibility.planar",
            math.inf,
            0.0,
            message=f"the file says {plan.feasibility.planar}, the URDF gives {feasibility.planar}",
        )
    for key, tol in (
        ("yaw_change_bounds_deg", BOUNDS_TOLERANCE_DEG),
        ("requested_yaw_change_deg", math.degrees(RELATIVE_TOLERANCE)),
    ):
        mine, theirs = getattr(feasibility, key), getattr(plan.feasibility, key)
        if (mine is None) != (theirs is None):
            raise PlanMismatchError(
                f"feasibility.{key}",
                math.inf,
                0.0,
                message=f"the file says {theirs}, the recomputation {mine}",
            )
        if mine is not None:
            _compare(f"feasibility.{key}", theirs, mine, tol, "deg")

    # The samples.
    samples = plan.samples
    again = sample_solution(problem, beta, len(samples.t))
    times = np.asarray(again.t)
    _compare("samples.t", samples.t, again.t, RELATIVE_TOLERANCE * T, "s", times)
    for key, suffix in (("q", ""), ("qd", "/s"), ("qdd", "/s^2")):
        mine = np.asarray(getattr(again, key))
        tol = RELATIVE_TOLERANCE * _scale(mine)
        _compare(f"samples.{key}", getattr(samples, key), mine, tol, unit + suffix, times, names)
    angles = _rotation_angles(
        np.asarray(samples.base_quaternion_xyzw, dtype=float),
        np.asarray(again.base_quaternion_xyzw),
    )
    _compare("samples.base_quaternion_xyzw", angles, 0.0 * angles, attitude_tol, "rad", times)
    stated = np.radians(np.asarray(samples.base_zyx_deg, dtype=float))
    angles = np.array(
        [
            geodesic_angle(quat_from_zyx(*row), np.asarray(quat))
            for row, quat in zip(stated, again.base_quaternion_xyzw, strict=True)
        ]
    )
    _compare("samples.base_zyx_deg", angles, 0.0 * angles, attitude_tol, "rad", times)
    positions = np.asarray(again.base_position), np.asarray(again.end_effector_position)
    size = _scale(*positions)
    for key, mine in zip(("base_position", "end_effector_position"), positions, strict=True):
        tol = RELATIVE_TOLERANCE * size + estimate * _scale(mine)
        _compare(f"samples.{key}", getattr(samples, key), mine, tol, "m", times, _AXES)
    for frame, path in again.end_effector_paths.items():  # every end effector (format 4)
        mine = np.asarray(path)
        tol = RELATIVE_TOLERANCE * _scale(np.asarray(again.base_position), mine)
        tol += estimate * _scale(mine)
        theirs = samples.path_of(frame)
        _compare(f"samples.end_effector_paths.{frame}", theirs, mine, tol, "m", times, _AXES)
    torque_unit = _unit(kinds, "N m", "N")
    for key, mine, label, columns in (
        ("base_angular_velocity", again.base_angular_velocity, "rad/s", _AXES),
        ("tau", again.tau, torque_unit, names),
    ):
        theirs = getattr(samples, key)
        if len(theirs):  # absent from files written before these were recorded
            tol = RELATIVE_TOLERANCE * _scale(np.asarray(mine))
            _compare(f"samples.{key}", theirs, mine, tol, label, times, columns)

    # The solver's report: what can be recomputed.
    solver = plan.solver
    chosen = float(np.linalg.norm(problem.residual(beta)))
    _compare(
        "solver.residual_rad", solver.residual_rad, chosen, RESIDUAL_TOLERANCE + estimate, "rad"
    )
    _compare(
        "solver.integration_error_rad",
        solver.integration_error_rad,
        estimate,
        RELATIVE_TOLERANCE + 0.5 * estimate,
        "rad",
    )
    for i, root in enumerate(solver.solutions):
        free = [root.free_parameters[name] for name in names]
        if i == 0:
            for name in names:
                field = f"solver.solutions[0].free_parameters.{name}"
                _compare(field, root.free_parameters[name], plan.free_parameters[name], 0.0)
        beta_i = root_beta(plan, problem.family, free)
        residual = float(np.linalg.norm(problem.residual(beta_i)))
        root_estimate = problem.integration_error(beta_i)
        _compare(
            f"solver.solutions[{i}].residual_rad",
            root.residual_rad,
            residual,
            RESIDUAL_TOLERANCE + root_estimate,
            "rad",
        )
        length = problem.path_length(beta_i)
        _compare(
            f"solver.solutions[{i}].path_length",
            root.path_length,
            length,
            RESIDUAL_TOLERANCE * max(1.0, length),
            unit,
        )
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
    check_objective(plan, problem, beta)
    _check_robustness(plan, problem, beta)
    return problem


def _check_robustness(plan: Plan, problem: Problem, beta: np.ndarray) -> None:
    """Recompute the ``robustness`` record (format 4, optional) for its stated uncertainty.

    The figures come from the exact sensitivity on the plan's grid and, for the worst case, a
    vertex search; both are deterministic, so :data:`ROBUSTNESS_TOLERANCE` of the figure is
    rounding with a wide margin.
    """
    record = plan.robustness
    if record is None:
        return
    try:
        uncertainty = Uncertainty(record.mass_fraction, record.com_m, record.inertia_fraction)
    except FreeFloatError as exc:
        raise PlanMismatchError("robustness", math.inf, 0.0, message=str(exc)) from None
    found = spread(attitude_sensitivity(problem, beta), uncertainty)
    for key, value in (("rms_rad", found.rms), ("worst_rad", found.worst)):
        tolerance = ROBUSTNESS_TOLERANCE * value + 1e-15
        _compare(f"robustness.{key}", getattr(record, key), value, tolerance, "rad")


def compare_verification(stored: Verification, recomputed: Verification) -> None:
    """Compare a plan file's verification figures with their recomputation.

    Nothing to compare when the file has none (format 1, or a plan not yet verified).

    Raises:
        PlanMismatchError: a check missing, added or reordered, or a figure that disagrees.
    """
    if not stored.checks:
        return
    mine = [c.name for c in recomputed.checks]
    theirs = [c.name for c in stored.checks]
    if mine != theirs:
        raise PlanMismatchError(
            "verification.checks",
            math.inf,
            0.0,
            message=f"the file lists {', '.join(theirs)}; the recomputation {', '.join(mine)}",
        )
    for i, (s, r) in enumerate(zip(stored.checks, recomputed.checks, strict=True)):
        field = f"verification.checks[{i}]"
        if s.unit != r.unit:
            raise PlanMismatchError(
                f"{field}.unit", math.inf, 0.0, message=f"{s.unit!r} stored, {r.unit!r} recomputed"
            )
        slack = FIGURE_FRACTION * r.tolerance
        _compare(
            f"{field}.tolerance", s.tolerance, r.tolerance, RELATIVE_TOLERANCE * r.tolerance, r.unit
        )
        _compare(f"{field}.value", s.value, r.value, slack + 2.0 * r.error_estimate, r.unit)
        _compare(
            f"{field}.error_estimate",
            s.error_estimate,
            r.error_estimate,
            slack + r.error_estimate,
            r.unit,
        )
