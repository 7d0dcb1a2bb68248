"""Independent verification of a plan, from the plan file alone: the list of its checks.

:func:`verify_plan` first recomputes every number of the plan (:mod:`.recompute`), then runs
the checks of :data:`PLAN_CHECKS`, each a function of a
:class:`~freefloat.verify.plan_checks.Subject` returning typed
:class:`~freefloat.plans.guarantees.Check` records with their own error estimates, in the order
the plan file lists them:

- ``momentum``, ``cm_offset``, ``base_wrench``, ``boundary``, ``samples``: exact up to rounding
  (:mod:`freefloat.verify.plan_checks`);
- ``attitude_independent``, ``replay_attitude``, ``replay_joints``: integrating, with step
  doubling (:mod:`freefloat.verify.integrating`);

then one check per constraint the plan honours, rebuilt from the registry
(:func:`plan_constraints`): each constraint's own ``excess`` (``joint_position_limits``...), and
clearance's certificate (:mod:`freefloat.verify.clearance_check`). Last, the figures are
compared with those the plan states, if it states any.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..errors import FreeFloatError, InputError, PlanFileError, PlanMismatchError
from ..physics.dynamics import inverse_dynamics
from ..physics.momentum import MomentumMap
from ..plans.format import Plan
from ..plans.guarantees import Check, Verification
from ..plans.robot_copy import plan_robot
from ..plans.versions import FORMAT_2, FORMAT_3, URDF_LIMITS
from ..problem.constraints import Constraint, JointEffortLimits, constraint_from_record
from ..problem.constraints.clearance import Clearance
from ..problem.constraints.registry import clearance_constraint
from ..robot.model import Robot
from .clearance_check import clearance_checks
from .integrating import INTEGRATING_CHECKS, integrating_checks
from .path_eval import file_path
from .plan_checks import (
    PlanCheck,
    Subject,
    base_wrench_check,
    boundary_check,
    momentum_checks,
    samples_check,
)
from .recompute import check_plan_numbers, compare_verification
from .segmented import segment_count
from .stepping import MAX_REPLAY_STEPS

__all__ = [
    "PLAN_CHECKS",
    "REPLAY_STEPS_LIMIT",
    "check_replay_steps",
    "constraint_checks",
    "joint_torque_function",
    "plan_constraints",
    "require_verified",
    "verify_plan",
]

#: The most replay steps a caller may allow (``--replay-steps``): 65536 Runge-Kutta steps.
REPLAY_STEPS_LIMIT = 1 << 16

#: Every check of a plan, in the order its file lists them (before one per constraint).
PLAN_CHECKS: tuple[PlanCheck, ...] = (
    momentum_checks,  # momentum, cm_offset
    base_wrench_check,
    integrating_checks,  # attitude_independent, replay_attitude, replay_joints
    boundary_check,
    samples_check,
)

#: Checks an older file cannot state as they are made now: effort (a /2 file predates it) and
#: clearance (before format 4: sampled on the meshes' own faces). Their stated figures are not
#: compared; the checks made now still decide whether the plan passes.
_CLEARANCE_CHECKS = ("clearance", "clearance_hull_agreement")
_PREDATED: dict[str, tuple[str, ...]] = {
    FORMAT_2: (JointEffortLimits.name, *_CLEARANCE_CHECKS),
    FORMAT_3: _CLEARANCE_CHECKS,
}


def joint_torque_function(plan: Plan, mmap: MomentumMap) -> Callable[[float], np.ndarray]:
    """``tau(t)``: joint torques (N m or N) of the plan at any time t (s), from its polynomials."""
    path = file_path(plan)

    def tau(t: float) -> np.ndarray:
        q, qd, qdd = (x[0] for x in path(np.array([t])))
        return inverse_dynamics(mmap, q, qd, qdd).tau

    return tau


def plan_constraints(plan: Plan, robot: Robot) -> list[Constraint]:
    """The constraints a plan states it honours, rebuilt from the registry by their records.

    Every ``constraints`` record, and clearance when its ``safety`` record says it was checked.
    A file written before constraint records is held to what its format promised
    (:data:`~freefloat.plans.versions.PROMISED`). Every plan is held to the URDF's limits
    (:data:`~freefloat.plans.versions.URDF_LIMITS`) whether its records name them or not: a
    file whose ``constraints`` list was emptied still answers to them.

    Raises:
        PlanFileError: a record names a constraint this freefloat does not know, or a bad
            parameter.
    """
    constraints = []
    for i, record in enumerate(plan.constraints):
        try:
            constraints.append(constraint_from_record(record.name, record.parameters))
        except FreeFloatError as exc:
            raise PlanFileError(f"plan field 'constraints[{i}]': {exc}") from None
    named = {record.name for record in plan.constraints}
    constraints += [constraint_from_record(n, {}) for n in URDF_LIMITS if n not in named]
    if plan.safety.checked:
        clearance = clearance_constraint(
            robot, plan.safety.srdf, plan.safety.obstacles, plan.safety.margin_m
        )
        if clearance is not None:
            constraints.append(clearance)
    return constraints


def check_replay_steps(steps: int, name: str = "replay_steps") -> None:
    """Refuse a replay cap outside 1 to :data:`REPLAY_STEPS_LIMIT` (``name`` for messages).

    Raises:
        InputError: ``steps`` below 1 or above the limit.
    """
    if steps < 1:
        raise InputError(f"{name} must be at least 1, got {steps}")
    if steps > REPLAY_STEPS_LIMIT:
        raise InputError(f"{name} must be at most {REPLAY_STEPS_LIMIT}, got {steps}")


def verify_plan(
    plan: Plan,
    robot: Robot | None = None,
    replay_steps: int = MAX_REPLAY_STEPS,
    constraints: list[Constraint] | None = None,
    recompute: bool = True,
) -> Verification:
    """Run every check on ``plan``; needs only the plan and its URDF.

    First every number of the plan is recomputed from its URDF, duration and coefficients and
    compared (:mod:`freefloat.verify.recompute`); then the checks run; then their figures are
    compared with those the plan states, if it states any.

    The two integrating checks estimate their own error by step doubling (the difference
    between the results on M and 2 M steps, which bounds the error of the finer one while the
    scheme converges) and refine until their verdict stands whatever that error, or their
    estimate is below :data:`~freefloat.verify.stepping.CONVERGED_FRACTION` of the tolerance.
    Each reports the finer result as its value and the difference as its ``error_estimate``.

    Args:
        plan: the plan (for example from :meth:`Plan.load`).
        robot: the loaded robot, to skip reloading the URDF.
        replay_steps: the most Runge-Kutta steps the forward-dynamics replay may take (>= 1); with
            other than the default, the replay's figures are not compared with the file's
            (made with the default), only judged.
        constraints: path constraints to check densely; default those the plan records
            (:func:`plan_constraints`).
        recompute: recompute and compare the plan's numbers and figures (the pipeline, which
            has just computed them with the same functions, skips it).

    Raises:
        InputError: ``replay_steps`` outside 1 to :data:`REPLAY_STEPS_LIMIT`.
        PlanMismatchError: a stored number or figure disagrees with its recomputation.
        PlanFileError: the plan's robot or request does not match its URDF.
    """
    check_replay_steps(replay_steps)
    robot = robot or plan_robot(plan)
    if recompute:
        check_plan_numbers(plan, robot)
    constraints = plan_constraints(plan, robot) if constraints is None else constraints
    subject = Subject(plan, robot, MomentumMap(robot), file_path(plan), replay_steps)
    checks = [check for plan_check in PLAN_CHECKS for check in plan_check(subject)]
    checks.extend(constraint_checks(subject, constraints))
    verification = Verification(tuple(checks))
    if recompute:
        # An older file states some checks as they were made then (_PREDATED; integrating
        # checks made by RK4: compared within both estimates), and a replay allowed other
        # steps than the file's (the default), or made otherwise (from rest against in
        # segments, or in another number of segments: another quantity), gives other
        # figures: the figures it states otherwise are compared; every check made now
        # decides whether it passes.
        predated = (*_PREDATED.get(plan.format, ()), *_replayed_otherwise(plan, verification))
        if replay_steps != MAX_REPLAY_STEPS:
            predated = (*predated, "replay_attitude", "replay_joints")
        stated = Verification(tuple(c for c in checks if c.name not in predated))
        on_file = Verification(tuple(c for c in plan.verification.checks if c.name not in predated))
        compare_verification(on_file, stated, _made_by_rk4(plan.verification))
    return verification


def _made_by_rk4(stated: Verification) -> frozenset[str]:
    """The integrating checks a file states as classical RK4 found them (an earlier version).

    Their ``detail`` starts ``"RK4, "``: their values are compared within both versions'
    error estimates, not the estimates themselves (:func:`compare_verification`).
    """
    return frozenset(
        c.name
        for c in stated.checks
        if c.name in INTEGRATING_CHECKS and c.detail.startswith("RK4, ")
    )


def _replayed_otherwise(plan: Plan, made: Verification) -> tuple[str, ...]:
    """The replay checks the file states as made another way than now (not compared).

    From rest against in segments, or in another number of segments (a host whose rounding
    decided at another count): the figures of a segmented replay are its defects scaled to
    the whole motion, which differ with the count, so they measure another quantity; the
    ``detail`` says which was made.
    """
    now = {c.name: c.detail for c in made.checks}
    return tuple(
        c.name
        for c in plan.verification.checks
        if c.name in ("replay_attitude", "replay_joints")
        and segment_count(c.detail) != segment_count(now.get(c.name, ""))
    )


def constraint_checks(subject: Subject, constraints: list[Constraint]) -> list[Check]:
    """One check per constraint that applies to the robot (clearance: its certificate's two).

    Each is the constraint's own exact ``excess`` along the plan's path, with its tolerance,
    unit and error estimate.
    """
    checks: list[Check] = []
    path = subject.plan.path()
    for constraint in constraints:
        if isinstance(constraint, Clearance):
            checks.extend(clearance_checks(subject.robot, constraint, subject.path))
        elif constraint.applies_to(subject.robot):
            excess = constraint.excess(subject.robot, path)
            checks.append(
                Check(
                    constraint.name,
                    excess.value,
                    constraint.tolerance,
                    constraint.unit,
                    excess.error_estimate,
                    excess.detail,
                )
            )
    return checks


def require_verified(plan: Plan, label: str, hint: str) -> None:
    """Refuse a plan read from a file that fails verification, before a command uses it.

    ``label``: how the message names the file (its path); ``hint``: what the reader can do.

    Raises:
        PlanFileError: a number disagrees with its recomputation, or a check fails (named).
    """
    try:
        verification = verify_plan(plan)
    except PlanMismatchError as exc:
        raise PlanFileError(f"{label}: {exc}; {hint}") from None
    if not verification.passed:
        failed = ", ".join(verification.failures)
        raise PlanFileError(f"{label}: the plan fails verification ({failed}); {hint}")
