"""Every number of a plan file, recomputed from its URDF, duration and coefficients.

A plan file vouches for every number in it, so ``freefloat verify`` trusts none of them: it
rebuilds the plan's problem from the URDF, the duration, the path coefficients and the stated
start and goal attitudes, recomputes each record with the functions that wrote it
(:mod:`freefloat.plans.sampling`), and raises :class:`~freefloat.errors.PlanMismatchError`
naming the first field that disagrees beyond its tolerance. The order is that of dependence:
``robot``, ``path.coefficients``, ``free_parameters``, ``request``, ``path_quality``, ``base``,
``feasibility``, ``samples`` (t, q, qd, qdd, base pose, end effector, base rate, torques),
``solver`` (residual, integration error, roots, freedom), ``objective``, ``robustness`` (when
present): the path here, the others in :data:`RECORD_CHECKS` (:mod:`.record_checks`,
:mod:`.objective`, :mod:`.path_records`); the verification figures are compared after the
checks have run (:func:`compare_verification`).

Tolerances (:mod:`freefloat.verify.agreement`). The recomputation runs the same deterministic
code on the same numbers (the coefficients round-trip through JSON exactly), so a genuine plan
disagrees with it by rounding alone: about 1e-15 of each quantity's scale (observed up to ~1e-13
for the integrated attitude, which chains thousands of steps). :data:`RELATIVE_TOLERANCE` =
1e-10 of the scale leaves a thousandfold margin over that, on any machine, and still catches a
1e-6 N m change in any torque of a plan whose peak torque is below 1e4 N m. The scale of a field
is its largest recomputed magnitude (positions share the robot's: the largest of base and end
effector). Numbers that depend on the attitude integration also allow the recomputation's own
error estimate (the Magnus scheme on the same grid against twice as many steps), and the planar
bounds their optimiser's accuracy (:data:`BOUNDS_TOLERANCE_DEG`). Attitude residuals of the
solver's roots were computed on the solver's grid before the last refinement, so they are held
to :data:`RESIDUAL_TOLERANCE` (the planner's default attitude tolerance) plus that estimate. A
verification figure must agree with its recomputation to :data:`FIGURE_FRACTION` of its check's
tolerance plus twice the recomputed error estimate.

Not recomputable, and so not checked: the solver's history (method, iterations, evaluations,
wall and stage times, strategy, attempts, whole turns added), the checks' ``detail`` text, and
the safety record, which is input (it changes the clearance check's figure when it matters).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..errors import FreeFloatError, InfeasibleError, PlanFileError, PlanMismatchError
from ..plans.format import Plan
from ..plans.guarantees import Check, Verification
from ..plans.versions import MONOMIAL_BASIS
from ..problem.build import build_problem
from ..problem.residual import Problem
from ..robot.model import Robot
from . import agreement
from .agreement import FIGURE_FRACTION, RELATIVE_TOLERANCE, unit_of
from .objective import check_objective
from .path_records import check_quality, free_counts, root_beta
from .record_checks import (
    Rebuilt,
    check_base,
    check_feasibility,
    check_robustness,
    check_samples,
    check_solver,
)

__all__ = [
    "RECORD_CHECKS",
    "check_plan_numbers",
    "compare_verification",
    "problem_from_plan",
]


def problem_from_plan(plan: Plan, robot: Robot) -> tuple[Problem, np.ndarray]:
    """The plan's problem (on its solver's integration grid) and its free coefficients beta.

    The path family's degrees come from the coefficient lists, beta from them (format 4) or
    from the monomials (older formats, :mod:`.path_records`), the start and goal joints from
    the request (checked against an older format's path first by :func:`check_plan_numbers`).

    Raises:
        PlanFileError: the plan's request cannot be a problem (joints beyond their limits, a
            goal a planar robot cannot reach).
    """
    request = (
        robot,
        np.asarray(plan.request.start_joints, dtype=float),
        np.asarray(plan.request.goal_joints, dtype=float),
        np.asarray(plan.base.start_quaternion_xyzw, dtype=float),
        np.asarray(plan.base.target_quaternion_xyzw, dtype=float),
        plan.duration,
    )
    try:
        try:
            problem = build_problem(*request, extra=free_counts(plan))
        except InfeasibleError:
            # beyond the planar bounds of simple motions: a path that goes back and forth (a
            # correcting loop, whose joints end where they start) is judged on its own checks
            problem = build_problem(*request, extra=free_counts(plan), check_bounds=False)
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
    kinds = [j.kind for j in robot.joints]
    if plan.robot.joint_kinds and list(plan.robot.joint_kinds) != kinds:
        raise PlanMismatchError(
            "robot.joint_kinds",
            math.inf,
            0.0,
            message=f"the file says {plan.robot.joint_kinds}, the URDF has {kinds}",
        )
    _check_path(plan, unit_of(kinds, "rad", "m"))
    rebuilt = Rebuilt(plan, robot, *problem_from_plan(plan, robot))
    for check in RECORD_CHECKS:
        check(rebuilt)
    return rebuilt.problem


def _term_scales(plan: Plan) -> list[float]:
    """Per joint, its path's largest monomial term ``|c_k| T^k`` (at least 1; rad or m)."""
    T = plan.duration
    stored = [np.asarray(plan.coefficients[name], dtype=float) for name in plan.robot.joints]
    return [max(1.0, float(np.max(np.abs(c) * T ** np.arange(len(c))))) for c in stored]


