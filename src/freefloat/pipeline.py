"""The planning pipeline: scenario -> problem -> solution -> sampled, verified plan.

:func:`plan` is the whole call: resolve the scenario (compose an inline servicer's URDF into
its cache, solve a Cartesian goal), search for a solution within the constraints, sample it,
compute the torques and verify the result independently. :func:`plan_from_solution` samples and
verifies a solution found elsewhere. The file format lives in :mod:`freefloat.plans`.
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import asdict, replace

import numpy as np

from ._blas import one_blas_thread
from .errors import (
    SolverError,
    VerificationError,
)
from .physics.attitude import geodesic_angle
from .plans.format import Plan
from .plans.guarantees import ObjectiveReport, SafetyReport
from .plans.records import PathQuality, Request, RobotRef, Samples, SolverReport, sha256_hex
from .plans.reports import (
    as_rebuilt,
    check_registered,
    constraint_records,
    norm_report,
    objective_report,
    safety_report,
)
from .plans.sampling import (
    base_report,
    feasibility_report,
    path_quality,
    sample_solution,
    solution_record,
)
from .problem.constraints import (
    Constraint,
    default_constraints,
    scenario_constraints,
)
from .problem.endpoints import check_end_attitudes, check_endpoints
from .problem.limits import check_samples
from .problem.objectives import DEFAULT_OBJECTIVE, Objective, objective_named
from .problem.paths import boundary_errors
from .problem.residual import Problem
from .problem.scenario import Scenario, scenario_of
from .progress import LOGGER, stage
from .robot.light_base import warn_light_base, warn_unphysical
from .robot.model import Robot
from .solvers.lazy_search import broken_by, explain_lazy_breaks, search_lazily
from .solvers.minimise import minimise
from .solvers.nearest import nearest_root
from .solvers.options import DEFAULT_TOLERANCE, Solution, SolveOptions
from .verify.checks import verify_plan

__all__ = ["BOUNDARY_TOLERANCE", "SPIN_WARNING", "plan", "plan_from_solution"]

#: Boundary conditions must hold to this (rad, rad/s, rad/s^2; relative to the joint travel).
BOUNDARY_TOLERANCE = 1e-9


def plan(
    scenario: Scenario | str | os.PathLike,
    options: SolveOptions | None = None,
    samples: int = 201,
    constraints: Sequence[Constraint] | None = None,
    objective: str | Objective | None = None,
) -> Plan:
    """Plan the scenario's motion and sample it (BLAS on one thread meanwhile: :mod:`._blas`).

    Args:
        scenario: what to plan (or the path of its TOML file).
        options: solver settings; the scenario's ``max_deviation`` overrides the default
            bracket.
        samples: number of equally spaced samples in [0, T] (2 to
            :data:`~freefloat.problem.limits.MAX_SAMPLES`).
        constraints: path constraints to honour (solvers and verification); default the
            scenario's (:func:`~freefloat.problem.constraints.scenario_constraints`: joint
            position, velocity and effort limits, its ``[constraints.<name>]`` tables, and
            clearance when checked). Each is recorded in the plan for ``freefloat verify``.
        objective: which path is best among those that reach the goal: an objective, or the
            name of one in :data:`~freefloat.problem.objectives.OBJECTIVES`; default the
            scenario's ``[path] objective``.

    Raises:
        FreeFloatError: any subclass: bad input, infeasible request, no solution.
        VelocityLimitError: no path within the velocity limits at this duration; carries the
            shortest duration at which the path found without them respects them.
        EffortLimitError: the same for the effort limits.
    """
    scenario = scenario_of(scenario)
    with one_blas_thread():
        return _plan(scenario, options, samples, constraints, objective)


def _plan(
    scenario: Scenario,
    options: SolveOptions | None,
    samples: int,
    constraints: Sequence[Constraint] | None,
    objective: str | Objective | None,
) -> Plan:
    """:func:`plan`'s work."""
    check_samples(samples)
    options = options or SolveOptions()
    if scenario.max_deviation is not None:
        options = SolveOptions(**{**asdict(options), "max_deviation": scenario.max_deviation})
    chosen_goal = bool(scenario.goal_poses)  # goal joints from inverse kinematics
    scenario = scenario.resolved()
    scenario.write_robot()  # an inline servicer or a payload: its URDF, into the cache
    constraints = scenario_constraints(scenario) if constraints is None else list(constraints)
    chosen = (
        objective
        if isinstance(objective, Objective)
        else objective_named(objective or scenario.objective)
    )
    check_registered(chosen, constraints)  # what verify could not rebuild: before any work
    check_endpoints(scenario, constraints, chosen_goal)
    check_end_attitudes(scenario, constraints)
    warn_light_base(scenario.robot)
    warn_unphysical(scenario.robot)
    clock = time.perf_counter()
    with stage("solve"):
        # another objective's freedom may find a path within limits the search's path breaks
        found, imposed = search_lazily(
            scenario, options, constraints, keep_broken=chosen.name != DEFAULT_OBJECTIVE
        )
    searched_norm = float(found.solution.beta @ found.solution.beta)
    if not found.problem.planar and scenario.raise_freedom:
        with stage("nearest root"):  # every objective starts from a natural path
            keep = constraints if chosen.name == DEFAULT_OBJECTIVE else imposed
            nearest = nearest_root(scenario, found, options, keep)
            found = replace(nearest.found, tried=[*found.tried, *nearest.tried])
    if chosen.name != DEFAULT_OBJECTIVE:
        with stage(f"minimise {chosen.name}"):
            minimised = minimise(scenario, found, chosen, options, imposed)
            left_out = [c for c in constraints if c not in imposed]
            if left_out and broken_by(minimised.found, left_out):
                again = minimise(scenario, minimised.found, chosen, options, constraints)
                if broken_by(again.found, left_out):  # from the search's own path instead
                    again = minimise(scenario, found, chosen, options, constraints)
                minimised = replace(
                    again,
                    start_value=minimised.start_value,
                    levels=minimised.levels + again.levels,
                )
        found = minimised.found
        explain_lazy_breaks(found, [c for c in constraints if c.lazy])
        report = objective_report(minimised)
    else:
        report = replace(norm_report(found.problem, found.solution.beta), start_value=searched_norm)
    solve_time = time.perf_counter() - clock
    problem = found.problem.with_steps(found.solution.steps)
    with stage("sample and verify"):
        result = plan_from_solution(
            problem,
            found.solution,
            samples,
            options.tolerance,
            constraints=constraints,
            safety=safety_report(scenario, constraints),
            objective=report,
        )
    solver = replace(
        result.solver,
        freedom=found.freedom,
        full_turns=found.full_turns,
        tried=found.tried,
        solve_time_s=solve_time,
    )
    if result.quality is not None:
        _warn_spinning(result.quality, scenario.robot, chosen.name)
    return replace(result, solver=solver)


