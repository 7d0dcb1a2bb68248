"""Speed bounds of the certificate's pairs from their bodies' lever arms (:mod:`.levers`).

The certificate (:mod:`freefloat.verify.certificate`) bounds each (interval, pair) from the
pair's speed. Where the bodies' reach from the joints leaves an interval open, that speed
comes from their lever arms about the joints' axes instead: for each interval of the first,
uniform pass and each pair, the arms that hold over the whole interval are worked out once
(from the arms at its two ends) and kept as weights ``w`` (N,), so that the pair's speed on
the interval, or on any part of it with joint-rate bounds ``m`` there, is at most ``m @ w``:
a part of an interval has its lever arms within the whole interval's, and its rates within
its own bounds. Never above the reach's (``pair_reach``).
"""

from __future__ import annotations

import bisect

import numpy as np

from .instants import Instants

__all__ = ["IntervalLevers"]


class IntervalLevers:
    """Lever-arm speed weights per interval of the first pass and pair, each worked out once.

    Args:
        store: the certificate's instants (placements, rates).
        times: the first pass's instants (s), ascending.
    """

    def __init__(self, store: Instants, times: np.ndarray) -> None:
        self.store, self.mesh = store, store.mesh
        self.times = times.tolist()
        self._axes: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._pairs: dict[tuple[int, int], np.ndarray] = {}
        #: (K, G, N) every body's lever arms at every instant, once the first pass asked.
        self._grid: np.ndarray | None = None

    def interval(self, t: float) -> int:
        """The first pass's interval that holds ``[t, t + dt]`` for a later ``t + dt`` (s)."""
        return min(bisect.bisect_right(self.times, t) - 1, len(self.times) - 2)

    def first_pass(
        self, rates: np.ndarray, items: tuple[np.ndarray, np.ndarray], placements: np.ndarray
    ) -> np.ndarray:
        """(X,) each pair ``pairs[x]``'s speed bound on interval ``rows[x]`` (m/s), at once.

        ``rates``: (K - 1, N) the joint-rate bounds on every interval (rad/s or m/s);
        ``items``: (rows, pairs); ``placements``: (K, G, 4, 4) the body poses at the first
        pass's instants.
        """
        rows, pairs = items
        if len(rows) == 0:
            return np.zeros(0)
        mesh, levers = self.mesh, self.mesh.levers
        found = levers.axes_from(placements)
        if found is None:  # a joint's link carries no object: from the joints' frames
            each = [self._axis(i) for i in range(len(self.times))]
            found = (np.array([a[0] for a in each]), np.array([a[1] for a in each]))
        centres = np.einsum("kgij,gj->kgi", placements[..., :3, :3], mesh.centres)
        centres += placements[..., :3, 3]
        bodies = np.arange(len(mesh.centres))[None]
        arms = levers.arms(found[0][:, None], found[1][:, None], centres, bodies)  # (K, G, N)
        self._grid = arms
        widths = np.diff(np.asarray(self.times))[rows]
        both = sum(
            levers.lever(
                widths,
                rates[rows],
                (arms[rows, body][:, None], arms[rows + 1, body][:, None]),
                levers.centre_t[body][:, None],
                levers.reach_t[body][:, None],
            )[:, 0]
            for body in (mesh.first[pairs], mesh.second[pairs])
        )
        return np.einsum("xn,xn->x", both * mesh.free[pairs], rates[rows])

    def pair(self, i: int, k: int) -> np.ndarray:
        """(N,) pair k's speed weights on interval i and its parts (m per rad, or 1)."""
        if (i, k) not in self._pairs:
            levers, bodies = self.mesh.levers, self.mesh.pair_bodies[k]
            lever = levers.lever(
                self._widths(i),
                self._rates(i),
                (self._body_arms(i)[bodies][None], self._body_arms(i + 1)[bodies][None]),
                levers.centre_t[bodies],
                levers.reach_t[bodies],
            )[0]
            self._pairs[(i, k)] = (lever[0] + lever[1]) * self.mesh.free[k]
        return self._pairs[(i, k)]

    def _widths(self, i: int) -> np.ndarray:
        return np.array([self.times[i + 1] - self.times[i]])

    def _rates(self, i: int) -> np.ndarray:
        """(1, N) the joint-rate bounds on interval i (kept by the store)."""
        return self.store.rates([self.times[i]], [self.times[i + 1]])

    def _axis(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """The joints' origins and unit axes (N, 3) at the first pass's instant i."""
        if i not in self._axes:
            levers, t = self.mesh.levers, self.times[i]
            found = levers.axes_from(self.store.at(t))
            if found is None:
                found = levers.axes_at(self.mesh.frames(self.store.joints[t]))
            self._axes[i] = found
        return self._axes[i]

    def _body_arms(self, i: int) -> np.ndarray:
        """(G, N) every body's lever arms at the first pass's instant i (m; :meth:`first_pass`)."""
        if self._grid is None:
            raise RuntimeError("lever arms asked for before the first pass")
        return self._grid[i]
