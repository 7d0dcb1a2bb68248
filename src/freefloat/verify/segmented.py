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
segment's in order. Re-anchoring each segment also hides most of what a wrong torque does: an
acceleration error ``a`` moves a segment of length ``h = T / K`` by about ``a h^2 / 2``, the
whole motion by ``a T^2 / 2``, ``K^2`` times as much. So each segment's defects are scaled by
``K^2``, and the tolerances are the replay's own:

- ``replay_attitude``: the angle (rad) from the end attitude to the target, plus ``K^2`` times
  the largest angle between a segment's replayed turn of the base and the path's own turn over
  it (integrated on the same steps from the base angular velocity that comes with the torques);
  its error estimate bounds how far both terms moved over the last doubling.
- ``replay_joints``: ``K^2`` times the largest joint defect at a segment's end (rad or m,
  continuous joints wrapped); its estimate ``K^2`` times the largest change of a segment's end
  over the last doubling.

Each level doubles the steps of every segment (from 8) and is decided as the whole replay is
(:func:`~freefloat.verify.stepping._decided`), including its rule before a refusal: the
segments are replayed once more with their torques perturbed by
:data:`~freefloat.verify.stepping.TORQUE_PERTURBATION`'s fraction, and how far the ends move
(scaled alike) joins the estimates. The segment counts tried are :data:`SEGMENT_COUNTS`, the
steps of all segments together within the replay's cap; a count whose figures are not
numbers, or that is undecided while a difference above rounding grows past its second
doubling, is left for the next. What a
segmented replay shows is weaker than a whole one, and the check's detail says which was made:
that the path and its torques satisfy the dynamics over every segment, not that the torques
alone, open loop, would bring the system there.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from ..physics.attitude import geodesic_angle, quat_multiply
from ..physics.replay import replay
from .plan_checks import TOLERANCES, Subject
from .stepping import (
    _FIRST_REPLAY_STEPS,
    _MAX_TURN,
    ROUNDING_FLOOR,
    _decided,
    _finite,
    _rk5_attitude,
    motion_speed,
    perturbed_torques,
    wrapped_joints,
)

__all__ = ["SEGMENTED", "SEGMENT_COUNTS", "SegmentedReplay", "segment_count", "segmented_replay"]

#: Segment counts tried, in order (a count each): more segments, shorter ones, less amplified.
SEGMENT_COUNTS = (8, 32, 128)
#: What the detail of a replay made in segments says after its count (``"RK5 in 8 segments of
#: 32 steps, ..."``); :func:`segment_count` reads the count back.
SEGMENTED = " segments of "


@dataclass(frozen=True)
class SegmentedReplay:
    """The last level of a replay in segments.

    Attributes:
        attitude: angle from the end attitude to the target plus the count squared times the
            largest angle between a segment's replayed turn and the path's (rad).
        joints: largest joint defect at a segment's end, times the count squared (rad or m).
        attitude_estimate: its change over the last doubling of the steps, and how far the
            perturbed torques moved it before a refusal (rad).
        joint_estimate: the same for the joints (rad or m).
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
    """One step count's segments: each one's turn of the base and its end joints.

    Attributes:
        turns: (K, 4) each segment's replayed turn of the base, ``[x, y, z, w]`` from the
            identity (the base frame at its start).
        path_turns: (K, 4) the path's own turn over each segment, integrated on the same
            steps from the base angular velocity that comes with the torques.
        ends: (K, N) each segment's end joints (rad or m).
        path_ends: (K, N) the path's joints at the segments' ends (rad or m).
    """

    turns: np.ndarray
    path_turns: np.ndarray
    ends: np.ndarray
    path_ends: np.ndarray

    def end(self, start: np.ndarray) -> np.ndarray:
        """The attitude ``[x, y, z, w]`` from ``start`` turned by every segment's turn in order."""
        attitude = np.asarray(start, dtype=float)
        for turn in self.turns:
            attitude = quat_multiply(attitude, turn)
        return attitude / np.linalg.norm(attitude)


def segment_count(detail: str) -> int | None:
    """The segment count a replay check's ``detail`` names, or None for a replay from rest."""
    found = re.search(rf" in (\d+){SEGMENTED}", detail)
    return int(found[1]) if found else None


def segmented_replay(subject: Subject) -> SegmentedReplay:
    """The replay in :data:`SEGMENT_COUNTS` segments, the first count that converges.

    The last count's level when none does (``converged`` False); none is tried when the cap
    cannot resolve the motion in any count (its largest turn in one step, the same for every
    count at the cap, beyond what a step-doubling check trusts).
    """
    level = SegmentedReplay(math.nan, math.nan, math.inf, math.inf, SEGMENT_COUNTS[0], 0, False)
    plan = subject.plan
    if motion_speed(plan) * plan.duration / subject.replay_steps > _MAX_TURN:
        return level
    for count in SEGMENT_COUNTS:
        if count * 2 * _FIRST_REPLAY_STEPS > subject.replay_steps:
            break  # not even two levels of this count fit the cap
        level = _doubling(subject, count)
        if level.converged:
            break
    return level