#: The warning of a path that turns a joint a full turn or more beyond its span (its format:
#: objective, turns, advice); a sweep says it once for all its jobs (:mod:`freefloat.sweep`).
SPIN_WARNING = (
    "the path (objective %s) turns a joint a full turn or more beyond its start-goal span (%s "
    "turns): if the real joint cannot turn freely (cables, hard stops), give it limits in the "
    "URDF%s"
)


def _warn_spinning(quality: PathQuality, robot: Robot, objective: str) -> None:
    """Warn when a turning joint goes a full turn or more beyond its start-goal span (deg).

    Legal for a joint without limits (``continuous``, or limits wider than a turn), and what an
    objective may find cheapest (``min_effort`` on ETS-VII spun its wrist 16 turns); a real
    joint's cables seldom allow it.
    """
    kinds = {joint.name: joint.kind for joint in robot.joints}
    spun = {
        name: beyond / 360.0
        for name, beyond in quality.excursion_beyond_span.items()
        if kinds.get(name) != "prismatic" and beyond >= 360.0
    }
    if spun:
        turns = ", ".join(f"{name!r} {value:.3g}" for name, value in spun.items())
        other = "" if objective == DEFAULT_OBJECTIVE else ", or plan with the default objective"
        LOGGER.warning(SPIN_WARNING, objective, turns, other)


