"""The zero-momentum map: base motion implied by joint motion (docs/method.md section 2).

With zero total momentum ``h = A_g(q) v = 0`` and ``A_g = [A_b | A_q]`` (Pinocchio's
centroidal map, 6 x (6+N)), the base twist in the base frame is

    v_base = -A_b^-1 A_q qdot        (rows 0:3 linear m/s, rows 3:6 angular rad/s)

Rows 3:6 are ``F1(q)``, so that ``omega_base = F1(q) qdot``. The map depends on the joint
values only (not on the base pose), so it is evaluated with the base at the origin and
identity attitude. The system centre of mass (CM) is the inertial origin.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..robot.content_cache import RobotCache
from ..robot.model import Robot
from .centroidal_batch import BatchedCentroidal, NodeRates

__all__ = ["MomentumMap", "NodeRates", "is_planar", "planar_axis"]


class MomentumMap:
    """Evaluate the momentum map and related kinematics for one robot.

    Reuses one Pinocchio ``Data`` and one configuration buffer across calls, so an instance is
    not thread-safe; make one per thread. :meth:`base_rates` reads the model's tree and
    inertias once, at its first call: a model changed in place afterwards (masses, say) needs a
    new instance (:mod:`freefloat.robust` copies the model for that).
    """

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()
        self._q = robot.configuration(np.zeros(robot.n))
        self.evaluations = 0
        self._batched: BatchedCentroidal | None = None  # built when base rates are first asked

    def base_twist_map(self, joints: np.ndarray) -> np.ndarray:
        """The 6 x N map from joint rates to the base twist (base frame).

        Args:
            joints: N joint values (rad or m).

        Returns:
            ``J`` with ``v_base = J qdot``: rows 0:3 give the base-origin velocity (m/s per
            unit rate), rows 3:6 give ``F1`` (rad/s per unit rate).
        """
        self.robot.write_joints(self._q, joints)
        ag = pin.computeCentroidalMap(self.model, self.data, self._q)
        self.evaluations += 1
        return -np.linalg.solve(ag[:, :6], ag[:, 6:])

    def configurations(self, joints: np.ndarray) -> np.ndarray:
        """(K, nq) Pinocchio configurations, base at the origin with identity attitude."""
        joints = np.atleast_2d(np.asarray(joints, dtype=float))
        out = np.repeat(self._q[None, :], len(joints), axis=0)
        for i, joint in enumerate(self.robot.joints):
            if joint.kind == "continuous":
                out[:, joint.idx_q] = np.cos(joints[:, i])
                out[:, joint.idx_q + 1] = np.sin(joints[:, i])
            else:
                out[:, joint.idx_q] = joints[:, i]
        return out

    def base_rates(
        self, joints: np.ndarray, rates: np.ndarray, derivatives: bool = False
    ) -> NodeRates:
        """Base angular velocity at K instants, every instant at once.

        The base block of the centroidal map is ``[[m I, -m [c]x], [0, I_c]]`` (base at the
        origin with identity attitude; ``c`` the CM, ``I_c`` the locked inertia about it, kg
        m^2), so the angular rows need only ``I_c^-1``: ``F1 = -I_c^-1 A_q[3:6]``. In array
        operations over the instants (:class:`~.centroidal_batch.BatchedCentroidal`; with the
        derivatives about 2.2-2.5 times faster than Pinocchio's centroidal derivatives one
        instant at a time, and the same to about 1e-14 of the largest entry); ``omega`` and
        ``f1`` are the same bits with or without the derivatives.

        Args:
            joints: (K, N) joint values (rad or m).
            rates: (K, N) joint rates (per unit of any time variable).
            derivatives: also return ``d omega / d q`` (analytic).
        """
        if self._batched is None:
            self._batched = BatchedCentroidal(self.robot)
        found = self._batched.base_rates(joints, rates, derivatives)
        self.evaluations += len(found.omega)
        return found

    def pinocchio_rates(self, joints: np.ndarray, rates: np.ndarray) -> np.ndarray:
        """(K, 3) base angular velocity from Pinocchio's centroidal map, one instant at a time.

        The same quantity as :meth:`base_rates` by another formula (Pinocchio's, not the
        planner's): the verification's.

        Args:
            joints: (K, N) joint values (rad or m).
            rates: (K, N) joint rates (per unit of any time variable).
        """
        configs = self.configurations(joints)
        k_count, model, data, cmap = len(configs), self.model, self.data, pin.computeCentroidalMap
        ag = np.array([cmap(model, data, q) for q in configs]).reshape(k_count, 6, model.nv)
        self.evaluations += k_count
        f1 = -np.linalg.solve(ag[:, 3:6, 3:6], ag[:, 3:6, 6:])  # LAPACK: any conditioning
        return np.einsum("kij,kj->ki", f1, np.atleast_2d(rates))

    def f1(self, joints: np.ndarray) -> np.ndarray:
        """``F1(q)``: 3 x N map from joint rates to the base angular velocity (base frame)."""
        return self.base_twist_map(joints)[3:]

    def base_position(self, joints: np.ndarray, quaternion_xyzw: np.ndarray) -> np.ndarray:
        """Base origin in the inertial frame (m) that keeps the system CM at the origin."""
        q = self.robot.configuration(joints, None, quaternion_xyzw)
        return -np.asarray(pin.centerOfMass(self.model, self.data, q))

    def configuration(self, joints: np.ndarray, quaternion_xyzw: np.ndarray) -> np.ndarray:
        """Full Pinocchio configuration with the base placed so that the CM is at the origin."""
        q = self.robot.configuration(joints, None, quaternion_xyzw)
        q[0:3] = -np.asarray(pin.centerOfMass(self.model, self.data, q))
        return q

    def velocity(self, joints: np.ndarray, rates: np.ndarray) -> np.ndarray:
        """Full Pinocchio velocity ``[v_base; qdot]`` with the zero-momentum base twist."""
        return np.concatenate([self.base_twist_map(joints) @ rates, rates])

    def end_effector_pose(
        self, joints: np.ndarray, quaternion_xyzw: np.ndarray, frame: str | None = None
    ) -> pin.SE3:
        """End-effector placement in the inertial frame (CM at the origin; m, rotation).

        ``frame``: which end effector (a frame name); default the robot's first.
        """
        q = self.configuration(joints, quaternion_xyzw)
        pin.framesForwardKinematics(self.model, self.data, q)
        index = self.robot.end_effector_frame if frame is None else self.model.getFrameId(frame)
        return self.data.oMf[index].copy()

    def momentum(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Total momentum ``[linear (kg m/s); angular about the CM (kg m^2/s)]``, inertial frame."""
        return np.asarray(pin.computeCentroidalMomentum(self.model, self.data, q, v).vector)


def planar_axis(robot: Robot, samples: int = 16, seed: int = 0) -> np.ndarray | None:
    """The axis (unit vector, base frame) the base alone can turn about, if there is one.

    A robot is planar (docs/method.md section 3) when every revolute axis is parallel to one axis
    ``n`` of the base, every prismatic axis is orthogonal to it, and the part of ``F1``
    orthogonal to ``n`` vanishes; the last condition is checked at ``samples`` random
    configurations (relative tolerance 1e-12). The usual planar arm has ``n`` = base z; a
    planar arm described in another plane of the base gets its own ``n``.
    """
    model, data = robot.model, robot.model.createData()
    q = robot.configuration(np.zeros(robot.n))
    pin.computeJointJacobians(model, data, q)
    columns = [
        pin.getJointJacobian(model, data, j.index, pin.LOCAL_WORLD_ALIGNED)[:, j.idx_v]
        for j in robot.joints
    ]
    axes = [c[3:] for c, j in zip(columns, robot.joints, strict=True) if j.angular]
    if not axes:
        return None
    n = axes[0] / np.linalg.norm(axes[0])
    if n @ np.array([0.0, 0.0, 1.0]) < -1e-12 or (abs(n[2]) < 1e-12 and n.sum() < 0):
        n = -n  # a canonical sign: +z for the usual planar arm
    for column, joint in zip(columns, robot.joints, strict=True):
        if joint.angular and np.linalg.norm(np.cross(column[3:], n)) > 1e-12:
            return None
        if not joint.angular and abs(column[:3] @ n) > 1e-12:
            return None
    mmap = MomentumMap(robot)
    rng = np.random.default_rng(seed)
    across = np.eye(3) - np.outer(n, n)
    for _ in range(samples):
        values = rng.uniform(-np.pi, np.pi, robot.n)
        for i, joint in enumerate(robot.joints):
            if not joint.angular or np.isfinite(joint.lower):  # within its limits, near 0
                low, high = max(joint.lower, -1.0), min(joint.upper, 1.0)
                if low > high:  # limits away from 0: one radian (or metre) of them
                    low, high = joint.lower, min(joint.upper, joint.lower + 1.0)
                values[i] = rng.uniform(low, high)
        f1 = mmap.f1(values)
        if np.abs(across @ f1).max() > 1e-12 * max(1.0, np.abs(n @ f1).max()):
            return None
    return n


def is_planar(robot: Robot, samples: int = 16, seed: int = 0) -> bool:
    """True when the base can only turn about one fixed axis (see :func:`planar_axis`)."""
    return planar_axis(robot, samples, seed) is not None


#: Planar axis (None: not planar), computed once per robot content.
_PLANAR_AXES: RobotCache[np.ndarray | None] = RobotCache()


def cached_planar_axis(robot: Robot) -> np.ndarray | None:
    """:func:`planar_axis`, computed once per robot content."""
    return _PLANAR_AXES.get(robot, lambda: planar_axis(robot))
