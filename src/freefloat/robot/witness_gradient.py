"""How a pair's signed distance changes with the joints, from its witness points.

coal gives the two closest points of a pair (``p_a``, ``p_b``, world frame) and the unit normal
``n`` from the first shape to the second. A point ``p`` fixed on a body moves at
``v + w x p`` (``v, w``: the body's spatial velocity at the world origin, Pinocchio's
world-frame Jacobian over the joints that carry the body), so the distance changes by
``n . (v_b + w_b x p_b) - n . (v_a + w_a x p_a)`` per unit joint rate, where
``n . (w x p) = (p x n) . w``. Shapes fixed to the spacecraft do not move with the joints.
"""

from __future__ import annotations

import coal
import numpy as np

from .model import Robot

__all__ = ["carriers", "witness_gradient"]


def carriers(robot: Robot, joint: int) -> np.ndarray | None:
    """1.0 for each of the robot's joints that moves Pinocchio joint ``joint``, else 0.0.

    None for the universe and the spacecraft (joints 0 and 1), which no joint moves.
    """
    if joint <= 1:
        return None
    support = set(robot.model.supports[joint])
    return np.array([1.0 if j.index in support else 0.0 for j in robot.joints])


def witness_gradient(
    result: coal.DistanceResult,
    carried: tuple[np.ndarray | None, np.ndarray | None],
    jacobian: np.ndarray,
    n: int,
) -> np.ndarray:
    """d(distance)/d(joints) of one pair (m per rad or m per m).

    Args:
        result: coal's result for the pair (witness points and normal, world frame).
        carried: :func:`carriers` of the pair's two shapes' bodies.
        jacobian: (6, N) Pinocchio's world-frame joint Jacobian (``data.J``) at the robot's
            joint columns, after ``computeJointJacobians`` at the pair's configuration.
        n: number of joints N.
    """
    nx, ny, nz = result.normal
    rows, weights = [], []
    for point, sign, moved in (
        (result.getNearestPoint1(), -1.0, carried[0]),
        (result.getNearestPoint2(), 1.0, carried[1]),
    ):
        if moved is None:
            continue
        px, py, pz = point
        rows.append((nx, ny, nz, py * nz - pz * ny, pz * nx - px * nz, px * ny - py * nx))
        weights.append(sign * moved)
    if not rows:
        return np.zeros(n)
    rates = np.array(rows) @ jacobian  # per witness point, m/s per unit joint rate
    return np.einsum("pn,pn->n", np.array(weights), rates)
