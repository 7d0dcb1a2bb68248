"""Clearance: every checked pair of bodies stays at least a margin apart along the path.

The pairs and their signed distances come from the robot's collision model (convex hulls,
coal's GJK/EPA; see :mod:`freefloat.robot.collision`). Obstacles are fixed to the spacecraft,
so clearance is a function of the joints alone.

For the solvers, each instant contributes one row: the margin minus the smallest distance over
the pairs the free coefficients move there (m; a pair none moves, of an arm that holds its
pose say, would give a row with no gradient that hides the pairs the solver can move; the
dense check takes every pair), with its gradient from the witness points of that pair and the
joint Jacobians, chained with the path's linear dependence on ``beta``.
The instants are a uniform grid refined around the minima of clearance, and the instants a
solver adds (where its dense check found a path below the margin:
:meth:`Clearance.critical_times`); the rows ask for a little more than the margin
(:data:`SOLVER_SLACK`) so that the dips between instants stay outside it.

The dense check samples the whole path (:data:`VERIFY_SAMPLES`), refines every near-minimum by
a bounded scalar search in time, and estimates its own error by step doubling (the same search
on every other sample).
"""

from __future__ import annotations

import math

import numpy as np

from ...robot.collision import CollisionModel
from ...robot.model import Robot
from ..paths import JointPolynomials, PathFamily
from ..residual import Problem
from .base import DEFAULT_INSTANTS, Constraint, ConstraintRows, Excess
from .clearance_samples import (
    Measured,
    MovedPairs,
    RowsAtBeta,
    arms_table,
    bounds_between,
    lever_arms,
    local_minima,
    lowest_minima,
    minima_floors,
    pair_bounds,
    refined_minima,
    refinement,
    undecided,
)

__all__ = [
    "COARSE_EVERY",
    "HALVINGS",
    "NEAR",
    "REFINE",
    "SOLVER_SLACK",
    "Clearance",
]

#: Extra clearance the solvers ask for beyond the margin, between constraint instants (m).
SOLVER_SLACK = 2e-3
#: Halvings of the intervals a bound cannot clear (the solvers' dense check).
HALVINGS = 12
#: Samples of the dense verification check (every near-minimum is then refined in time).
VERIFY_SAMPLES = 401
#: Extra instants per grid interval next to a local minimum of clearance.
REFINE = 3
#: Sampled local minima of clearance within this of the smallest are refined in time (m).
NEAR = 0.01
#: The solvers' dense check first measures every this many of its samples, and the ones
#: between only where the bound between measured samples does not clear the margin.
COARSE_EVERY = 8
#: A lowest point of clearance along a path: the distance (m), its time (s) and its pair.
Lowest = tuple[float, float, int]


