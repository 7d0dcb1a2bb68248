"""Second-order lower bounds of a pair's distance over an interval of time, from one direction.

The certificate's other bounds over an interval ``[t0, t1]`` are first order: the distance at
the ends less the pair's largest speed times the width. Along a stretch where two bodies stay
near one another, that loses the speed bound times the width even where the distance barely
changes, and only halving narrows it. This bound loses the actual rate of change at the
middle instead, and a term of the second order in the width.

Take the middle ``tm`` and half-width ``h``, and a unit direction ``n`` fixed in the frame
``C`` of the link both bodies hang from (the spacecraft when no joint moves both). Along
``n`` the two bodies lie at least ``min over B of n.x - max over A of n.x`` apart (a
separating plane, :mod:`.separation`); each extreme is over a finite set of points
(:meth:`.Separation.points`: every vertex of a mesh or box, a sphere's centre or a capsule's
ends, widened by their radius). Each point's ``f(t) = n.x(t)`` in ``C`` obeys

    f(t)  >=  f(tm) - h |f'(tm)| - M h^2 / 2    on [tm - h, tm + h],

``f'(tm) = n.v`` its velocity relative to ``C`` at the middle (the joint Jacobians in the
spacecraft frame, with the rates of the joints that move both bodies left out: they move
``C`` and the point alike), and ``M`` a bound on the acceleration of any point of the body
relative to ``C`` over the interval. For the joints ``j`` between ``C`` and the body, in
order from ``C``, with ``w_j`` the body's reach from joint j's axis (m per rad; 1 for a
prismatic joint, :func:`~.motion.reach_coefficients`) and ``Qd_j``, ``Qdd_j`` the largest
``|qd_j|`` and ``|qdd_j|`` over the interval (exact: the paths are polynomials):

    |x''|  <=  sum_j w_j (Qdd_j + Qd_j (Qd_j + 2 sum_{i before j} Qd_i))

because a point's second derivative along joints i, j is a vector of length at most the
reach from the deeper one's axis (``z_i x (z_j x r_j)`` and kin). The direction is GJK's
between the bodies' hulls at the middle (only proposed: any unit ``n`` gives a bound).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pinocchio as pin

from .instants import Instants

__all__ = ["IntervalTaylor"]


class IntervalTaylor:
    """Second-order lower bounds of pair distances over intervals of one certificate's path.

    Args:
        store: the certificate's instants (placements, rates, directions per instant).
    """

    def __init__(self, store: Instants) -> None:
        mesh = store.mesh
        robot = mesh.robot
        self._store = store
        joints = [j.index for j in robot.joints]
        #: The bound needs the joints in the order of the chains (parents first).
        self.usable = all(a < b for a, b in itertools.pairwise(joints))
        self._columns = np.array([robot.model.joints[j].idx_v for j in joints], dtype=int)
        self._reach = mesh.levers.reach_t  # (G, N): m per rad, 1 for prismatic
        self._parents = [int(o.parentJoint) for o in mesh.geometry.geometryObjects]
        self._data = robot.model.createData()
        self._jacobians: dict[float, dict[int, np.ndarray]] = {}
        self._points: dict[int, tuple[np.ndarray, float] | None] = {}
        self._pair_chains: dict[int, tuple[_Chain, _Chain]] = {}

    def spread(self, t0: float, t1: float, k: int) -> float:
        """``M_a + M_b`` (m/s^2): how fast pair k's bodies' points can accelerate.

        Over ``[t0, t1]`` (s), relative to the link they both hang from; inf when not usable.
        ``-spread h^2 / 2`` is the second-order term of :meth:`bound`: with it the certificate
        sees whether the bound can settle an interval before asking for it.
        """
        if not self.usable:
            return math.inf
        speeds = self._store.rates([t0], [t1])[0].tolist()
        accelerations = self._store.acceleration_bounds(t0, t1).tolist()
        return sum(_acceleration(chain, speeds, accelerations) for chain in self._chains(k))

    def bound(self, t0: float, t1: float, k: int, spread: float) -> float:
        """A lower bound (m) of pair k's distance over ``[t0, t1]`` (s); -inf when none.

        ``spread``: :meth:`spread` of the same interval and pair (m/s^2).
        """
        store = self._store
        a, b = store.mesh.pairs[k]
        points_a, points_b = self._points_of(a), self._points_of(b)
        if points_a is None or points_b is None or not math.isfinite(spread):
            return -math.inf
        middle, half = 0.5 * (t0 + t1), 0.5 * (t1 - t0)
        n = store.direction(middle, k)
        if n is None:
            return -math.inf
        placements = store.at(middle)
        chain_a, chain_b = self._chains(k)
        low_b = self._extreme(b, points_b, placements[b], n, chain_b, middle, half, -1.0)
        high_a = self._extreme(a, points_a, placements[a], n, chain_a, middle, half, 1.0)
        value = low_b - high_a - 0.5 * spread * half * half
        return value if value > 0.0 else -math.inf

    def _chains(self, k: int) -> tuple[_Chain, _Chain]:
        """The joints that move pair k's first body but not its second, and the reverse."""
        if k not in self._pair_chains:
            a, b = self._store.mesh.pairs[k]
            moves_a, moves_b = self._reach[a] > 0.0, self._reach[b] > 0.0
            self._pair_chains[k] = (
                _Chain(np.flatnonzero(moves_a & ~moves_b), self._reach[a]),
                _Chain(np.flatnonzero(moves_b & ~moves_a), self._reach[b]),
            )
        return self._pair_chains[k]

    def _extreme(
        self,
        i: int,
        points: tuple[np.ndarray, float],
        placement: np.ndarray,
        n: np.ndarray,
        chain: _Chain,
        middle: float,
        half: float,
        side: float,
    ) -> float:
        """Object i's least (``side`` -1) or largest (+1) ``n.x`` over the interval (m).

        To first order: each point's value at the middle less (or plus) ``half`` (s) times its
        rate along ``n`` (m/s); the second-order term is the caller's.
        """
        local, radius = points
        rotation, origin = placement[:3, :3], placement[:3, 3]
        if len(chain.columns):
            rates = self._store.velocities[middle][chain.columns]
            jacobian = self._jacobian(middle, self._parents[i])[:, chain.columns]
            twist = jacobian @ rates  # at the frame's origin
            linear, angular = twist[:3], twist[3:]
            # a point x moves at linear + angular x x: along n, n.linear + x.(n x angular)
            turn = _cross(n, angular)
            both = local @ (rotation.T @ np.stack([n, turn], axis=1))
            values = both[:, 0] + float(n @ origin)
            rates_n = both[:, 1] + float(turn @ origin) + float(n @ linear)
            values = values + side * half * np.abs(rates_n)
        else:
            values = local @ (rotation.T @ n) + float(n @ origin)
        if side < 0.0:
            return float(np.min(values)) - radius
        return float(np.max(values)) + radius

    def _jacobian(self, t: float, joint: int) -> np.ndarray:
        """(6, N) the joint's Jacobian in the spacecraft frame at ``t`` over the arm joints.

        Every object's joint's at once, per instant (the model's data then moves on).
        """
        found = self._jacobians.get(t)
        if found is None:
            model = self._store.mesh.robot.model
            q = self._store.mesh.robot.configuration(self._store.joints[t])
            pin.computeJointJacobians(model, self._data, q)
            world = pin.ReferenceFrame.WORLD
            found = self._jacobians[t] = {
                j: pin.getJointJacobian(model, self._data, j, world)[:, self._columns]
                for j in set(self._parents)
            }
        return found[joint]

    def _points_of(self, i: int) -> tuple[np.ndarray, float] | None:
        if i not in self._points:
            self._points[i] = self._store.mesh.separation.points(i)
        return self._points[i]


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``u x v`` of two 3-vectors (numpy's general cross costs far more for one pair)."""
    return np.array(
        [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    )


class _Chain:
    """The joints between the link two bodies hang from and one of them, parents first.

    Attributes:
        columns: their columns among the arm joints (pinocchio's order: parents first).
        pairs: per joint, its column and the body's reach from it (m per rad; 1 for a
            prismatic joint).
    """

    def __init__(self, columns: np.ndarray, reach: np.ndarray) -> None:
        self.columns = columns
        self.pairs = list(zip(columns.tolist(), reach[columns].tolist(), strict=True))


def _acceleration(chain: _Chain, speeds: list[float], accelerations: list[float]) -> float:
    """Bound of any point's acceleration relative to the chain's root link (m/s^2).

    ``speeds``, ``accelerations``: per arm joint, the largest ``|qd|`` and ``|qdd|`` over the
    interval; each joint adds its reach times its acceleration plus its rate times the rate
    of itself and twice those of the joints before it.
    """
    total, before = 0.0, 0.0
    for j, reach in chain.pairs:
        qd = speeds[j]
        total += reach * (accelerations[j] + qd * (qd + 2.0 * before))
        before += qd
    return total
