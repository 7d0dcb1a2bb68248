"""What the clearance certificate knows of each instant (:mod:`freefloat.verify.certificate`).

Joint values and rate bounds, placements, exact pair distances and leaf-pair gaps, each
computed once per instant (or interval) and kept for the certificate's later questions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .clearance import MeshClearance, Placed
from .motion import PolynomialMotion

__all__ = ["Instants"]


class Instants:
    """Placements, joint speeds and exact distances per instant, each computed once.

    The joint values and rates of an instant come from one evaluation of the paths (several
    instants per evaluation when they are asked for together); the rates' absolute values
    give the ends of the speed bound of every interval that ends there. An instant's
    placements are computed when first used.
    """

    def __init__(self, mesh: MeshClearance, motion: PolynomialMotion) -> None:
        self.mesh, self.motion = mesh, motion
        self.joints: dict[float, np.ndarray] = {}
        self.placements: dict[float, np.ndarray] = {}
        self.placed: dict[float, Placed] = {}
        self.speeds: dict[float, np.ndarray] = {}
        #: Signed joint rates (rad/s or m/s) and absolute accelerations per instant.
        self.velocities: dict[float, np.ndarray] = {}
        self.accelerations: dict[float, np.ndarray] = {}
        self.directions: dict[tuple[float, int], np.ndarray | None] = {}
        self.exact: dict[tuple[float, int], float] = {}
        self.separated: dict[tuple[float, int], float] = {}
        self.leaf_gaps: dict[tuple[float, int], np.ndarray] = {}
        self.interval_rates: dict[tuple[float, float], np.ndarray] = {}
        self.interval_accelerations: dict[tuple[float, float], np.ndarray] = {}
        self.leaf_speeds: dict[int, np.ndarray] = {}
        #: The first pass's leaf-pair gaps (see :meth:`keep_gaps`), looked up when asked for.
        self.grid: dict[float, int] = {}
        self.grid_gaps: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None

    def load(self, times: np.ndarray) -> None:
        """Joint values and speeds at many instants (s), evaluated in one call."""
        joints, rates, accelerations = self.motion.path(np.asarray(times, dtype=float))
        for t, q, qd, qdd in zip(times.tolist(), joints, rates, accelerations, strict=True):
            if t not in self.joints:
                self.joints[t], self.speeds[t], self.velocities[t] = q, np.abs(qd), qd
                self.accelerations[t] = np.abs(qdd)

    def at(self, t: float) -> np.ndarray:
        """(G, 4, 4) placements at ``t`` (s)."""
        if t not in self.placements:
            if t not in self.joints:
                self.load(np.array([t]))
            self.placements[t] = self.mesh.placements(self.joints[t])
        return self.placements[t]

    def rates(self, t0: Sequence[float], t1: Sequence[float]) -> np.ndarray:
        """(K, N) largest ``|qd_j|`` over each ``[t0, t1]`` (rad/s or m/s), each kept.

        Row by row the bound of one interval alone (:meth:`PolynomialMotion.rate_bounds`
        works row by row), so an interval asked for again gets the same figures.
        """
        rates = self.interval_rates
        if len(t0) == 1 and (t0[0], t1[0]) in rates:
            return rates[(t0[0], t1[0])][None]
        for t in (*t0, *t1):
            self.at(t)
        ends = np.array([self.speeds[t] for t in (*t0, *t1)])
        found = self.motion.rate_bounds(np.array(t0), np.array(t1), ends)
        for a, b, row in zip(t0, t1, found, strict=True):
            rates[(a, b)] = row
        return found

    def leaf_reach(self, k: int) -> np.ndarray:
        """(N, R) the speed coefficients of pair k's leaf pairs (:attr:`LeafSpheres.row_reach`)."""
        if k not in self.leaf_speeds:
            leaves = self.mesh.leaves
            self.leaf_speeds[k] = leaves.row_reach[:, leaves.rows_of(k)]
        return self.leaf_speeds[k]

    def keep_gaps(
        self,
        times: np.ndarray,
        codes: np.ndarray,
        starts: np.ndarray,
        gaps: np.ndarray,
    ) -> None:
        """Keep the leaf-pair gaps the first pass computed, for :meth:`gaps` to look up.

        ``codes``: sorted ``instant * P + pair`` of each (instant of ``times``, pair) cell;
        ``starts``: where each cell's run of leaf pairs begins in ``gaps`` (m), the cell's
        pair's leaf pairs in order, as :meth:`gaps` gives them.
        """
        self.grid = {t: i for i, t in enumerate(times.tolist())}
        self.grid_gaps = (
            codes,
            starts,
            starts + self.mesh.leaves.count[codes % len(self.mesh.pairs)],
            gaps,
        )

    def _kept_gaps(self, t: float, k: int) -> np.ndarray | None:
        """Pair k's leaf-pair gaps at ``t`` (m) if the first pass computed them."""
        if self.grid_gaps is None or t not in self.grid:
            return None
        codes, starts, ends, gaps = self.grid_gaps
        code = self.grid[t] * len(self.mesh.pairs) + k
        at = int(np.searchsorted(codes, code))
        if at == len(codes) or codes[at] != code:
            return None
        return gaps[starts[at] : ends[at]]

    def gaps(self, t: float, k: int) -> np.ndarray:
        """Lower bounds (m) of the distance between the leaves of each of pair k's leaf pairs."""
        if (t, k) not in self.leaf_gaps and (kept := self._kept_gaps(t, k)) is not None:
            self.leaf_gaps[(t, k)] = kept
        if (t, k) not in self.leaf_gaps:
            self.leaf_gaps[(t, k)] = self.mesh.leaves.pair_gaps(self.at(t), k)
        return self.leaf_gaps[(t, k)]

    def distance(self, t: float, k: int) -> float:
        """Pair k's exact signed distance at ``t`` (m; :meth:`MeshClearance.exact_placed`)."""
        if (t, k) not in self.exact:
            self.exact[(t, k)] = self.mesh.exact_placed(self._placed(t), k)
        return self.exact[(t, k)]

    def lower(self, t: float, k: int) -> float:
        """A lower bound of pair k's distance at ``t`` (m): the exact distance if measured.

        Otherwise, for a pair of two meshes, the separating-direction bound
        (:mod:`.separation`); -inf when it gives none, and for the other pairs (whose exact
        query costs about as much).
        """
        if (t, k) in self.exact:
            return self.exact[(t, k)]
        if k not in self.mesh.separable:
            return -math.inf
        return self.separation(t, k)

    def separation(self, t: float, k: int) -> float:
        """Pair k's separating-direction bound at ``t`` (m; -inf when none), kept.

        Positive: a plane separates the two bodies (:mod:`.separation`), any pair.
        """
        if (t, k) not in self.separated:
            n = self.direction(t, k)
            a, b = self.mesh.pairs[k]
            placements = self.at(t)
            self.separated[(t, k)] = (
                -math.inf
                if n is None
                else self.mesh.separation.along(a, b, placements[a], placements[b], n)
            )
        return self.separated[(t, k)]

    def direction(self, t: float, k: int) -> np.ndarray | None:
        """The unit direction GJK proposes between pair k's hulls at ``t`` (None: none), kept."""
        if (t, k) not in self.directions:
            a, b = self.mesh.pairs[k]
            placed = self._placed(t)
            transforms = (placed.transform(a), placed.transform(b))
            self.directions[(t, k)] = self.mesh.separation.direction(a, b, transforms)
        return self.directions[(t, k)]

    def acceleration_bounds(self, t0: float, t1: float) -> np.ndarray:
        """(N,) largest ``|qdd_j|`` over ``[t0, t1]`` (rad/s^2 or m/s^2)."""
        found = self.interval_accelerations.get((t0, t1))
        if found is None:
            for t in (t0, t1):
                if t not in self.joints:
                    self.load(np.array([t]))
            ends = np.array([self.accelerations[t0], self.accelerations[t1]])
            found = self.motion.acceleration_bounds(np.array([t0]), np.array([t1]), ends)[0]
            self.interval_accelerations[(t0, t1)] = found
        return found

    def _placed(self, t: float) -> Placed:
        """The instant ``t`` (s) placed for queries, kept."""
        if t not in self.placed:
            self.placed[t] = Placed(self.mesh, self.at(t))
        return self.placed[t]
