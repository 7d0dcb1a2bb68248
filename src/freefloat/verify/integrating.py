"""The checks of a plan that integrate: its attitude, and a forward-dynamics replay.

Both integrate by Butcher's fifth-order Runge-Kutta method (:data:`METHOD`,
:mod:`freefloat.physics.runge_kutta`), not the planner's Magnus scheme:

- ``attitude_independent``: the final attitude (rad from the target) from the quaternion ODE
  in seconds along the file's paths, with Pinocchio's centroidal map for the base rate.
- ``replay_attitude``, ``replay_joints``: forward dynamics of the free system (ABA) driven
  only by the planned joint torques from the start at rest: final attitude error (rad) and
  joint error (rad or m; continuous joints wrapped).

Both double their steps and report the difference between the last two results as their
``error_estimate``; they refine until their verdict stands whatever that error, or the estimate
is below :data:`~freefloat.verify.stepping.CONVERGED_FRACTION` of the tolerance
(:mod:`freefloat.verify.stepping`). A replay the allowed steps cannot resolve says so in its
``detail`` and reports an estimate at least its value: no verdict.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..physics.attitude import geodesic_angle
from ..physics.replay import replay
from ..plans.guarantees import Check
from ..robot.model import Robot
from . import stepping
from .plan_checks import TOLERANCES, Subject
from .segmented import SEGMENTED, segmented_replay
from .stepping import (
    _FIRST_ATTITUDE_STEPS,
    _FIRST_REPLAY_STEPS,
    _MAX_ATTITUDE_STEPS,
    AttitudeLevel,
    _decided,
    _finite,
    _refine,
    attitude_by_doubling,
    motion_speed,
    perturbed_torques,
    wrapped_joints,
)

__all__ = ["INTEGRATING_CHECKS", "METHOD", "attitude_check", "integrating_checks", "replay_checks"]

#: The integrator the checks name in their ``detail`` (``"RK5, 32 steps"``); a file whose
#: checks name another (``RK4`` before this version) states figures of that integrator.
METHOD = "RK5"
#: The checks this module makes.
INTEGRATING_CHECKS = ("attitude_independent", "replay_attitude", "replay_joints")


def integrating_checks(subject: Subject) -> list[Check]:
    """``attitude_independent``, ``replay_attitude``, ``replay_joints``, in that order.

    The replay runs first: the base angular velocity its torques come with
    (:class:`~freefloat.verify.along.PathDynamics`) serves the attitude check at those instants.
    """
    replayed = replay_checks(subject)
    return attitude_check(subject) + replayed


def attitude_check(subject: Subject) -> list[Check]:
    """``attitude_independent``: the quaternion ODE in seconds (:data:`METHOD`), step doubling."""
    plan = subject.plan
    duration = plan.duration
    start_quat = np.asarray(plan.base.start_quaternion_xyzw, dtype=float)
    target = np.asarray(plan.base.target_quaternion_xyzw, dtype=float)
    tolerance = TOLERANCES["attitude_independent_rad"]

    def settled(level: AttitudeLevel) -> bool:
        value = geodesic_angle(level.attitude, target)
        return _decided(value, level.estimate, level.previous, tolerance, level.turn)

    level = attitude_by_doubling(
        start_quat,
        subject.dynamics.omega,
        duration,
        _FIRST_ATTITUDE_STEPS,
        _MAX_ATTITUDE_STEPS,
        settled,
    )
    value, estimate = geodesic_angle(level.attitude, target), level.estimate
    detail = f"{METHOD}, {level.steps} steps"
    return [Check("attitude_independent", value, tolerance, "rad", estimate, detail)]


@dataclass(frozen=True)
class _Replay:
    """The last level of a replay: its figures, estimates, steps and whether it converged.

    ``moved``: how far its end moved with the torques perturbed (attitude rad, joints rad or
    m; included in the estimates), when it was asked (before a refusal), else None.
    """

    attitude: float
    joints: float
    attitude_estimate: float
    joint_estimate: float
    steps: int
    converged: bool
    moved: tuple[float, float] | None = None


def replay_checks(subject: Subject) -> list[Check]:
    """``replay_attitude`` and ``replay_joints``: forward dynamics from the start at rest.

    When the replay over the whole motion cannot decide (it does not converge within its
    steps, blows up, or its end moves as far when its torques are perturbed by their own
    assumed error), it is made again in segments, each from the path's state at its start
    (:mod:`.segmented`); their figures stand when they converge, and the detail says that
    they are a segmented replay's and why.
    """
    level = _replay(subject)
    checks = _from_rest(level)
    if level.converged and all(c.verdict != "no verdict" for c in checks):
        return checks
    pieces = segmented_replay(subject)
    if not pieces.converged:
        return checks
    why = (
        f"{level.steps} steps did not converge"
        if not level.converged
        else f"its end moves as far with its torques perturbed by {stepping.TORQUE_PERTURBATION:g}"
    )
    return _checks(
        (pieces.attitude, pieces.joints),
        (pieces.attitude_estimate, pieces.joint_estimate),
        f"{METHOD} in {pieces.segments}{SEGMENTED}{pieces.steps} steps, each from the path's "
        f"state at its start, figures scaled to the whole motion (from rest, {why}: open "
        "loop, the replay amplifies its own error)",
    )


def _from_rest(level: _Replay) -> list[Check]:
    """The replay checks from the replay over the whole motion from rest (its last level)."""
    att_estimate, joint_estimate = level.attitude_estimate, level.joint_estimate
    detail = f"{METHOD}, {level.steps} steps"
    if not level.converged:
        # The steps allowed do not resolve this motion (a long, fast or sensitive one): the
        # difference bounds nothing, and the replay cannot tell its error from the value.
        # A coarser level that blew up differs by inf: the value itself is then the bound,
        # so the file holds finite numbers. At least the tolerance too: the check's verdict
        # is then "no verdict", never "ok" (a last level that blew up has no value: it fails).
        att_tolerance, joint_tolerance = (
            TOLERANCES["replay_attitude_rad"],
            TOLERANCES["replay_joint"],
        )
        att_estimate = max(
            att_estimate if math.isfinite(att_estimate) else 0.0, level.attitude, att_tolerance
        )
        joint_estimate = max(
            joint_estimate if math.isfinite(joint_estimate) else 0.0, level.joints, joint_tolerance
        )
        if math.isfinite(level.attitude) and math.isfinite(level.joints):
            detail += ", not converged: no verdict"
        else:  # no figure at all: not a number fails (Check.passed), and says why
            detail += ", not converged: its last level blew up (not a number)"
    if level.moved is not None:
        detail += (
            f", torques perturbed by {stepping.TORQUE_PERTURBATION:g} of their largest move its "
            f"end by {level.moved[0]:.2g} rad, {level.moved[1]:.2g} (joints)"
        )
    return _checks((level.attitude, level.joints), (att_estimate, joint_estimate), detail)


def _checks(
    values: tuple[float, float], estimates: tuple[float, float], detail: str
) -> list[Check]:
    """The two replay checks: (attitude rad, joints rad or m) with their estimates."""
    return [
        Check(
            "replay_attitude",
            values[0],
            TOLERANCES["replay_attitude_rad"],
            "rad",
            estimates[0],
            detail,
        ),
        Check(
            "replay_joints", values[1], TOLERANCES["replay_joint"], "rad|m", estimates[1], detail
        ),
    ]


def _replay(subject: Subject) -> _Replay:
    """Replay on doubling steps until both verdicts stand or the steps allowed run out."""
    plan, mmap, robot = subject.plan, subject.mmap, subject.robot
    duration, start, goal = plan.duration, subject.start, subject.goal
    start_quat = np.asarray(plan.base.start_quaternion_xyzw, dtype=float)
    target = np.asarray(plan.base.target_quaternion_xyzw, dtype=float)

    def run(steps: int, table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        result = replay(mmap, start, start_quat, table, duration, steps, False)
        return result.quaternion_xyzw, result.joints

    # the torques at k duration / (4 steps), each level reusing the instants of the last;
    # the first three levels' in one batch (the second always runs when the steps allow it,
    # and the third unless the first difference is below rounding: a motion that barely moves)
    steps = min(_FIRST_REPLAY_STEPS, subject.replay_steps)
    batch = steps
    for _ in range(2):
        batch = 2 * batch if 2 * batch <= subject.replay_steps else batch
    subject.dynamics.torques(np.linspace(0.0, duration, 4 * batch + 1))
    torques = _refine(None, steps, duration, subject.dynamics.torques)
    coarse_q, coarse_j = run(steps, torques)
    replay_att = geodesic_angle(coarse_q, target)
    replay_joint = float(np.abs(wrapped_joints(robot, coarse_j - goal)).max())
    speed = motion_speed(plan)
    att_estimate = joint_estimate = math.inf
    previous = earlier = (math.inf, math.inf)  # the last two differences (attitude, joints)
    while 2 * steps <= subject.replay_steps:
        steps *= 2
        torques = _refine(torques, steps, duration, subject.dynamics.torques)
        fine_q, fine_j = run(steps, torques)
        replay_att = geodesic_angle(fine_q, target)
        replay_joint = float(np.abs(wrapped_joints(robot, fine_j - goal)).max())
        att_estimate = _finite(geodesic_angle(coarse_q, fine_q))
        joint_estimate = _finite(float(np.abs(wrapped_joints(robot, fine_j - coarse_j)).max()))
        turn = speed * duration / steps
        attitude_settled = _decided(
            replay_att,
            att_estimate,
            previous[0],
            TOLERANCES["replay_attitude_rad"],
            turn,
            earlier[0],
        )
        if attitude_settled and _decided(
            replay_joint, joint_estimate, previous[1], TOLERANCES["replay_joint"], turn, earlier[1]
        ):
            moved = None
            if (
                replay_att - att_estimate > TOLERANCES["replay_attitude_rad"]
                or replay_joint - joint_estimate > TOLERANCES["replay_joint"]
            ):  # a refusal: unless the inputs' own error could move the end that far
                moved = _moved(run, steps, torques, (fine_q, fine_j), robot)
                att_estimate, joint_estimate = att_estimate + moved[0], joint_estimate + moved[1]
            return _Replay(
                replay_att, replay_joint, att_estimate, joint_estimate, steps, True, moved
            )
        coarse_q, coarse_j = fine_q, fine_j
        earlier, previous = previous, (att_estimate, joint_estimate)
    return _Replay(replay_att, replay_joint, att_estimate, joint_estimate, steps, False)


def _moved(
    run: Callable[[int, np.ndarray], tuple[np.ndarray, np.ndarray]],
    steps: int,
    torques: np.ndarray,
    end: tuple[np.ndarray, np.ndarray],
    robot: Robot,
) -> tuple[float, float]:
    """How far the replay's ``end`` (attitude, joints) moves when its torques are perturbed.

    Each joint's torques are offset by :data:`~.stepping.TORQUE_PERTURBATION` of its largest
    (:func:`~.stepping.perturbed_torques`): about a thousand times their own rounding. A motion
    whose open-loop replay amplifies that much (a light wrist on a heavy spacecraft over a
    long time) cannot tell a plan's error from its inputs' rounding. Returns the attitude's
    move (rad) and the largest joint's (rad or m).
    """
    attitude, joints = run(steps, perturbed_torques(torques))
    return (
        _finite(geodesic_angle(attitude, end[0])),
        _finite(float(np.abs(wrapped_joints(robot, joints - end[1])).max())),
    )
