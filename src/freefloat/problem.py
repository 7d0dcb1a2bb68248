"""The planning problem, built apart from its solution (method.md section 5).

A :class:`Problem` holds the robot, the start and goal, the path family and the integration
grid, and evaluates the residual ``h(beta)``: the attitude reached at the end of the path minus
the attitude wanted (rad). Planar systems have one equation (yaw, not wrapped, against the
requested yaw change); others have three (the rotation vector from the goal attitude to the
reached one, in the goal frame).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from .attitude import (
    GAUSS3_WEIGHTS,
    magnus_increment_jacobian,
    magnus_increments,
    propagate,
    quat_conjugate,
    quat_exp,
    quat_log,
    quat_multiply,
    quat_to_matrix,
    rotation_matrices,
    so3_right_jacobian,
    step_nodes,
)
from .bounds import PlanarBounds, cached_planar_bounds
from .errors import InfeasibleError, InputError, JointLimitError
from .model import Robot
from .momentum import MomentumMap, NodeRates, cached_planar_axis
from .paths import PathFamily
from .planar import PlanarMap, identify

__all__ = ["Problem", "build_problem", "wrap_angle"]

#: Target of the integration error estimate (rad) when choosing the number of steps.
INTEGRATION_TOLERANCE = 1e-12
_MIN_STEPS, _MAX_STEPS = 16, 4096


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
        evaluations: residual evaluations so far (each integrates the attitude along a path).
        map_evaluations: momentum-map evaluations so far (one per node and path).
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
    evaluations: int = 0
    map_evaluations: int = 0
    _grid: tuple[np.ndarray, ...] = field(default=(), init=False, repr=False)
    _grids: dict[int | str, tuple[np.ndarray, ...]] = field(
        default_factory=dict, init=False, repr=False
    )
    _memo: dict[tuple[int, bytes], np.ndarray] = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self) -> None:
        self.set_steps(self.steps)

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

    def set_steps(self, steps: int) -> None:
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
        self.evaluations += 1
        self.map_evaluations += len(q)
        return self.mmap.base_rates(q, qs, derivatives), qs

    def planar_rates(self, betas: np.ndarray) -> np.ndarray:
        """Planar problems: yaw rate at the nodes for several ``beta`` at once, (G, K)."""
        _, q0, qs0, dq, dqs = self._grid
        betas = np.atleast_2d(np.asarray(betas, dtype=float))
        q = q0[None] + np.einsum("knf,gf->gkn", dq, betas)
        qs = qs0[None] + np.einsum("knf,gf->gkn", dqs, betas)
        if self.planar_map is not None:
            self.evaluations += len(betas)
            self.map_evaluations += q.shape[0] * q.shape[1]
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
        self.evaluations += len(betas)
        self.map_evaluations += q.shape[0] * q.shape[1]
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

        The last few values are remembered (by step count and ``beta``), since the solver asks
        again for some of them (the quintic path's, the chosen root's).
        """
        key = (self.steps, np.asarray(beta, dtype=float).tobytes())
        if key not in self._memo:
            if len(self._memo) >= 8:
                self._memo.pop(next(iter(self._memo)))
            self._memo[key] = self._residual(beta)
        return self._memo[key].copy()

    def _residual(self, beta: np.ndarray) -> np.ndarray:
        if self.planar:
            assert self.yaw_change is not None
            return np.array([self.yaw_change_of(beta) - self.yaw_change])
        reached = self.achieved(beta)
        return quat_log(quat_multiply(quat_conjugate(self.goal_quaternion), reached))

    def residual_and_jacobian(self, beta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``h(beta)`` and its exact Jacobian ``dh/dbeta`` (rad per unit of beta).

        The Jacobian differentiates the discrete scheme itself: node rates through Pinocchio's
        analytic centroidal derivatives and the path's linear dependence on ``beta``; each
        step's Magnus vector by complex steps; the chain of step rotations with SO(3) right
        Jacobians; the residual's logarithm with ``pin.Jlog3``.
        """
        h, q0, qs0, dq, dqs = self._grid
        if self.planar and self.planar_map is not None:
            assert self.yaw_change is not None
            beta = np.asarray(beta, dtype=float)
            q, qs = q0 + dq @ beta, qs0 + dqs @ beta
            gains, dgains = self.planar_map.gains_and_derivatives(q)
            self.evaluations += 1
            self.map_evaluations += len(q)
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
        rotations = rotation_matrices(increments)
        # after[m] = E_{m+1} ... E_{M}: the rotation that follows step m.
        after = np.empty_like(rotations)
        after[-1] = np.eye(3)
        for m in range(self.steps - 1, 0, -1):
            after[m - 1] = rotations[m] @ after[m]
        right = so3_right_jacobian(increments)
        dtheta = np.einsum("mji,mjk,mkf->if", after, right, dw)  # body frame at the end
        reached = propagate(self.start_quaternion, increments)[-1]
        relative = quat_multiply(quat_conjugate(self.goal_quaternion), reached)
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

    def limit_constraints(self, points: int = 97) -> tuple[np.ndarray, np.ndarray]:
        """Joint position limits as linear inequalities ``G beta <= g`` at ``points`` instants.

        The joint values are affine in ``beta``, so the limits along the path are linear
        constraints; only joints with finite limits contribute rows.
        """
        s = np.linspace(0.0, 1.0, points)
        base, dq, _ = self.family.linear_map(s)
        rows, bounds = [], []
        for i, joint in enumerate(self.robot.joints):
            if np.isfinite(joint.upper):
                rows.append(dq[:, i, :])
                bounds.append(joint.upper - base.q[:, i])
            if np.isfinite(joint.lower):
                rows.append(-dq[:, i, :])
                bounds.append(base.q[:, i] - joint.lower)
        if not rows:
            return np.zeros((0, self.n_free)), np.zeros(0)
        return np.concatenate(rows), np.concatenate(bounds)

    def limit_violation(self, beta: np.ndarray, points: int = 801) -> tuple[float, str]:
        """Largest excursion beyond a joint limit along the path (rad or m) and the joint."""
        limited = [
            i
            for i, j in enumerate(self.robot.joints)
            if np.isfinite(j.lower) or np.isfinite(j.upper)
        ]
        if not limited:
            return 0.0, ""
        q = self.family.evaluate(beta, np.linspace(0.0, 1.0, points)).q
        worst, name = 0.0, ""
        for i, joint in enumerate(self.robot.joints):
            over = max(float(q[:, i].max() - joint.upper), float(joint.lower - q[:, i].min()))
            if over > worst:
                worst, name = over, joint.name
        return worst, name

    def attitudes(self, beta: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Base attitude ``[x, y, z, w]`` at normalised instants ``s`` (ascending, from 0).

        Each interval between instants is split so that the steps are no longer than those of
        the solver's grid, so the last attitude agrees with :meth:`achieved` to within the
        integration error.
        """
        s = np.asarray(s, dtype=float)
        sub = max(1, math.ceil(self.steps * float(np.max(np.diff(s))) - 1e-9))
        edges = np.concatenate(
            [np.linspace(a, b, sub + 1)[:-1] for a, b in itertools.pairwise(s)] + [s[-1:]]
        )
        nodes, h = step_nodes(edges)
        path = self.family.evaluate(beta, nodes)
        omega = self.mmap.base_rates(path.q, path.qd).omega
        if self.planar:
            omega = np.outer(omega @ self.axis, self.axis)
        quats = propagate(self.start_quaternion, magnus_increments(omega.reshape(-1, 3, 3), h))
        return quats[::sub]

    def integration_error(self, beta: np.ndarray) -> float:
        """Estimated integration error (rad) of the attitude at T with the current steps."""
        coarse = self.residual(beta)
        steps = self.steps
        self.set_steps(2 * steps)
        fine = self.residual(beta)
        self.set_steps(steps)
        # Sixth order: the error of the coarse result is 64/63 of the difference.
        return float(np.linalg.norm(coarse - fine) * 64.0 / 63.0)

    def choose_steps(self, beta: np.ndarray | None = None) -> int:
        """Double the step count until the integration error estimate is tiny; return it."""
        beta = np.zeros(self.n_free) if beta is None else beta
        self.set_steps(max(_MIN_STEPS, self.steps))
        while self.integration_error(beta) > INTEGRATION_TOLERANCE and self.steps < _MAX_STEPS:
            self.set_steps(2 * self.steps)
        return self.steps


def _axis_name(axis: np.ndarray) -> str:
    for name, unit in (("z", (0, 0, 1)), ("y", (0, 1, 0)), ("x", (1, 0, 0))):
        if np.allclose(np.abs(axis), unit, atol=1e-12):
            return f"its {name} axis"
    return f"the axis {np.round(axis, 6).tolist()} of its frame"


def _check_finite(name: str, values: np.ndarray) -> None:
    if not np.all(np.isfinite(values)):
        raise InputError(f"{name} contains NaN or infinite values; give finite numbers")


def _check_limits(robot: Robot, values: np.ndarray, where: str) -> None:
    for joint, value in zip(robot.joints, values, strict=True):
        if joint.kind == "continuous":
            continue
        if not joint.lower - 1e-12 <= value <= joint.upper + 1e-12:
            scale = 180.0 / math.pi if joint.angular else 1.0
            unit = "deg" if joint.angular else "m"
            raise JointLimitError(joint.name, value, joint.lower, joint.upper, where, unit, scale)


def build_problem(
    robot: Robot,
    start: np.ndarray,
    goal: np.ndarray,
    start_quaternion: np.ndarray,
    goal_quaternion: np.ndarray,
    duration: float,
    extra: Sequence[int] | Mapping[str, int] | None = None,
    mmap: MomentumMap | None = None,
    check_bounds: bool = True,
) -> Problem:
    """Build and check a planning problem.

    Args:
        robot: the free-floating robot.
        start: N start joint values (rad or m).
        goal: N goal joint values (rad or m).
        start_quaternion: base attitude at t = 0, ``[x, y, z, w]``.
        goal_quaternion: wanted base attitude at t = T, ``[x, y, z, w]``.
        duration: motion time T (s), > 0.
        extra: free coefficients beyond the quintic per joint (a sequence of N counts or a
            ``{joint: count}`` mapping); default one on the joint nearest the base for planar
            systems and one on each of the first three joints otherwise.
        mmap: momentum-map evaluator to reuse.
        check_bounds: refuse planar requests outside the planar bounds (method.md section 6).

    Raises:
        InputError: non-finite numbers, a non-positive duration, a bad quaternion.
        JointLimitError: start or goal outside the joint limits.
        InfeasibleError: planar request outside the reachable interval, or a goal attitude a
            planar system cannot reach (it only turns about its z axis).
    """
    start = np.asarray(start, dtype=float)
    goal = np.asarray(goal, dtype=float)
    for name, arr in (("start joints", start), ("goal joints", goal)):
        _check_finite(name, arr)
    if not (isinstance(duration, (int, float)) and math.isfinite(duration) and duration > 0.0):
        raise InputError(f"duration must be a finite number of seconds > 0, got {duration!r}")
    quats = []
    for name, quat in (("start attitude", start_quaternion), ("goal attitude", goal_quaternion)):
        quat = np.asarray(quat, dtype=float)
        _check_finite(name, quat)
        norm = float(np.linalg.norm(quat))
        if quat.shape != (4,) or norm < 1e-9:
            raise InputError(f"{name} must be a non-zero quaternion [x, y, z, w]")
        quats.append(quat / norm)
    _check_limits(robot, start, "start")
    _check_limits(robot, goal, "goal")

    mmap = mmap or MomentumMap(robot)
    axis = cached_planar_axis(robot)
    planar = axis is not None
    planar_map = None
    if axis is not None:
        if "planar_map" not in robot.cache:
            robot.cache["planar_map"] = identify(robot, axis)
        planar_map = robot.cache["planar_map"]
    if extra is None:
        counts = [0] * robot.n
        for i in range(1 if planar else 3):
            counts[i % robot.n] += 1
    elif isinstance(extra, Mapping):
        counts = [0] * robot.n
        for name, count in extra.items():
            index = robot.joint_names.index(robot.joint(name).name)
            counts[index] = int(count)
    else:
        counts = [int(c) for c in extra]
    if any(c < 0 for c in counts):
        raise InputError(f"free coefficient counts must be >= 0, got {counts}")
    family = PathFamily.with_extra(start, goal, counts)

    bounds = yaw_change = None
    if planar:
        relative = quat_log(quat_multiply(quat_conjugate(quats[0]), quats[1]))
        assert axis is not None
        off_axis = float(np.linalg.norm(relative - (relative @ axis) * axis))
        if off_axis > 1e-9:
            raise InfeasibleError(
                math.degrees(off_axis),
                (0.0, 0.0),
                message=(
                    f"this robot is planar: its base turns only about {_axis_name(axis)}, but the "
                    "goal "
                    f"attitude is {math.degrees(off_axis):.6g} deg away from the start about "
                    "other axes; give the goal the start's pitch and roll"
                ),
            )
        yaw_change = wrap_angle(float(relative @ axis))
        bounds = cached_planar_bounds(mmap, axis, planar_map)
        lo, hi = bounds.interval(goal - start)
        if check_bounds:
            branches = [yaw_change + 2.0 * math.pi * k for k in range(-3, 4)]
            # Open interval; when no joint moves it shrinks to the single point 0.
            inside = [b for b in branches if lo < b < hi or (lo == hi == 0.0 and b == 0.0)]
            if not inside:
                interval = (math.degrees(lo), math.degrees(hi))
                raise InfeasibleError(math.degrees(yaw_change), interval)
            yaw_change = min(inside, key=abs)
    problem = Problem(
        robot=robot,
        mmap=mmap,
        family=family,
        duration=float(duration),
        start_quaternion=quats[0],
        goal_quaternion=quats[1],
        planar=planar,
        axis=np.array([0.0, 0.0, 1.0]) if axis is None else axis,
        planar_map=planar_map,
        bounds=bounds,
        yaw_change=yaw_change,
    )
    if family.n_free < problem.n_equations:
        raise InputError(
            f"{family.n_free} free path coefficient(s) for {problem.n_equations} attitude "
            f"equation(s); add at least {problem.n_equations - family.n_free} more with "
            "[path] extra"
        )
    problem.choose_steps()
    return problem
