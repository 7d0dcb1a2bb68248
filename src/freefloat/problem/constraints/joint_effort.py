"""Joint effort limits from the URDF along the whole path.

The torques of a zero-momentum motion (N m, or N for prismatic joints) follow from the joint
path alone (:mod:`freefloat.physics.torque_derivatives`). With ``s = t / T`` they are
``tau(t) = tau_1(s) / T^2``: the path shape does not depend on ``T``, so the shortest duration
at which a path respects every effort limit is exact, ``T_min = T sqrt(max_i peak_i / limit_i)``
(:meth:`JointEffortLimits.shortest_duration`), as it is for velocity limits.

Planning imposes them lazily (they rarely bind and their rows cost inverse dynamics with
derivatives): first without them, then with them only if the path found breaks them. For the
solvers, the limits are rows ``+-tau_i(s) - limit_i`` at the instants, with their exact
Jacobian by the chain rule through Pinocchio's RNEA derivatives. The dense check samples the
torques on :data:`DENSE_SAMPLES` instants and refines every sampled local maximum that could hold
a joint's peak by a bracket search between its neighbours (every bracket cut into
:data:`SECTIONS` sections per round, all brackets of all joints in one batch per round); its
error estimate is what remains of the search (the rise of the torque from the final brackets'
ends to their best sample).
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable

import numpy as np

from ...errors import EffortLimitError
from ...physics.joint_torques import joint_torques_batch
from ...physics.momentum import MomentumMap
from ...physics.torque_derivatives import torques_and_derivatives
from ...robot.model import Joint, Robot
from ..paths import JointPolynomials
from ..residual import Problem
from .base import DEFAULT_INSTANTS, ConstraintRows, DurationScaledLimit, Excess, LimitPeak

__all__ = ["DENSE_SAMPLES", "JointEffortLimits"]

#: Instants of the dense check on [0, T].
DENSE_SAMPLES = 401
#: Sections each refinement round splits a candidate peak's bracket into.
SECTIONS = 8
#: Refinement rounds: the brackets shrink to (2 / SECTIONS)^REFINE_ROUNDS of two sample
#: steps (1.5e-5; about 1e-6 s on a 20 s path), where a torque's rise is ~1e-12 of its scale.
REFINE_ROUNDS = 8


class JointEffortLimits(DurationScaledLimit):
    """Every joint's torque stays within ``+-effort_limit`` of its URDF (N m or N)."""

    name = "joint_effort_limits"
    unit = "N m|N"
    tolerance = 1e-9
    affine = False
    lazy = True
    power = 2

    def __init__(self) -> None:
        self._maps: weakref.WeakKeyDictionary[Robot, MomentumMap] = weakref.WeakKeyDictionary()
        # the last paths' peaks per robot: planning checks a path, verification the same one
        self._peaks: weakref.WeakKeyDictionary[
            Robot, dict[bytes, tuple[np.ndarray, np.ndarray, float]]
        ] = weakref.WeakKeyDictionary()

    def applies_to(self, robot: Robot) -> bool:
        """True when some joint has a finite effort limit."""
        return any(math.isfinite(j.effort_limit) for j in robot.joints)

    def _map(self, robot: Robot) -> MomentumMap:
        if robot not in self._maps:
            self._maps[robot] = MomentumMap(robot)
        return self._maps[robot]

    def rows(
        self, problem: Problem, beta: np.ndarray, instants: np.ndarray = DEFAULT_INSTANTS
    ) -> ConstraintRows:
        """``+-tau_i(t) - limit_i`` at the instants (N m or N), exact Jacobian."""
        samples = problem.family.affine_samples(np.asarray(instants, dtype=float))
        path = samples.at(beta)
        found = torques_and_derivatives(problem.mmap, path.q, path.qd, path.qdd)
        scale = problem.duration**-2
        tau = found.tau * scale
        dtau = scale * (
            np.einsum("kij,kjf->kif", found.d_q, samples.dq)
            + np.einsum("kij,kjf->kif", found.d_qd, samples.dqs)
            + np.einsum("kij,kjf->kif", found.d_qdd, samples.dqss)
        )
        values, rows = [], []
        for i, joint in enumerate(problem.robot.joints):
            if math.isfinite(joint.effort_limit):
                values += [tau[:, i] - joint.effort_limit, -tau[:, i] - joint.effort_limit]
                rows += [dtau[:, i, :], -dtau[:, i, :]]
        if not values:
            return ConstraintRows(np.zeros(0), np.zeros((0, problem.n_free)))
        return ConstraintRows(np.concatenate(values), np.concatenate(rows))

    def peaks(self, robot: Robot, path: JointPolynomials) -> tuple[np.ndarray, np.ndarray, float]:
        """Each joint's largest ``|tau|`` (N m or N), its time (s), and their error estimate.

        The torques are sampled at :data:`DENSE_SAMPLES` instants; every sampled local maximum
        that could hold the peak (within four of the joint's largest second differences of its
        top sample, a bound on what the grid can miss) is refined by a bracket search between
        its neighbours: each round samples every bracket at :data:`SECTIONS` - 1 interior
        instants (all brackets in one batch) and keeps the two sections about the largest
        sample, :data:`REFINE_ROUNDS` rounds. The error estimate is the largest rise of
        ``|tau|`` from a final bracket's ends to its best sample: at least four times what a
        torque that is locally quadratic can still rise between the samples. The last few
        paths' results are kept (copies are returned): planning and verification look at the
        same path.
        """
        shape = np.asarray(path.coefficients.shape, dtype=np.int64).tobytes()
        key = shape + np.float64(path.duration).tobytes() + path.coefficients.tobytes()
        kept = self._peaks.setdefault(robot, {})
        if key not in kept:
            if len(kept) >= 4:
                kept.clear()
            kept[key] = self._peaks_of(robot, path)
        peak, where, spread = kept[key]
        return peak.copy(), where.copy(), spread

    def _peaks_of(
        self, robot: Robot, path: JointPolynomials
    ) -> tuple[np.ndarray, np.ndarray, float]:
        mmap = self._map(robot)
        t = np.linspace(0.0, path.duration, DENSE_SAMPLES)

        def torques(times: np.ndarray) -> np.ndarray:
            s = path.evaluate(times)
            return np.abs(joint_torques_batch(mmap, s.q, s.qd, s.qdd))

        sampled = torques(t)
        peak = sampled.max(axis=0)
        where = t[sampled.argmax(axis=0)]
        padded = np.vstack([sampled[:1] - 1.0, sampled, sampled[-1:] - 1.0])
        local = (padded[1:-1] >= padded[:-2]) & (padded[1:-1] >= padded[2:])
        reach = 4.0 * np.abs(np.diff(sampled, 2, axis=0)).max(axis=0)
        rows, joints = np.nonzero(local & (sampled >= peak - reach))  # each joint's top one too
        grid, values = _refined(
            torques,
            joints,
            t[np.maximum(rows - 1, 0)],
            t[np.minimum(rows + 1, len(t) - 1)],
            sampled[np.maximum(rows - 1, 0), joints],
            sampled[np.minimum(rows + 1, len(t) - 1), joints],
        )
        best = values.argmax(axis=1)
        found = values[np.arange(len(best)), best]
        # the bracket's best sample against its lower neighbour: at least four times what a
        # locally quadratic torque can still rise between the samples
        left = values[np.arange(len(best)), np.maximum(best - 1, 0)]
        right = values[np.arange(len(best)), np.minimum(best + 1, SECTIONS)]
        spread = float(np.max(found - np.minimum(left, right), initial=0.0))  # none: no bracket
        for value, time, i in zip(found, grid[np.arange(len(best)), best], joints, strict=True):
            if value > peak[i]:
                peak[i], where[i] = value, time
        return peak, where, spread

    def critical_times(self, robot: Robot, path: JointPolynomials) -> np.ndarray:
        """Times (s) of each limited joint's largest torque."""
        _, where, _ = self.peaks(robot, path)
        return np.array([w for w, j in zip(where, robot.joints, strict=True) if _limited(j)])

    def excess(self, robot: Robot, path: JointPolynomials) -> Excess:
        """Largest torque beyond a limit (N m or N), with the refinement's error estimate."""
        if not self.applies_to(robot):
            return Excess(0.0, 0.0, "no joint has an effort limit")
        peak, where, spread = self.peaks(robot, path)
        worst, detail = -math.inf, ""
        for i, joint in enumerate(robot.joints):
            if _limited(joint) and peak[i] - joint.effort_limit > worst:
                worst = float(peak[i] - joint.effort_limit)
                detail = f"joint {joint.name!r} at t = {where[i]:.4g} s"
        return Excess(worst, spread, detail)

    def worst(self, robot: Robot, path: JointPolynomials) -> LimitPeak | None:
        """The joint whose peak torque (N m or N) is the largest fraction of its limit."""
        if not self.applies_to(robot):
            return None
        peak, _, _ = self.peaks(robot, path)
        fraction, i = max(
            (float(peak[i] / j.effort_limit), i) for i, j in enumerate(robot.joints) if _limited(j)
        )
        joint = robot.joints[i]
        shortest = path.duration * math.sqrt(fraction)
        return LimitPeak(joint, float(peak[i]), joint.effort_limit, fraction, shortest)

    def error(self, peak: LimitPeak) -> EffortLimitError:
        """:class:`EffortLimitError` naming the joint, its torque and the shortest duration."""
        return EffortLimitError(
            peak.joint.name, peak.peak, peak.limit, peak.shortest_duration, peak.joint.effort_unit
        )


