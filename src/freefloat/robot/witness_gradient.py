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
from .sphere_distance import SphereWitness

__all__ = ["WitnessBatch", "carriers", "witness_gradients"]


def carriers(robot: Robot, joint: int) -> np.ndarray:
    """1.0 for each of the robot's joints that moves Pinocchio joint ``joint``, else 0.0.

    All zeros for the universe and the spacecraft (joints 0 and 1), which no joint moves.
    """
    support = set(robot.model.supports[joint]) if joint > 1 else set()
    return np.array([1.0 if j.index in support else 0.0 for j in robot.joints])


def witness_gradients(
    normals: np.ndarray,
    points: np.ndarray,
    carried: np.ndarray,
    jacobians: np.ndarray,
) -> np.ndarray:
    """d(distance)/d(joints) of B pairs, one per configuration (B, N; m per rad or m per m).

    Args:
        normals: (B, 3) unit normals from each pair's first shape to its second (world frame).
        points: (B, 2, 3) the witness points on the first and on the second shape (m).
        carried: (B, 2, N) :func:`carriers` of the two shapes' bodies.
        jacobians: (B, 6, N) world-frame joint Jacobians (``data.J`` at the robot's columns),
            each at its pair's configuration.
    """
    moments = np.cross(points, normals[:, None, :])  # p x n, per witness point
    rows = np.concatenate([np.broadcast_to(normals[:, None, :], moments.shape), moments], axis=2)
    rates = np.einsum("bks,bsn->bkn", rows, jacobians)  # m/s per unit joint rate, per point
    return (rates[:, 1] * carried[:, 1]) - (rates[:, 0] * carried[:, 0])


class WitnessBatch:
    """Normals, witness points and joint Jacobians of B pair queries, taken one at a time.

    Args:
        count: B, the number of queries.
        n: number of joints N.
    """

    def __init__(self, count: int, n: int) -> None:
        self.normals = np.zeros((count, 3))
        self.points = np.zeros((count, 2, 3))
        self.jacobians = np.zeros((count, 6, n))

    def take(
        self, i: int, result: coal.DistanceResult | SphereWitness, jacobian: np.ndarray
    ) -> None:
        """Query ``i``'s result (coal's or a closed form's; world frame, m) and Jacobian.

        ``jacobian``: the (6, N) world-frame joint Jacobian at the query's configuration.
        """
        self.normals[i] = result.normal
        self.points[i, 0] = result.getNearestPoint1()
        self.points[i, 1] = result.getNearestPoint2()
        self.jacobians[i] = jacobian

    def gradients(self, carried: np.ndarray, shapes: np.ndarray) -> np.ndarray:
        """(B, N) each query's distance gradient (m per rad or m).

        Args:
            carried: (G, N) :func:`carriers` of every shape's body (zeros: fixed to the
                spacecraft).
            shapes: (B, 2) the two shapes (indices) of each query's pair.
        """
        return witness_gradients(self.normals, self.points, carried[shapes], self.jacobians)
