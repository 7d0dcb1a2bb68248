"""The forward-dynamics replay in segments, each from the path's own state (multiple shooting).

The replay from rest over the whole motion (:mod:`freefloat.verify.integrating`) shows that
the torques alone drive the system to the goal; but an open-loop replay amplifies its own
error, and on some motions (light links on a heavy spacecraft over tens of seconds, long
chains) no step count within its cap resolves it: it reaches no verdict, or blows up. The
replay is then made again in ``K`` segments of the duration. Each segment starts from the
state the file's path gives at its start (joint values and rates, and the zero-momentum base
twist they come with: :meth:`~freefloat.verify.along.PathDynamics.velocities`), is driven by
the same torques, and its end is compared with the path's state there. Without gravity the
articulated-body algorithm does not depend on the base pose, so each segment turns the base
by a rotation of its own, and the attitude at the end is the start attitude turned by every
segment's in order. The figures:

- ``replay_attitude``: the angle (rad) from that end attitude to the target; its error
  estimate is the angle between the end attitudes of the last two step counts (rotations
  compose isometrically: the segments' errors add at most).
- ``replay_joints``: the largest joint defect at a segment's end (rad or m, continuous joints
  wrapped); its estimate the largest change of a segment's end over the last doubling.

Each level doubles the steps of every segment (from 8) and is decided as the whole replay is
(:func:`~freefloat.verify.stepping._decided`); the segment counts tried are
:data:`SEGMENT_COUNTS`, the steps of all segments together within the replay's cap. What a
segmented replay shows is weaker than a whole one, and the check's detail says which was made:
that the path and its torques satisfy the dynamics over every segment (defects within the
tolerance), not that the torques alone, open loop, would bring the system there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..physics.attitude import geodesic_angle
from ..physics.replay import replay
from .plan_checks import TOLERANCES, Subject
from .stepping import _FIRST_REPLAY_STEPS, _decided, _finite, motion_speed, wrapped_joints

__all__ = ["SEGMENT_COUNTS", "SegmentedReplay", "segmented_replay"]

#: Segment counts tried, in order (a count each): more segments, shorter ones, less amplified.
SEGMENT_COUNTS = (8, 32, 128)


@dataclass(frozen=True)
class SegmentedReplay:
    """The last level of a replay in segments.

    Attributes:
        attitude: angle from the end attitude to the target (rad).
        joints: largest joint defect at a segment's end (rad or m).
        attitude_estimate: its change over the last doubling of the steps (rad).
        joint_estimate: the same for the joint defects (rad or m).
        segments: the number of segments.
        steps: Runge-Kutta steps per segment at the last level (0: none fitted the cap).
        converged: whether both verdicts stand whatever those estimates.
    """

    attitude: float
    joints: float
    attitude_estimate: float
    joint_estimate: float
    segments: int
    steps: int
    converged: bool


@dataclass(frozen=True)
class _Shot:
    """One step count's segments: the end attitude and each segment's end joints."""

    quaternion: np.ndarray
    ends: np.ndarray


def segmented_replay(subject: Subject) -> SegmentedReplay:
    """The replay in :data:`SEGMENT_COUNTS` segments, the first count that converges.

    The last count's level when none does (``converged`` False).
    """
    level = SegmentedReplay(math.nan, math.nan, math.inf, math.inf, SEGMENT_COUNTS[0], 0, False)
    for count in SEGMENT_COUNTS:
        if count * 2 * _FIRST_REPLAY_STEPS > subject.replay_steps:
            break  # not even two levels of this count fit the cap
        level = _doubling(subject, count)
        if level.converged:
            break
    return level


def _doubling(subject: Subject, count: int) -> SegmentedReplay:
    """``count`` segments on doubling steps until both verdicts stand or the cap is reached."""
    plan, robot = subject.plan, subject.robot
    target = np.asarray(plan.base.target_quaternion_xyzw, dtype=float)
    tolerances = (TOLERANCES["replay_attitude_rad"], TOLERANCES["replay_joint"])
    knots = subject.path(np.linspace(0.0, plan.duration, count + 1))[0]
    speed = motion_speed(plan)
    steps = _FIRST_REPLAY_STEPS
    coarse = _shot(subject, count, steps)
    previous = earlier = (math.inf, math.inf)  # the last two differences (attitude, joints)
    figures = (math.nan, math.nan)
    while count * 2 * steps <= subject.replay_steps:
        steps *= 2
        fine = _shot(subject, count, steps)
        figures = (
            geodesic_angle(fine.quaternion, target),
            float(np.abs(wrapped_joints(robot, fine.ends - knots[1:])).max()),
        )
        estimates = (
            _finite(geodesic_angle(coarse.quaternion, fine.quaternion)),
            _finite(float(np.abs(wrapped_joints(robot, fine.ends - coarse.ends)).max())),
        )
        turn = speed * plan.duration / (count * steps)
        if all(
            _decided(value, estimate, before, tolerance, turn, earliest)
            for value, estimate, before, tolerance, earliest in zip(
                figures, estimates, previous, tolerances, earlier, strict=True
            )
        ):
            return SegmentedReplay(*figures, *estimates, count, steps, True)
        coarse, earlier, previous = fine, previous, estimates
    return SegmentedReplay(*figures, *previous, count, steps, False)


def _shot(subject: Subject, count: int, steps: int) -> _Shot:
    """Every segment replayed on ``steps`` steps from the path's state at its start.

    The torques come at the quarters of the steps of the whole duration's grid
    ``k T / (4 count steps)`` (the instants the whole replay uses, to the bit, when the counts
    are powers of two), each segment taking its share.
    """
    plan = subject.plan
    grid = np.linspace(0.0, plan.duration, 4 * steps * count + 1)
    torques = subject.dynamics.torques(grid)
    knots = grid[:: 4 * steps]
    joints = subject.path(knots[:-1])[0]
    velocities = subject.dynamics.velocities(knots[:-1])
    quaternion = np.asarray(plan.base.start_quaternion_xyzw, dtype=float)
    ends = np.empty((count, subject.robot.n))
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(count):
            share = torques[4 * steps * k : 4 * steps * (k + 1) + 1]
            result = replay(
                subject.mmap,
                joints[k],
                quaternion,
                share,
                float(knots[k + 1] - knots[k]),
                steps,
                track_momentum=False,
                start_velocity=velocities[k],
            )
            quaternion, ends[k] = result.quaternion_xyzw, result.joints
    return _Shot(quaternion, ends)