def _doubling(subject: Subject, count: int) -> SegmentedReplay:
    """``count`` segments on doubling steps until both verdicts stand or the cap is reached.

    A refusal stands only when the torques perturbed by their assumed error do not move the
    ends as far (:data:`~freefloat.verify.stepping.TORQUE_PERTURBATION`); otherwise, and
    when the figures are not numbers or the estimates grow past the second doubling, this
    count is left undecided.
    """
    plan = subject.plan
    tolerances = (TOLERANCES["replay_attitude_rad"], TOLERANCES["replay_joint"])
    speed = motion_speed(plan)
    steps = _FIRST_REPLAY_STEPS
    coarse = _shot(subject, count, steps)
    previous = earlier = (math.inf, math.inf)  # the last two differences (attitude, joints)
    figures, estimates = (math.nan, math.nan), (math.inf, math.inf)
    while count * 2 * steps <= subject.replay_steps:
        steps *= 2
        fine = _shot(subject, count, steps)
        figures, estimates = _figures(subject, count, fine), _apart(subject, count, coarse, fine)
        if not all(map(math.isfinite, figures)):
            break  # blew up at this count: a later one may not
        turn = speed * plan.duration / (count * steps)
        if all(
            _decided(value, estimate, before, tolerance, turn, earliest)
            for value, estimate, before, tolerance, earliest in zip(
                figures, estimates, previous, tolerances, earlier, strict=True
            )
        ):
            if _refuses(figures, estimates, tolerances):
                moved = _apart(subject, count, fine, _shot(subject, count, steps, perturbed=True))
                estimates = (estimates[0] + moved[0], estimates[1] + moved[1])
                if not _refuses(figures, estimates, tolerances):
                    break  # its inputs' own error could move the ends that far: undecided
            return SegmentedReplay(*figures, *estimates, count, steps, True)
        if steps > 4 * _FIRST_REPLAY_STEPS and _growing(estimates, previous, tolerances):
            break  # not converging at this count: a later one may
        coarse, earlier, previous = fine, previous, estimates
    return SegmentedReplay(*figures, *estimates, count, steps, False)


def _refuses(
    figures: tuple[float, float], estimates: tuple[float, float], tolerances: tuple[float, float]
) -> bool:
    """Whether a figure exceeds its tolerance by more than its estimate (a refusal)."""
    return any(f - e > t for f, e, t in zip(figures, estimates, tolerances, strict=True))


def _growing(
    estimates: tuple[float, float], previous: tuple[float, float], tolerances: tuple[float, float]
) -> bool:
    """Whether a difference grew over the last doubling, above the rounding floor.

    Differences at the floor (:data:`~freefloat.verify.stepping.ROUNDING_FLOOR` of the
    tolerance) go up and down with rounding: their growth means nothing.
    """
    return any(
        e > p and e > ROUNDING_FLOOR * t
        for e, p, t in zip(estimates, previous, tolerances, strict=True)
    )


def _figures(subject: Subject, count: int, shot: _Shot) -> tuple[float, float]:
    """The attitude and joint figures of a shot, scaled to the whole motion (rad; rad or m).

    Attitude: the angle from the end attitude to the target, plus ``K^2`` times the largest
    angle between a segment's replayed turn and the path's own; joints: ``K^2`` times the
    largest joint defect at a segment's end.
    """
    plan = subject.plan
    start = np.asarray(plan.base.start_quaternion_xyzw, dtype=float)
    target = np.asarray(plan.base.target_quaternion_xyzw, dtype=float)
    defect = float(np.abs(wrapped_joints(subject.robot, shot.ends - shot.path_ends)).max())
    turned = max(geodesic_angle(a, b) for a, b in zip(shot.turns, shot.path_turns, strict=True))
    square = count * count
    return geodesic_angle(shot.end(start), target) + square * turned, square * defect


def _apart(subject: Subject, count: int, one: _Shot, other: _Shot) -> tuple[float, float]:
    """How far two shots' figures can differ, bounded as :func:`_figures` is made (inf: NaN).

    A segment's defect angle moves at most by how far its replayed turn and the path's turn
    moved (the triangle inequality); the end attitude by the segments' turns' moves in all.
    """
    start = np.asarray(subject.plan.base.start_quaternion_xyzw, dtype=float)
    turns = max(
        geodesic_angle(a, b) + geodesic_angle(c, d)
        for a, b, c, d in zip(one.turns, other.turns, one.path_turns, other.path_turns, strict=True)
    )
    joints = float(np.abs(wrapped_joints(subject.robot, one.ends - other.ends)).max())
    square = count * count
    return (
        _finite(geodesic_angle(one.end(start), other.end(start)) + square * turns),
        _finite(square * joints),
    )


def _shot(subject: Subject, count: int, steps: int, perturbed: bool = False) -> _Shot:
    """Every segment replayed on ``steps`` steps from the path's state at its start.

    The torques (N m or N) come at the quarters of the steps of the whole duration's grid
    ``k T / (4 count steps)`` (the instants the whole replay uses, to the bit, when the counts
    are powers of two), each segment taking its share; ``perturbed``: offset as
    :func:`~freefloat.verify.stepping.perturbed_torques` offsets them.
    """
    plan = subject.plan
    grid = np.linspace(0.0, plan.duration, 4 * steps * count + 1)
    torques = subject.dynamics.torques(grid)
    if perturbed:
        torques = perturbed_torques(torques)
    knots = grid[:: 4 * steps]
    joints = subject.path(knots)[0]  # each segment's start, and the path at its end
    velocities = subject.dynamics.velocities(knots[:-1])
    omega = subject.dynamics.omega(grid)
    identity = np.array([0.0, 0.0, 0.0, 1.0])
    turns, path_turns = np.empty((count, 4)), np.empty((count, 4))
    ends = np.empty((count, subject.robot.n))
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(count):
            share = slice(4 * steps * k, 4 * steps * (k + 1) + 1)
            width = float(knots[k + 1] - knots[k])
            result = replay(
                subject.mmap,
                joints[k],
                identity,
                torques[share],
                width,
                steps,
                track_momentum=False,
                start_velocity=velocities[k],
            )
            turns[k], ends[k] = result.quaternion_xyzw, result.joints
            path_turns[k] = _rk5_attitude(identity, omega[share], width)
    return _Shot(turns, path_turns, ends, joints[1:])
