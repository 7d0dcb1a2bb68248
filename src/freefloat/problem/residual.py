"""The planning problem, built apart from its solution (docs/method.md section 5).

A :class:`Problem` holds the robot, the start and goal, the path family and the integration
grid, and evaluates the residual ``h(beta)``: the attitude reached at the end of the path minus
the attitude wanted (rad). Planar systems have one equation (yaw, not wrapped, against the
requested yaw change); others have three (the rotation vector from the goal attitude to the
reached one, in the goal frame).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..physics.attitude import (
    GAUSS3_WEIGHTS,
    magnus_increment_jacobian,
    magnus_increments,
    propagate,
    quat_exp,
    quat_log,
    quat_multiply,
    quat_to_matrix,
    relative_quat,
    relative_rotvec,
    so3_right_jacobian,
    step_nodes,
)
from ..physics.momentum import MomentumMap, NodeRates
from ..physics.planar_map import PlanarMap
from ..robot.model import Robot
from .bounds import PlanarBounds
from .paths import JointPolynomials, PathFamily

__all__ = ["EvaluationCounter", "Problem", "wrap_angle"]

#: Target of the integration error estimate (rad) when choosing the number of steps.
INTEGRATION_TOLERANCE = 1e-12
_MIN_STEPS, _MAX_STEPS = 16, 4096
#: Residual values a problem and its copies at other step counts remember.
MEMO_SIZE = 16


def wrap_angle(angle: float) -> float:
    """Angle wrapped to (-pi, pi] (rad)."""
    wrapped = math.remainder(angle, 2.0 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped


@dataclass(eq=False)
class Problem:
    """A point-to-point planning problem for a free floater.

    Attributes:
        robot: the robot.
        mmap: its momentum map evaluator.
        family: joint path family (start, goal, degrees).
        duration: motion time T (s).
        start_quaternion: base attitude at t = 0, ``[x, y, z, w]``.
        goal_quaternion: wanted base attitude at t = T, ``[x, y, z, w]``.
        planar: whether the base only turns about one axis (``axis``).
        bounds: planar gain extremes (planar problems only).
        yaw_change: requested yaw change (rad), on the branch inside the bounds (planar only).
        axis: the axis a planar base turns about (unit vector, base frame); "yaw" is the
            rotation about it.
        planar_map: cosine-polynomial gains of a planar all-revolute robot (vectorised fast
            path, identified from and checked against Pinocchio); None otherwise.
        steps: number of integration steps on the normalised interval [0, 1].
        counter: evaluations so far, shared with copies at other step counts.
    """

    robot: Robot
    mmap: MomentumMap
    family: PathFamily
    duration: float
    start_quaternion: np.ndarray
    goal_quaternion: np.ndarray
    planar: bool
    bounds: PlanarBounds | None = None
    yaw_change: float | None = None
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    planar_map: PlanarMap | None = None
    steps: int = 64
    counter: EvaluationCounter = field(default_factory=lambda: EvaluationCounter())
    _grid: tuple[np.ndarray, ...] = field(default=(), init=False, repr=False)
    _grids: dict[int | str, tuple[np.ndarray, ...]] = field(
        default_factory=dict, init=False, repr=False
    )
    _memo: dict[tuple[int, bytes], np.ndarray] = field(default_factory=dict, init=False, repr=False)
    _evaluated: tuple[tuple[int, bytes], np.ndarray, np.ndarray] | None = field(
        default=None, init=False, repr=False
    )

    def __post_init__(self) -> None:
        self._use_steps(self.steps)

    @property
    def evaluations(self) -> int:
        """Residual evaluations so far, by this problem and its copies at other step counts."""
        return self.counter.evaluations

    @property
    def map_evaluations(self) -> int:
        """Momentum-map evaluations so far (one per node and path), shared with copies."""
        return self.counter.map_evaluations

    def with_steps(self, steps: int) -> Problem:
        """The same problem on ``steps`` integration steps (a copy; this one is unchanged).

        The copy shares the immutable integration grids, the evaluation counter and the
        remembered residuals (kept by step count).
        """
        if int(steps) == self.steps:
            return self
        other = copy.copy(self)
        other._use_steps(int(steps))
        return other

    def with_duration(self, duration: float) -> Problem:
        """The same problem with motion time ``duration`` (s) (a copy; this one is unchanged).

        The path shape, and so the attitude residual, does not depend on the duration; rates,
        torques and objectives do. The copy shares the grids, the memo and the counter.
        """
        if float(duration) == self.duration:
            return self
        other = copy.copy(self)
        other.duration = float(duration)
        return other

    def with_goal(self, goal_quaternion: np.ndarray) -> Problem:
        """The same problem with another goal attitude ``[x, y, z, w]`` (a copy).

        Spatial problems only (a planar goal is a yaw change). The copy shares the integration
        grids and the evaluation counter; this problem is unchanged.
        """
        if self.planar:
            raise ValueError("with_goal is for spatial problems; a planar goal is a yaw change")
        goal = np.asarray(goal_quaternion, dtype=float)
        other = copy.copy(self)
        other.goal_quaternion = goal / np.linalg.norm(goal)
        other._memo, other._evaluated = {}, None
        return other

    @property
    def n_equations(self) -> int:
        """Number of attitude equations: 1 (planar yaw) or 3."""
        return 1 if self.planar else 3

    @property
    def n_free(self) -> int:
        """Number of free path coefficients."""
        return self.family.n_free

    @property
    def bounds_interval(self) -> tuple[float, float] | None:
        """Reachable yaw-change interval (rad) for this joint motion, planar problems only."""
        if self.bounds is None:
            return None
        return self.bounds.interval(self.family.goal - self.family.start)

    def _use_steps(self, steps: int) -> None:
        """Use ``steps`` uniform integration steps (three Gauss nodes each) on [0, 1]."""
        self.steps = int(steps)
        if self.steps not in self._grids:
            nodes, h = step_nodes(np.linspace(0.0, 1.0, self.steps + 1))
            base, dq, dqs = self.family.linear_map(nodes)
            self._grids[self.steps] = (h, base.q, base.qd, dq, dqs)
        self._grid = self._grids[self.steps]

    def _nodes(self, beta: np.ndarray, derivatives: bool = False) -> tuple[NodeRates, np.ndarray]:
        """Base rates at the integration nodes and the joint rates there (per unit s)."""
        _, q0, qs0, dq, dqs = self._grid
        beta = np.asarray(beta, dtype=float)
        if not np.all(np.isfinite(beta)):
            raise FloatingPointError("non-finite free path coefficients")
        q = q0 + dq @ beta
        qs = qs0 + dqs @ beta
        self.counter.evaluations += 1
        self.counter.map_evaluations += len(q)
        return self.mmap.base_rates(q, qs, derivatives), qs

    def planar_rates(self, betas: np.ndarray) -> np.ndarray:
        """Planar problems: yaw rate at the nodes for several ``beta`` at once, (G, K)."""
        _, q0, qs0, dq, dqs = self._grid
        betas = np.atleast_2d(np.asarray(betas, dtype=float))
        q = q0[None] + np.einsum("knf,gf->gkn", dq, betas)
        qs = qs0[None] + np.einsum("knf,gf->gkn", dqs, betas)
        if self.planar_map is not None:
            self.counter.evaluations += len(betas)
            self.counter.map_evaluations += q.shape[0] * q.shape[1]
            return np.sum(self.planar_map.gains(q) * qs, axis=-1)
        return np.stack([self._nodes(b)[0].omega @ self.axis for b in betas])

    def yaw_changes_and_slopes(self, betas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One-unknown planar problems with a planar map: yaw changes and d/dbeta, (G,) each."""
        assert self.planar_map is not None and self.n_free == 1
        h, q0, qs0, dq, dqs = self._grid
        betas = np.asarray(betas, dtype=float).reshape(-1)
        q = q0[None] + dq[None, :, :, 0] * betas[:, None, None]
        qs = qs0[None] + dqs[None, :, :, 0] * betas[:, None, None]
        gains, dgains = self.planar_map.gains_and_derivatives(q)
        self.counter.evaluations += len(betas)
        self.counter.map_evaluations += q.shape[0] * q.shape[1]
        weights = (h[:, None] * GAUSS3_WEIGHTS[None, :]).ravel()
        rate = np.sum(gains * qs, axis=-1)
        dgains_dbeta = (dgains @ dq[None, :, :, :])[..., 0]  # (G, K, N)
        slope = np.sum(dgains_dbeta * qs + gains * dqs[None, :, :, 0], axis=-1)
        return rate @ weights, slope @ weights

    def yaw_changes(self, betas: np.ndarray) -> np.ndarray:
        """Planar problems: yaw change (rad) for each row of ``betas`` (vectorised)."""
        h = self._grid[0]
        weights = (h[:, None] * GAUSS3_WEIGHTS[None, :]).ravel()
        return self.planar_rates(betas) @ weights

    def rates(self, beta: np.ndarray) -> np.ndarray:
        """Base angular velocity at the integration nodes, (steps, 3, 3), rad per unit s."""
        if self.planar and self.planar_map is not None:
            rate = self.planar_rates(beta)[0]
            return np.outer(rate, self.axis).reshape(self.steps, 3, 3)
        omega = self._nodes(beta)[0].omega
        if self.planar:
            omega = np.outer(omega @ self.axis, self.axis)
        return omega.reshape(self.steps, 3, 3)

    def yaw_change_of(self, beta: np.ndarray) -> float:
        """Planar problems: yaw change over the path (rad), a plain Gauss-Legendre integral."""
        return float(self.yaw_changes(beta)[0])

    def achieved(self, beta: np.ndarray) -> np.ndarray:
        """Base attitude reached at t = T, ``[x, y, z, w]``."""
        if self.planar:
            step = quat_exp(self.yaw_change_of(beta) * self.axis)
            return quat_multiply(self.start_quaternion, step)
        increments = magnus_increments(self.rates(beta), self._grid[0])
        return propagate(self.start_quaternion, increments)[-1]

    def residual(self, beta: np.ndarray) -> np.ndarray:
        """``h(beta)`` (rad): 1 equation (planar) or 3 (rotation vector in the goal frame).

        The last few values are remembered (by step count and ``beta``, with those of this
        problem's copies at other step counts), since the solver asks again for some of them
        (the quintic path's, the chosen root's, a root's on the grids that certify it). A
        spatial problem's value at the last point :meth:`residual_and_jacobian` evaluated is
        taken from there (the same computation).
        """
        key = (self.steps, np.asarray(beta, dtype=float).tobytes())
        if key not in self._memo:
            if len(self._memo) >= MEMO_SIZE:
                self._memo.pop(next(iter(self._memo)))
            last = self._evaluated
            if last is not None and last[0] == key and not self.planar:
                self._memo[key] = last[1]
            else:
                self._memo[key] = self._residual(beta)
        return self._memo[key].copy()

    def _residual(self, beta: np.ndarray) -> np.ndarray:
        if self.planar:
            assert self.yaw_change is not None
            return np.array([self.yaw_change_of(beta) - self.yaw_change])
        reached = self.achieved(beta)
        return relative_rotvec(self.goal_quaternion, reached)

    def residual_and_jacobian(self, beta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``h(beta)`` and its exact Jacobian ``dh/dbeta`` (rad per unit of beta).

        The Jacobian differentiates the discrete scheme itself: node rates through their
        analytic joint derivatives (:class:`~freefloat.physics.centroidal_batch.BatchedCentroidal`)
        and the path's linear dependence on ``beta``; each
        step's Magnus vector by complex steps; the chain of step rotations with SO(3) right
        Jacobians; the residual's logarithm with ``pin.Jlog3``. The last point's are
        remembered (solvers evaluate a root they found again where their next pass starts).
        """
        key = (self.steps, np.asarray(beta, dtype=float).tobytes())
        last = self._evaluated
        if last is None or last[0] != key:
            last = (key, *self._residual_and_jacobian(beta))
            self._evaluated = last
        return last[1].copy(), last[2].copy()

    def _residual_and_jacobian(self, beta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        h, q0, qs0, dq, dqs = self._grid
        if self.planar and self.planar_map is not None:
            assert self.yaw_change is not None
            beta = np.asarray(beta, dtype=float)
            q, qs = q0 + dq @ beta, qs0 + dqs @ beta
            gains, dgains = self.planar_map.gains_and_derivatives(q)
            self.counter.evaluations += 1
            self.counter.map_evaluations += len(q)
            weights = (h[:, None] * GAUSS3_WEIGHTS[None, :]).ravel()
            rate = np.sum(gains * qs, axis=1)
            drate = np.einsum("kif,ki->kf", dgains @ dq, qs) + np.einsum("ki,kif->kf", gains, dqs)
            return np.array([rate @ weights - self.yaw_change]), (weights @ drate)[None, :]
        nodes, _qs = self._nodes(beta, derivatives=True)
        assert nodes.domega_dq is not None
        # d omega / d beta at each node: (K, 3, n_free).
        domega = np.einsum("kij,kjf->kif", nodes.domega_dq, dq) + np.einsum(
            "kij,kjf->kif", nodes.f1, dqs
        )
        omega = nodes.omega.reshape(self.steps, 3, 3)
        domega = domega.reshape(self.steps, 3, 3, self.n_free)
        if self.planar:
            assert self.yaw_change is not None
            weights = h[:, None] * GAUSS3_WEIGHTS[None, :]
            yaw = float(np.sum(weights * (omega @ self.axis))) - self.yaw_change
            gradient = np.einsum("mn,mnif,i->f", weights, domega, self.axis)
            return np.array([yaw]), gradient[None, :]
        increments = magnus_increments(omega, h)
        dw_domega = magnus_increment_jacobian(omega, h)  # (M, 3, 9)
        dw = np.einsum("mck,mkf->mcf", dw_domega, domega.reshape(self.steps, 9, self.n_free))
        quaternions = propagate(self.start_quaternion, increments)
        attitudes = quat_to_matrix(quaternions)
        # after[m] = E_{m+1} ... E_{M} = R_m^T R_M: the rotation that follows step m.
        after = np.einsum("mji,jk->mik", attitudes[1:], attitudes[-1])
        right = so3_right_jacobian(increments)
        dtheta = np.einsum("mji,mjk,mkf->if", after, right, dw)  # body frame at the end
        relative = relative_quat(self.goal_quaternion, quaternions[-1])
        value = quat_log(relative)
        jac = np.asarray(pin.Jlog3(quat_to_matrix(relative))) @ dtheta
        return value, jac

    def jacobian(self, beta: np.ndarray) -> np.ndarray:
        """Exact ``dh/dbeta`` (see :meth:`residual_and_jacobian`)."""
        return self.residual_and_jacobian(beta)[1]

    def path_length(self, beta: np.ndarray) -> float:
        """Summed joint travel along the path (rad, plus m for prismatic joints)."""
        if "length" not in self._grids:
            base, dq, _ = self.family.linear_map(np.linspace(0.0, 1.0, 401))
            self._grids["length"] = (base.q, dq)
        q0, dq = self._grids["length"]
        q = q0 + dq @ np.asarray(beta, dtype=float)
        return float(np.abs(np.diff(q, axis=0)).sum())

    def polynomials(self, beta: np.ndarray) -> JointPolynomials:
        """The path at ``beta`` as polynomials in time on [0, T] (s)."""
        return self.family.polynomials(beta, self.duration)

    def attitudes(self, beta: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Base attitude ``[x, y, z, w]`` at normalised instants ``s`` (ascending, from 0).

        Each interval between instants is split so that the steps are no longer than those of
        the solver's grid, so the last attitude agrees with :meth:`achieved` to within the
        integration error.
        """
        s = np.asarray(s, dtype=float)
        sub = max(1, math.ceil(self.steps * float(np.max(np.diff(s))) - 1e-9))
        fractions = np.arange(sub) / sub
        edges = np.concatenate([(s[:-1, None] + np.diff(s)[:, None] * fractions).ravel(), s[-1:]])
        nodes, h = step_nodes(edges)
        path = self.family.evaluate(beta, nodes)
        if self.planar and self.planar_map is not None:  # the yaw rate the residual integrates
            omega = np.outer(np.sum(self.planar_map.gains(path.q) * path.qd, axis=-1), self.axis)
        else:
            omega = self.mmap.base_rates(path.q, path.qd).omega
            if self.planar:
                omega = np.outer(omega @ self.axis, self.axis)
        quats = propagate(self.start_quaternion, magnus_increments(omega.reshape(-1, 3, 3), h))
        return quats[::sub]

    def integration_error(self, beta: np.ndarray) -> float:
        """Estimated integration error (rad) of the attitude at T with the current steps.

        Step doubling: sixth order, so the error of the coarse result is 64/63 of the
        difference to the result on twice the steps.
        """
        coarse = self.residual(beta)
        fine = self.with_steps(2 * self.steps).residual(beta)
        return float(np.linalg.norm(coarse - fine) * 64.0 / 63.0)

    def steps_for(self, beta: np.ndarray | None = None) -> int:
        """Smallest doubling of the step count whose error estimate at ``beta`` is tiny.

        Starts from the current count (at least 16) and doubles until the estimate is below
        :data:`INTEGRATION_TOLERANCE` or the cap of 4096 steps is met; nothing is changed.
        """
        beta = np.zeros(self.n_free) if beta is None else beta
        trial = self.with_steps(max(_MIN_STEPS, self.steps))
        while trial.integration_error(beta) > INTEGRATION_TOLERANCE and trial.steps < _MAX_STEPS:
            trial = trial.with_steps(2 * trial.steps)
        return trial.steps


@dataclass
class EvaluationCounter:
    """How much work a problem (and its copies at other step counts) has done.

    Attributes:
        evaluations: residual evaluations (each integrates the attitude along a path).
        map_evaluations: momentum-map evaluations (one per node and path).
    """

    evaluations: int = 0
    map_evaluations: int = 0