def plan_from_solution(
    problem: Problem,
    solution: Solution,
    samples: int = 201,
    tolerance: float = DEFAULT_TOLERANCE,
    verify: bool = True,
    constraints: Sequence[Constraint] | None = None,
    safety: SafetyReport | None = None,
    objective: ObjectiveReport | None = None,
) -> Plan:
    """Sample a solved problem into a verified :class:`Plan`.

    Args:
        problem: the solved problem.
        solution: its solution.
        samples: number of equally spaced samples in [0, T].
        tolerance: attitude tolerance (rad).
        verify: run the independent checks of :mod:`freefloat.verify` (a plan from
            :func:`plan` always is).
        constraints: path constraints verification checks, recorded in the plan; default
            joint position, velocity and effort limits.
        safety: the plan's record of its clearance constraint (default: none checked).
        objective: the plan's record of what it minimised (default: the minimum norm).

    Raises:
        SolverError: the attitude reached (by the solver's grid or by the sampling grid) is
            farther than ``tolerance`` (rad) from the goal, or a boundary condition fails.
        VerificationError: an independent check fails.
    """
    robot, family = problem.robot, problem.family
    clock = time.perf_counter()
    sampled = sample_solution(problem, solution.beta, samples)
    sample_time = time.perf_counter() - clock
    base = base_report(problem, solution.beta)
    _check_reached(problem, solution.beta, base.attitude_error_rad, sampled, tolerance)
    chosen = solution_record(problem, solution.beta, solution.residual, 0.0)
    unverified = Plan(
        robot=_robot_ref(robot),
        duration=problem.duration,
        coefficients={name: list(values) for name, values in chosen.free_parameters.items()},
        free_parameters=chosen.free_parameters,
        base=base,
        feasibility=feasibility_report(problem),
        samples=sampled,
        solver=_solver_report(problem, solution, sample_time),
        request=Request(start_joints=family.start.tolist(), goal_joints=family.goal.tolist()),
        safety=safety or SafetyReport(),
        objective=objective or norm_report(problem, solution.beta),
        constraints=constraint_records(
            default_constraints() if constraints is None else constraints
        ),
        quality=path_quality(problem, solution.beta),
    )
    if not verify:
        return unverified
    clock = time.perf_counter()
    verification = verify_plan(
        unverified,
        robot,
        constraints=None if constraints is None else as_rebuilt(constraints),
        recompute=False,  # the numbers were just computed by the same functions
    )
    if not verification.passed:
        failed = [c for c in verification.checks if not c.passed]
        raise VerificationError(
            [c.name for c in failed],
            [
                f"{c.value:.4g} {c.unit} against a tolerance of {c.tolerance:.2g}"
                + (f" and its own error {c.error_estimate:.2g}" if c.error_estimate else "")
                + (f", {c.detail}" if c.detail else "")
                for c in failed
            ],
        )
    report = replace(unverified.solver, verify_time_s=time.perf_counter() - clock)
    return replace(unverified, verification=verification, solver=report)


def _check_reached(
    problem: Problem, beta: np.ndarray, error: float, sampled: Samples, tolerance: float
) -> None:
    """Raise :class:`SolverError` when the path misses its target.

    ``error``: the attitude error on the solver's grid (rad); the sampling grid's last
    attitude must be within ``tolerance`` (rad) too, and the boundary conditions hold.
    """
    sampled_error = geodesic_angle(
        np.asarray(sampled.base_quaternion_xyzw[-1]), problem.goal_quaternion
    )
    family = problem.family
    boundary = boundary_errors(problem.polynomials(beta), family.start, family.goal)["relative_max"]
    if max(error, sampled_error) > tolerance or boundary > BOUNDARY_TOLERANCE:
        raise SolverError(
            "the planned path misses its target (attitude error "
            f"{max(error, sampled_error):.3g} rad, boundary error {boundary:.3g})",
            max(error, sampled_error),
        )


def _robot_ref(robot: Robot) -> RobotRef:
    """The plan's record of its robot (the URDF text and its digest included)."""
    return RobotRef(
        urdf=str(robot.urdf),
        joints=robot.joint_names,
        end_effector=robot.end_effector,
        joint_kinds=[j.kind for j in robot.joints],
        end_effectors=list(robot.end_effectors),
        urdf_text=robot.urdf_text,
        urdf_sha256=sha256_hex(robot.urdf_text),
    )


def _residual(problem: Problem, beta: np.ndarray) -> float:
    """The norm of the attitude residual at ``beta`` on the problem's grid (rad).

    The chosen root's is the solver's, certified on that grid; another root may have been
    found on a coarser one (a wild path's differed by 3.9e-9 rad, beyond verify's 1e-9).
    """
    return float(np.linalg.norm(problem.residual(beta)))


def _solver_report(problem: Problem, solution: Solution, sample_time: float) -> SolverReport:
    """The plan's record of the solve (``sample_time``: the sampling's wall time, s)."""
    return SolverReport(
        method=solution.method,
        iterations=solution.iterations,
        evaluations=solution.evaluations,
        residual_rad=solution.residual,
        wall_time_s=solution.wall_time,
        solutions=[  # the others' residuals on the plan's own grid, as verification's
            solution_record(
                problem,
                root.beta,
                root.residual if k == 0 else _residual(problem, root.beta),
                root.path_length,
            )
            for k, root in enumerate(solution.roots)
        ],
        integration_steps=problem.steps,
        integration_error_rad=solution.integration_error,
        strategy=solution.strategy,
        solve_time_s=solution.wall_time,
        sample_time_s=sample_time,
    )