class Clearance(Constraint):
    """Every checked pair at least ``margin`` apart (m) at every instant of the path.

    Args:
        model: the robot's collision model (pairs, obstacles).
        margin: required clearance (m), >= 0.
    """

    name = "clearance"
    unit = "m"
    tolerance = 1e-6
    affine = False
    own_instants = True

    def __init__(self, model: CollisionModel, margin: float = 0.01) -> None:
        if not (math.isfinite(margin) and margin >= 0.0):
            raise ValueError(f"clearance margin must be a finite number >= 0 m, got {margin!r}")
        self.model = model
        self.margin = float(margin)
        self._memo: tuple[PathFamily, bytes, ConstraintRows] | None = None
        self._picked: tuple[PathFamily, bytes, np.ndarray] | None = None
        self._at_beta = RowsAtBeta()  # the rows of the last beta, per instant
        self._smallest_memo: dict[tuple[bytes, float, int, int], Lowest] = {}
        self._sampled_memo: tuple[tuple[bytes, float, int], np.ndarray] | None = None
        self._measured_memo: tuple[tuple[bytes, float, int, float | None], Measured] | None = None
        self._below_memo: tuple[tuple[bytes, float, int, float], Lowest] | None = None
        self._moved = MovedPairs(model)  # the pairs the rows take, per path family

    def __repr__(self) -> str:
        return f"Clearance(margin={self.margin:g} m, {self.model.n_pairs} pairs)"

    def applies_to(self, robot: Robot) -> bool:
        """True when the collision model has pairs to check."""
        return self.model.n_pairs > 0

    def rows(
        self, problem: Problem, beta: np.ndarray, instants: np.ndarray = DEFAULT_INSTANTS
    ) -> ConstraintRows:
        """``margin + slack - min_pair d(q(s))`` (m) and its exact gradient, one row an instant.

        The smallest over the pairs the free coefficients move (:class:`MovedPairs`). Clearance
        picks its own instants: the uniform grid :data:`DEFAULT_INSTANTS`, plus :data:`REFINE`
        instants in each grid interval next to each of the two lowest local minima on that
        grid; and it keeps the ``instants`` asked beyond that grid (the solvers ask only at the
        dips they found below the margin, :meth:`critical_times`). For given ``instants`` the
        number of rows is fixed, as SLSQP needs.
        """
        beta = np.asarray(beta, dtype=float)
        key = beta.tobytes() + np.asarray(instants, dtype=float).tobytes()
        # The rows depend on the family and beta only: continuation's targets share them.
        if self._memo is not None and self._memo[0] is problem.family and self._memo[1] == key:
            return self._memo[2]
        grid = DEFAULT_INSTANTS
        values_grid, jacobian_grid = self._rows_at(problem, beta, grid)
        coarse = self.margin + SOLVER_SLACK - values_grid  # the smallest distance there
        refined = np.concatenate([refinement(grid, k, REFINE) for k in lowest_minima(coarse)])
        passed = np.setdiff1d(np.asarray(instants, dtype=float), np.union1d(grid, refined))
        extra = np.concatenate([refined, passed])
        values_extra, jacobian_extra = self._rows_at(problem, beta, extra)
        values = np.concatenate([values_grid, values_extra])
        jacobian = np.concatenate([jacobian_grid, jacobian_extra])
        rows = ConstraintRows(values, jacobian)
        self._memo = (problem.family, key, rows)  # solvers ask several times at one beta
        self._picked = (problem.family, beta.tobytes(), refined)  # with it: the same beta
        return rows

    def picked_instants(self, problem: Problem, beta: np.ndarray) -> np.ndarray:
        """The instants :meth:`rows` refines at ``beta`` beyond the grid (normalised)."""
        beta = np.asarray(beta, dtype=float)
        picked = self._picked
        if picked is None or picked[0] is not problem.family or picked[1] != beta.tobytes():
            self.rows(problem, beta, DEFAULT_INSTANTS)
            picked = self._picked
        assert picked is not None
        return picked[2]

    def _rows_at(
        self, problem: Problem, beta: np.ndarray, instants: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Row values (m) and Jacobian at ``instants``, each measured once per beta (RowsAtBeta)."""
        among = self._moved(problem.family)

        def measure(at: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            base, dq, _ = problem.family.linear_map(at)
            joints = base.q + dq @ beta
            closest = self.model.closest_many(joints, at, gradients=True, among=among)
            assert closest.gradients is not None
            jacobian = -np.einsum("kn,knf->kf", closest.gradients, dq)
            return self.margin + SOLVER_SLACK - closest.values, jacobian

        return self._at_beta.rows(problem.family, beta, np.asarray(instants, float), measure)

    def critical_times(self, robot: Robot, path: JointPolynomials) -> np.ndarray:
        """The time (s) of the smallest clearance along ``path`` when it breaks the margin.

        The solvers' dense check (:meth:`violation`, the same answer: remembered for the last
        path) found the path below the margin there; a solver that adds the time to its
        instants gets a row there (:meth:`rows`) and corrects the dip itself, where the
        grid's rows alone would bring back the same path. None when the path keeps the margin.
        """
        if self.model.n_pairs == 0:
            return np.zeros(0)
        lowest = self._solvers_check(path)[1]
        if lowest is None or lowest[0] >= self.margin - self.tolerance:  # not broken
            return np.zeros(0)
        return np.array([lowest[1]])

    def smallest(self, path: JointPolynomials, samples: int, every: int = 1) -> Lowest:
        """Smallest clearance along ``path`` (m), its time (s) and pair, from ``samples``.

        Only every ``every``-th of the samples is used (the verification's coarser estimate of
        its own error); with every sample, those a bound shows to lie more than
        :data:`NEAR` above the smallest are not measured (:meth:`_measured`: they can be
        neither the smallest nor a local minimum near it, so the answer is the same). Every
        sampled local minimum within :data:`NEAR` of the smallest is
        refined by a bounded scalar search between its neighbouring samples. The last few
        answers are remembered (solvers ask several times about one path).
        """
        key = (path.coefficients.tobytes(), path.duration, samples, every)
        if key in self._smallest_memo:
            return self._smallest_memo[key]
        t_all = np.linspace(0.0, path.duration, samples)
        if every == 1:  # the samples a bound cannot spare: the rest are above best + NEAR
            sampled_all = np.nan_to_num(self._measured(path, samples, None).known, nan=math.inf)
        else:
            sampled_all = self._sampled(path, t_all)
        t, sampled = t_all[::every], sampled_all[::every]

        minima = local_minima(sampled)
        best, best_t, best_pair = refined_minima(
            self.model, path, t, sampled, minima[sampled[minima] <= float(sampled.min()) + NEAR]
        )
        answer = (best, best_t, best_pair)
        if len(self._smallest_memo) >= 16:
            self._smallest_memo.pop(next(iter(self._smallest_memo)))
        self._smallest_memo[key] = answer
        return answer

    def _sampled(self, path: JointPolynomials, t: np.ndarray) -> np.ndarray:
        """Smallest distance over the pairs at each time of ``t`` (m), remembered per path."""
        key = self._key(path, t)
        if self._sampled_memo is None or self._sampled_memo[0] != key:
            q = path.positions(t)
            self._sampled_memo = (key, self.model.closest_many(q).values)
        return self._sampled_memo[1]

    def _measured(self, path: JointPolynomials, samples: int, limit: float | None) -> Measured:
        """The smallest distance (m) at the samples a bound cannot spare, and a lower bound.

        Coarse then exact, a count: the smallest distance over the pairs at every
        :data:`COARSE_EVERY`-th of ``samples`` instants (those of :meth:`smallest`, the same
        bits); between two measured instants each pair's distance is at least the mean of its
        bounds there less half the time between them times how fast its distance can change
        there (bounds of the joint rates times its bodies' lever arms about the joint axes,
        :func:`bounds_between`), and the clearance at least the smallest of these. Where that
        falls below ``limit`` (the margin; or, with None, :data:`NEAR` above the smallest
        measured), the sample halfway is measured too, down to neighbouring samples. Returns
        the distances (NaN where spared: every such sample is above the limit), the pairs'
        bounds and the spheres' lever arms at the samples measured, and the lower bound of the
        clearance along the whole path (m; -inf when the model has no motion weights, a
        prismatic joint say: then nothing bounds the clearance between samples). Remembered
        for the last path and limit only, so that the answer never depends on earlier calls.
        """
        key = (*self._key(path, np.zeros(samples)), limit)
        memo = self._measured_memo
        if memo is not None and memo[0] == key:  # the same path and limit: the same answer
            return memo[1]
        t = np.linspace(0.0, path.duration, samples)
        q = path.positions(t)
        known = np.full(samples, math.nan)
        lower = np.full((samples, self.model.n_pairs), math.nan)
        todo = np.unique(np.append(np.arange(0, samples, COARSE_EVERY), samples - 1))
        if self.model.weights is None:  # no bound between samples: every sample, no bound
            known[:] = self.model.closest_many(q).values
            answer = Measured(known, lower, -math.inf, arms_table(self.model, samples))
            self._measured_memo = (key, answer)
            return answer
        arms = arms_table(self.model, samples)
        # the bound on the interval from each sample, and that interval's end (-1: none yet)
        bounded, ends = np.full(samples, math.nan), np.full(samples, -1)
        with self.model.own_bounds():  # pair bounds from this path's samples alone
            while True:
                todo = todo[np.isnan(known[todo])]
                found = self.model.closest_many(q[todo], todo / (samples - 1))
                known[todo], lower[todo] = found.values, pair_bounds(found)
                arms[todo] = lever_arms(self.model, q[todo])
                nodes = np.flatnonzero(~np.isnan(known))
                a, b = nodes[:-1], nodes[1:]
                new = ends[a] != b  # intervals split since: bounded again, the others kept
                x, y = a[new], b[new]
                bounded[x] = bounds_between(
                    self.model, path, (t[x], t[y]), (lower[x], lower[y]), (arms[x], arms[y])
                )
                ends[x] = y
                between = bounded[a]
                floor = float(np.nanmin(known)) + NEAR if limit is None else limit
                short = (between < floor) & (b - a >= 2)
                if not np.any(short):
                    bound = float(min(between.min(), np.nanmin(known)))
                    break
                todo = (a[short] + b[short]) // 2
        answer = Measured(known, lower, bound, arms)
        self._measured_memo = (key, answer)
        return answer

    def _below(self, path: JointPolynomials, measured: Measured, limit: float) -> Lowest:
        """The smallest clearance (m), its time (s) and pair, for a path a bound cannot clear.

        ``measured``: :meth:`_measured` with ``limit`` (m; NaN where spared: above it). An
        interval between samples both above ``limit`` where the bound falls below it is
        halved, measuring its middle, until the bound clears ``limit`` on each half or a
        sample falls below it, at most :data:`HALVINGS` times; the sampled local minima below
        ``limit``, and the middles of halves left undecided, are then refined by a bounded
        scalar search. Once a sample lies below ``limit``, only intervals whose bound falls
        below the smallest sample so far are halved: no other can hold the smallest clearance.
        """
        key = (*self._key(path, measured.known), limit)
        if self._below_memo is not None and self._below_memo[0] == key:  # the same answer
            return self._below_memo[1]
        known, table, arms = measured.known, measured.lower, measured.arms
        t = np.linspace(0.0, path.duration, len(known))
        times, values = [t], [np.nan_to_num(known, nan=math.inf)]
        rows = np.arange(len(known), dtype=float)
        # Rows: t0, t1 (s), v0, v1 (m), and the rows of ``table`` (pair bounds) at t0 and t1.
        ends = np.stack([t[:-1], t[1:], known[:-1], known[1:], rows[:-1], rows[1:]])
        with self.model.own_bounds():  # pair bounds from this path's samples alone
            for _ in range(HALVINGS):
                lowest = float(min(np.min(v, initial=math.inf) for v in values))
                ends = ends[:, undecided(self.model, path, ends, (table, arms), limit, lowest)]
                if ends.shape[1] == 0:
                    break
                mid = 0.5 * (ends[0] + ends[1])
                q_mid = path.positions(mid)
                found = self.model.closest_many(q_mid, mid / path.duration)
                vm, at = found.values, np.arange(len(table), len(table) + len(mid), dtype=float)
                table = np.concatenate([table, pair_bounds(found)])
                arms = np.concatenate([arms, lever_arms(self.model, q_mid)])
                times.append(mid)
                values.append(vm)
                ends = np.concatenate(
                    [
                        np.stack([ends[0], mid, ends[2], vm, ends[4], at]),
                        np.stack([mid, ends[1], vm, ends[3], at, ends[5]]),
                    ],
                    axis=1,
                )
        if ends.shape[1]:
            lowest = float(min(np.min(v, initial=math.inf) for v in values))
            ends = ends[:, undecided(self.model, path, ends, (table, arms), limit, lowest)]
        t_all, v_all = np.concatenate(times), np.concatenate(values)
        order = np.argsort(t_all, kind="stable")  # the samples' rows of table, in time
        t_all, v_all = t_all[order], v_all[order]
        minima = local_minima(v_all)
        minima = minima[v_all[minima] < limit]
        spans = np.searchsorted(t_all, 0.5 * (ends[0] + ends[1]))
        chosen = np.unique(np.append(minima, spans))
        floors = minima_floors(self.model, path, t_all, chosen, (table[order], arms[order]))
        answer = refined_minima(self.model, path, t_all, v_all, chosen, floors)
        self._below_memo = (key, answer)
        return answer

    @staticmethod
    def _key(path: JointPolynomials, t: np.ndarray) -> tuple[bytes, float, int]:
        return (path.coefficients.tobytes(), path.duration, len(t))

    def _solvers_check(self, path: JointPolynomials) -> tuple[float, Lowest | None]:
        """The solvers' dense check of ``path`` (201 samples): its bound and its lowest point.

        The bound of the clearance along the path (m), and where it does not clear the margin,
        the smallest clearance (m), its time (s) and pair (None when it clears it).
        """
        measured = self._measured(path, 201, self.margin)
        if measured.bound >= self.margin:
            return measured.bound, None
        if self.model.weights is None:
            return measured.bound, self.smallest(path, 201)
        return measured.bound, self._below(path, measured, self.margin)

    def excess(self, robot: Robot, path: JointPolynomials) -> Excess:
        """``margin - smallest clearance`` along the path (m), with its own error estimate."""
        if self.model.n_pairs == 0:
            return Excess(-math.inf, 0.0, "no pairs to check")
        fine = self.smallest(path, VERIFY_SAMPLES)
        coarse = self.smallest(path, VERIFY_SAMPLES, every=2)  # the same distances, halved
        clearance, when, pair = fine
        estimate = abs(coarse[0] - fine[0])
        detail = (
            f"min clearance {clearance:.6g} m ({self.model.names[pair]}) at t = {when:.4g} s, "
            f"margin {self.margin:g} m"
        )
        return Excess(self.margin - clearance, estimate, detail)

    def violation(self, problem: Problem, beta: np.ndarray) -> Excess:
        """The excess of the problem's path at ``beta`` for solvers (201 samples, refined).

        Verification uses :meth:`excess` (twice as dense, with its error estimate).
        """
        if self.model.n_pairs == 0:
            return Excess(-math.inf, 0.0, "no pairs to check")
        path = problem.polynomials(beta)
        bound, lowest = self._solvers_check(path)
        if lowest is None:  # clear everywhere: the refined minimum is not needed
            detail = f"min clearance >= {bound:.6g} m everywhere, margin {self.margin:g} m"
            return Excess(self.margin - bound, 0.0, detail)
        clearance, when, pair = lowest
        detail = (
            f"min clearance {clearance:.6g} m ({self.model.names[pair]}) at t = {when:.4g} s, "
            f"margin {self.margin:g} m"
        )
        return Excess(self.margin - clearance, 0.0, detail)