def _limited(joint: Joint) -> bool:
    return math.isfinite(joint.effort_limit)


def _refined(
    torques: Callable[[np.ndarray], np.ndarray],
    joints: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    f_lo: np.ndarray,
    f_hi: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Brackets ``[lo, hi]`` (s) shrunk about the largest ``|tau|`` of their joint.

    Each round samples :data:`SECTIONS` - 1 evenly spaced interior instants of every bracket,
    all brackets in one batch, and keeps the two sections on either side of the largest
    sample: the bracket shrinks by ``2 / SECTIONS`` per round. Returns the last round's
    (B, SECTIONS + 1) instants (s) and ``|tau|`` of each bracket's joint there (N m or N).
    """
    fraction = np.linspace(0.0, 1.0, SECTIONS + 1)
    index = np.arange(len(joints))
    for _ in range(REFINE_ROUNDS):
        grid = lo[:, None] + (hi - lo)[:, None] * fraction[None, :]
        inner = torques(grid[:, 1:-1].ravel()).reshape(len(joints), SECTIONS - 1, -1)
        values = np.column_stack([f_lo, inner[index, :, joints], f_hi])
        best = values.argmax(axis=1)
        below, above = np.maximum(best - 1, 0), np.minimum(best + 1, SECTIONS)
        lo, hi = grid[index, below], grid[index, above]
        f_lo, f_hi = values[index, below], values[index, above]
    return grid, values
