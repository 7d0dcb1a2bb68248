"""The torques and base angular velocity of a plan's paths, each instant computed once.

The attitude check and the forward-dynamics replay (:mod:`freefloat.verify.integrating`) both
refine on the grids ``k T / 2^m`` of the plan's duration ``T``; on those grids the instants of
a coarse level are, to the bit, instants of every finer one (``numpy.linspace`` of a dyadic
count). One inverse-dynamics batch (:func:`~freefloat.physics.dynamics.inverse_dynamics_batch`,
the zero-momentum base twist and the joint torques of the file's paths) serves both: what one
check has asked for, the other reads.
"""

from __future__ import annotations

import numpy as np

from ..physics.dynamics import inverse_dynamics_batch
from ..physics.momentum import MomentumMap
from .path_eval import FilePath

__all__ = ["PathDynamics"]


class PathDynamics:
    """Joint torques (N m or N) and base angular velocity (rad/s, base frame) along a path.

    Args:
        mmap: the robot's momentum map.
        path: the file's joint paths.
    """

    def __init__(self, mmap: MomentumMap, path: FilePath) -> None:
        self.mmap, self.path = mmap, path
        self._rows: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    def _fill(self, t: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        missing = np.array(sorted({x for x in t.tolist() if x not in self._rows}))
        if len(missing):
            q, qd, qdd = self.path(missing)
            dyn = inverse_dynamics_batch(self.mmap, q, qd, qdd)
            for x, tau, omega in zip(missing.tolist(), dyn.tau, dyn.base_twist[:, 3:], strict=True):
                self._rows[x] = (tau, omega)
        return [self._rows[x] for x in t.tolist()]

    def torques(self, t: np.ndarray) -> np.ndarray:
        """(len(t), N) joint torques at times ``t`` (s)."""
        return np.array([row[0] for row in self._fill(np.asarray(t, dtype=float))])

    def omega(self, t: np.ndarray) -> np.ndarray:
        """(len(t), 3) base angular velocity at times ``t`` (s)."""
        return np.array([row[1] for row in self._fill(np.asarray(t, dtype=float))])