def _check_path(plan: Plan, unit: str) -> None:
    """The path's free parameters and, for monomials, the request they imply."""
    names = list(plan.robot.joints)
    stored = [np.asarray(plan.coefficients[name], dtype=float) for name in names]
    if plan.basis != MONOMIAL_BASIS:  # format 4: the path is the free parameters
        for name, c in zip(names, stored, strict=True):
            tol = RELATIVE_TOLERANCE * max(1.0, float(np.abs(c).max(initial=0.0)))
            agreement.compare(f"free_parameters.{name}", plan.free_parameters[name], c, tol, unit)
        return
    T = plan.duration
    term_scale = _term_scales(plan)
    start = np.array([c[0] for c in stored])
    goal = np.array([np.polynomial.polynomial.polyval(T, c) for c in stored])
    joint_tol = RELATIVE_TOLERANCE * np.array(term_scale)
    for name, c, scale in zip(names, stored, term_scale, strict=True):
        stated_free = plan.free_parameters[name]
        agreement.compare_terms(f"free_parameters.{name}", stated_free, c, 6, T, scale, unit)
    for key, value in (("start_joints", start), ("goal_joints", goal)):
        stated = getattr(plan.request, key)
        agreement.compare(f"request.{key}", stated, value, joint_tol, unit, None, names)


def _check_coefficients(r: Rebuilt) -> None:
    """A monomial path's coefficients, rebuilt from the problem's (format 4: they are beta)."""
    plan = r.plan
    if plan.basis != MONOMIAL_BASIS:
        return
    stored = [np.asarray(plan.coefficients[name], dtype=float) for name in r.names]
    rebuilt = r.problem.polynomials(r.beta).monomials()
    for name, c, again, scale in zip(r.names, stored, rebuilt, _term_scales(plan), strict=True):
        agreement.compare_terms(
            f"path.coefficients.{name}", c, again[: len(c)], 0, plan.duration, scale, r.unit
        )


def _check_quality(r: Rebuilt) -> None:
    """The ``path_quality`` record (:mod:`.path_records`)."""
    check_quality(r.plan, r.problem, r.beta, RELATIVE_TOLERANCE)


def _check_objective(r: Rebuilt) -> None:
    """The ``objective`` record (:mod:`.objective`)."""
    check_objective(r.plan, r.problem, r.beta)


#: The checks of a plan's records on its rebuilt problem, in the order of dependence.
RECORD_CHECKS: tuple[Callable[[Rebuilt], None], ...] = (
    _check_coefficients,
    _check_quality,
    check_base,
    check_feasibility,
    check_samples,
    check_solver,
    _check_objective,
    check_robustness,
)


def compare_verification(
    stored: Verification, recomputed: Verification, other_method: frozenset[str] = frozenset()
) -> None:
    """Compare a plan file's verification figures with their recomputation.

    Nothing to compare when the file has none (format 1, or a plan not yet verified). Checks
    named in ``other_method`` were made by another method than the recomputation's (another
    integrator, or a replay from rest against one in segments): both
    results lie within their own error estimates of the truth, so the value must agree within
    the sum of the two estimates, and the estimates themselves are not compared (a stated
    check that could not tell, "no verdict", states an estimate that covers its value: its
    value says nothing, and the check made now decides).

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
        try:
            _compare_check(f"verification.checks[{i}]", s, r, other_method)
        except PlanMismatchError as exc:  # named by the check, not its index alone
            if exc.where or exc.difference == math.inf:
                raise
            raise PlanMismatchError(
                exc.field, exc.difference, exc.tolerance, exc.unit, f"(the {s.name} check)"
            ) from None


def _compare_check(field: str, s: Check, r: Check, other_method: frozenset[str]) -> None:
    """One stored check ``s`` against its recomputation ``r`` (see :func:`compare_verification`)."""
    if s.unit != r.unit:
        raise PlanMismatchError(
            f"{field}.unit", math.inf, 0.0, message=f"{s.unit!r} stored, {r.unit!r} recomputed"
        )
    slack = FIGURE_FRACTION * r.tolerance
    agreement.compare(
        f"{field}.tolerance", s.tolerance, r.tolerance, RELATIVE_TOLERANCE * r.tolerance, r.unit
    )
    if s.name in other_method:
        allowed = slack + s.error_estimate + r.error_estimate
        agreement.compare(f"{field}.value", s.value, r.value, allowed, r.unit)
        return
    agreement.compare(f"{field}.value", s.value, r.value, slack + 2.0 * r.error_estimate, r.unit)
    agreement.compare(
        f"{field}.error_estimate",
        s.error_estimate,
        r.error_estimate,
        slack + r.error_estimate,
        r.unit,
    )
