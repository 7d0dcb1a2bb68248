"""The torques and base angular velocity of a plan's paths, each instant computed once.

The attitude check and the forward-dynamics replay (:mod:`freefloat.verify.integrating`) both
refine on the grids ``k T / 2^m`` of the plan's duration ``T``; on those grids the instants of
a coarse level are, to the bit, instants of every finer one (``numpy.linspace`` of a dyadic
count). The replay's torques come in batches of instants
(:func:`~freefloat.physics.joint_torques.joint_torques_and_twist`: the centroidal map and RNEA
at base acceleration zero, not the sampling's inverse dynamics), which also gives the
zero-momentum base twist at those instants; the attitude check reads the base angular velocity
there, and asks Pinocchio's centroidal map
(:meth:`~freefloat.physics.momentum.MomentumMap.pinocchio_rates`, one call per instant, not the
planner's batched formula) only at the instants the replay did not need.
"""

from __future__ import annotations

import numpy as np

from ..physics.joint_torques import joint_torques_and_twist
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
        self._torques: dict[float, np.ndarray] = {}
        self._omega: dict[float, np.ndarray] = {}
        self._twist: dict[float, np.ndarray] = {}

    def torques(self, t: np.ndarray) -> np.ndarray:
        """(len(t), N) joint torques at times ``t`` (s)."""
        times = np.asarray(t, dtype=float).tolist()
        missing = _missing(times, self._torques)
        if len(missing):
            q, qd, qdd = self.path(missing)
            found = joint_torques_and_twist(self.mmap, q, qd, qdd)
            for x, tau, twist in zip(missing.tolist(), found.tau, found.twist, strict=True):
                self._torques[x] = tau
                self._twist[x] = twist
                self._omega.setdefault(x, twist[3:])
        return np.array([self._torques[x] for x in times])

    def velocities(self, t: np.ndarray) -> np.ndarray:
        """(len(t), nv) Pinocchio velocities at times ``t`` (s): ``[v_base; qdot]``.

        The zero-momentum base twist (base frame, m/s then rad/s) that comes with the torques,
        the file's joint rates in their velocity slots (rad/s or m/s).
        """
        times = np.asarray(t, dtype=float)
        self.torques(times)  # the twists come with them
        out = np.zeros((len(times), self.mmap.model.nv))
        out[:, :6] = [self._twist[x] for x in times.tolist()]
        slots = [j.idx_v for j in self.mmap.robot.joints]
        out[:, slots] = self.path(times)[1]
        return out

    def omega(self, t: np.ndarray) -> np.ndarray:
        """(len(t), 3) base angular velocity at times ``t`` (s)."""
        times = np.asarray(t, dtype=float).tolist()
        missing = _missing(times, self._omega)
        if len(missing):
            q, qd, _ = self.path(missing)
            omega = self.mmap.pinocchio_rates(q, qd)
            self._omega.update(zip(missing.tolist(), omega, strict=True))
        return np.array([self._omega[x] for x in times])


def _missing(times: list[float], known: dict[float, np.ndarray]) -> np.ndarray:
    """The instants (s) of ``times`` not in ``known``, ascending, each once."""
    return np.array(sorted({x for x in times if x not in known}), dtype=float)
