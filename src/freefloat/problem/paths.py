"""Polynomial joint paths with free coefficients (docs/method.md section 4).

Joint i follows a polynomial of degree ``k_i >= 5`` in time on ``[0, T]`` with zero rate and
acceleration at both ends. Internally time is normalised, ``s = t / T`` in [0, 1]:

    q_i(s) = q_i0 + dq_i (10 s^3 - 15 s^4 + 6 s^5) + sum_{j=6..k_i} beta_ij phi_j(s)

where ``phi_j(s) = s^j - (a3 s^3 + a4 s^4 + a5 s^5)`` keeps the six boundary conditions, so
that each ``beta_ij`` is exactly the coefficient of ``s^j``; in time it is the coefficient of
``t^j`` times ``T^j``. The free parameters ``beta`` (rad, or m for prismatic joints) are
duration independent: the path shape, and so the attitude reached, does not depend on T.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..errors import InputError

__all__ = [
    "AffineSamples",
    "JointPolynomials",
    "PathFamily",
    "PathSamples",
    "basis_coefficients",
    "boundary_errors",
]

_QUINTIC = np.array([0.0, 0.0, 0.0, 10.0, -15.0, 6.0])


def basis_coefficients(power: int) -> np.ndarray:
    """Ascending coefficients of ``phi_power(s)``: ``s^power`` with the six end conditions zero."""
    if power < 6:
        raise ValueError("free coefficients start at s^6")
    lhs = np.array([[1.0, 1.0, 1.0], [3.0, 4.0, 5.0], [6.0, 12.0, 20.0]])
    rhs = np.array([1.0, power, power * (power - 1.0)])
    a3, a4, a5 = np.linalg.solve(lhs, rhs)
    coeffs = np.zeros(power + 1)
    coeffs[3:6] = [-a3, -a4, -a5]
    coeffs[power] = 1.0
    return coeffs


def boundary_errors(
    coefficients: list[np.ndarray], start: np.ndarray, goal: np.ndarray, duration: float
) -> dict[str, float]:
    """Boundary-condition errors of joint polynomials (ascending powers of t in s).

    The same evaluation a plan's verification makes of its stored coefficients.

    Returns the largest position error against ``start`` and ``goal`` (rad or m), the largest
    end rate (per s) and acceleration (per s^2), and ``relative_max``: the largest of these
    made dimensionless by the duration and the joint travel (at least 1).
    """
    poly = np.polynomial.polynomial
    groups = (
        coefficients,
        [poly.polyder(c) for c in coefficients],
        [poly.polyder(c, 2) for c in coefficients],
    )
    q0, qd0, qdd0 = (np.array([poly.polyval(0.0, c) for c in g]) for g in groups)
    q1, qd1, qdd1 = (np.array([poly.polyval(duration, c) for c in g]) for g in groups)
    travel = np.maximum(1.0, np.abs(goal - start))
    position = np.maximum(np.abs(q0 - start), np.abs(q1 - goal))
    rate = np.maximum(np.abs(qd0), np.abs(qd1))
    accel = np.maximum(np.abs(qdd0), np.abs(qdd1))
    relative = np.maximum.reduce([position, rate * duration, accel * duration**2]) / travel
    return {
        "position": float(position.max()),
        "rate": float(rate.max()),
        "acceleration": float(accel.max()),
        "relative_max": float(relative.max()),
    }


@dataclass(frozen=True)
class PathSamples:
    """Joint positions and their first two derivatives at given instants.

    Each array is (len(s), N). Derivatives are with respect to normalised time ``s`` unless
    the samples were taken in seconds (see :meth:`PathFamily.at_times`).
    """

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray


@dataclass(frozen=True)
class AffineSamples:
    """The path at instants as an affine function of the free coefficients ``beta``.

    ``q = base.q + dq @ beta``, ``q_s = base.qd + dqs @ beta``, ``q_ss = base.qdd + dqss @ beta``
    (s-derivatives); each map is (len(s), N, n_free).
    """

    base: PathSamples
    dq: np.ndarray
    dqs: np.ndarray
    dqss: np.ndarray

    def at(self, beta: np.ndarray) -> PathSamples:
        """Positions and s-derivatives at ``beta``."""
        beta = np.asarray(beta, dtype=float)
        return PathSamples(
            self.base.q + self.dq @ beta,
            self.base.qd + self.dqs @ beta,
            self.base.qdd + self.dqss @ beta,
        )


@dataclass(frozen=True)
class JointPolynomials:
    """Finished joint paths as polynomials in time, as a plan file stores them.

    Attributes:
        coefficients: (N, K) ascending coefficients of each joint's polynomial in t (s);
            values in rad (or m), so row i, column k is in rad/s^k.
        duration: T (s); the paths are defined on [0, T].
    """

    coefficients: np.ndarray
    duration: float

    @classmethod
    def from_lists(
        cls, coefficients: Sequence[Sequence[float]], duration: float
    ) -> JointPolynomials:
        """From per-joint coefficient lists of any lengths (padded with zeros)."""
        width = max(len(c) for c in coefficients)
        matrix = np.zeros((len(coefficients), width))
        for i, c in enumerate(coefficients):
            matrix[i, : len(c)] = c
        return cls(matrix, float(duration))

    def derivative(self, order: int) -> np.ndarray:
        """(N, K - order) coefficients of the ``order``-th time derivative (per s^order)."""
        c = self.coefficients
        for _ in range(order):
            c = c[:, 1:] * np.arange(1, c.shape[1])[None, :]
        return c if c.shape[1] else np.zeros((len(self.coefficients), 1))

    def evaluate(self, t: np.ndarray) -> PathSamples:
        """Positions (rad or m), rates (per s) and accelerations (per s^2) at times ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        out = []
        for order in range(3):
            c = self.derivative(order)
            powers = t[:, None] ** np.arange(c.shape[1])[None, :]
            out.append(powers @ c.T)
        return PathSamples(*out)

    def extremes(
        self, joint: int, order: int = 0
    ) -> tuple[tuple[float, float], tuple[float, float]]:
        """Exact ``((min, t_min), (max, t_max))`` of a joint's ``order``-th derivative on [0, T].

        Extremes of a polynomial on an interval are at its ends or at real roots of its
        derivative inside (found by numpy's companion-matrix roots, then evaluated).
        """
        poly = np.polynomial.polynomial
        c = self.derivative(order)[joint]
        dc = poly.polyder(c) if len(c) > 1 else np.zeros(1)
        candidates = [0.0, self.duration]
        if np.any(dc != 0.0):
            trimmed = np.trim_zeros(dc, "b")
            if len(trimmed) > 1:
                for root in poly.polyroots(trimmed):
                    if abs(root.imag) <= 1e-9 * max(1.0, abs(root.real)):
                        r = float(root.real)
                        if 0.0 < r < self.duration:
                            candidates.append(r)
        times = np.array(candidates)
        values = poly.polyval(times, c)
        lo, hi = int(np.argmin(values)), int(np.argmax(values))
        return (float(values[lo]), float(times[lo])), (float(values[hi]), float(times[hi]))


@dataclass(frozen=True)
class PathFamily:
    """The family of polynomial joint paths between two joint configurations.

    Attributes:
        start: N start joint values (rad or m).
        goal: N goal joint values (rad or m).
        degrees: polynomial degree of each joint (>= 5).
    """

    start: np.ndarray
    goal: np.ndarray
    degrees: tuple[int, ...]
    _index: tuple[tuple[int, int], ...] = field(init=False, repr=False)
    _affine: dict[bytes, AffineSamples] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        start = np.asarray(self.start, dtype=float)
        goal = np.asarray(self.goal, dtype=float)
        if start.shape != goal.shape or start.ndim != 1:
            raise InputError("start and goal need one value per joint")
        if len(self.degrees) != len(start):
            raise InputError(f"{len(self.degrees)} degrees given for {len(start)} joints")
        for degree in self.degrees:
            if int(degree) != degree or degree < 5:
                raise InputError(f"polynomial degree {degree} is invalid; each must be >= 5")
        object.__setattr__(self, "start", start)
        object.__setattr__(self, "goal", goal)
        object.__setattr__(self, "degrees", tuple(int(d) for d in self.degrees))
        index = tuple((i, p) for i, d in enumerate(self.degrees) for p in range(6, d + 1))
        object.__setattr__(self, "_index", index)

    @classmethod
    def with_extra(cls, start: np.ndarray, goal: np.ndarray, extra: Sequence[int]) -> PathFamily:
        """Family with ``extra[i]`` free coefficients (degree ``5 + extra[i]``) on joint i."""
        return cls(start, goal, tuple(5 + int(e) for e in extra))

    @property
    def n_joints(self) -> int:
        """Number of joints N."""
        return len(self.degrees)

    @property
    def n_free(self) -> int:
        """Number of free coefficients (the length of ``beta``)."""
        return len(self._index)

    @property
    def free_index(self) -> tuple[tuple[int, int], ...]:
        """``(joint, power)`` of each entry of ``beta``."""
        return self._index

    @cached_property
    def _basis(self) -> np.ndarray:
        """(n_free, max degree + 1) ascending coefficients of each free basis polynomial."""
        width = max(self.degrees) + 1
        out = np.zeros((self.n_free, width))
        for k, (_, power) in enumerate(self._index):
            out[k, : power + 1] = basis_coefficients(power)
        return out

    def coefficients(self, beta: np.ndarray) -> list[np.ndarray]:
        """Ascending coefficients in ``s`` of each joint's polynomial (rad or m)."""
        beta = self._check(beta)
        out = []
        delta = self.goal - self.start
        for i, degree in enumerate(self.degrees):
            c = np.zeros(degree + 1)
            c[:6] = delta[i] * _QUINTIC
            c[0] = self.start[i]
            out.append(c)
        for k, (i, _) in enumerate(self._index):
            out[i] += beta[k] * self._basis[k, : self.degrees[i] + 1]
        return out

    def time_coefficients(self, beta: np.ndarray, duration: float) -> list[np.ndarray]:
        """Ascending coefficients in ``t`` (seconds) of each joint's polynomial."""
        return [c / duration ** np.arange(len(c)) for c in self.coefficients(beta)]

    def free_time_coefficients(self, beta: np.ndarray, duration: float) -> list[list[float]]:
        """Per joint, the coefficients of ``t^6`` and up (rad/s^j or m/s^j)."""
        beta = self._check(beta)
        out: list[list[float]] = [[] for _ in self.degrees]
        for k, (i, power) in enumerate(self._index):
            out[i].append(float(beta[k] / duration**power))
        return out

    def beta_from_time_coefficients(
        self, free: Sequence[Sequence[float]], duration: float
    ) -> np.ndarray:
        """Inverse of :meth:`free_time_coefficients`."""
        beta = np.zeros(self.n_free)
        counters = [0] * self.n_joints
        for k, (i, power) in enumerate(self._index):
            beta[k] = free[i][counters[i]] * duration**power
            counters[i] += 1
        return beta

    @cached_property
    def _coefficient_matrix(self) -> np.ndarray:
        """(max degree + 1, N) coefficients of the quintic paths (beta = 0), zero-padded."""
        out = np.zeros((max(self.degrees) + 1, self.n_joints))
        for i, c in enumerate(self.coefficients(np.zeros(self.n_free))):
            out[: len(c), i] = c
        return out

    def _powers(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Powers of ``s`` and their first two derivatives, each (len(s), max degree + 1)."""
        j = np.arange(max(self.degrees) + 1)
        s = np.asarray(s, dtype=float)[:, None]
        powers = s**j
        first = j * s ** np.maximum(j - 1, 0)
        second = j * (j - 1) * s ** np.maximum(j - 2, 0)
        return powers, first, second

    def linear_map(self, s: np.ndarray) -> tuple[PathSamples, np.ndarray, np.ndarray]:
        """The path at instants ``s`` as an affine function of ``beta``.

        Returns:
            ``(base, dq, dqs)``: the quintic path (``beta = 0``) with its s-derivatives, and the
            (len(s), N, n_free) arrays with ``q = base.q + dq @ beta`` and
            ``q_s = base.qd + dqs @ beta``.
        """
        full = self.affine_samples(s)
        return full.base, full.dq, full.dqs

    def affine_samples(self, s: np.ndarray) -> AffineSamples:
        """The path and both its s-derivatives at instants ``s`` as affine functions of beta.

        Kept for the last few instant sets asked for (objectives ask for the same nodes often).
        """
        s = np.asarray(s, dtype=float)
        key = s.tobytes()
        if key in self._affine:
            return self._affine[key]
        if len(self._affine) >= 8:
            self._affine.clear()
        self._affine[key] = self._affine_samples(s)
        return self._affine[key]

    def _affine_samples(self, s: np.ndarray) -> AffineSamples:
        powers, first, second = self._powers(np.asarray(s, dtype=float))
        c = self._coefficient_matrix
        base = PathSamples(powers @ c, first @ c, second @ c)
        dq = np.zeros((len(powers), self.n_joints, self.n_free))
        dqs = np.zeros_like(dq)
        dqss = np.zeros_like(dq)
        joints = [i for i, _ in self._index]
        columns = np.arange(self.n_free)
        dq[:, joints, columns] = powers @ self._basis.T
        dqs[:, joints, columns] = first @ self._basis.T
        dqss[:, joints, columns] = second @ self._basis.T
        return AffineSamples(base, dq, dqs, dqss)

    def evaluate(self, beta: np.ndarray, s: np.ndarray) -> PathSamples:
        """Positions and s-derivatives (per unit s, per unit s^2) at normalised instants ``s``."""
        beta = self._check(beta)
        c = self._coefficient_matrix.copy()
        for k, (i, _) in enumerate(self._index):
            c[:, i] += beta[k] * self._basis[k]
        powers, first, second = self._powers(np.asarray(s, dtype=float))
        return PathSamples(powers @ c, first @ c, second @ c)

    def at_times(self, beta: np.ndarray, t: np.ndarray, duration: float) -> PathSamples:
        """Positions (rad or m), rates (per s) and accelerations (per s^2) at times ``t`` (s)."""
        n = self.evaluate(beta, np.asarray(t, dtype=float) / duration)
        return PathSamples(n.q, n.qd / duration, n.qdd / duration**2)

    def embed(self, other: PathFamily, beta: np.ndarray) -> np.ndarray | None:
        """``beta`` of ``other`` as free coefficients of this family (new ones zero).

        The path is unchanged: each free coefficient multiplies the same basis polynomial in
        both families. None when this family lacks one of ``other``'s coefficients or the two
        join different configurations.
        """
        if not (np.array_equal(self.start, other.start) and np.array_equal(self.goal, other.goal)):
            return None
        position = {key: k for k, key in enumerate(self.free_index)}
        out = np.zeros(self.n_free)
        for value, key in zip(np.asarray(beta, dtype=float), other.free_index, strict=True):
            if key not in position:
                return None
            out[position[key]] = value
        return out

    def polynomials(self, beta: np.ndarray, duration: float) -> JointPolynomials:
        """The path at ``beta`` as polynomials in time on [0, ``duration``] (s)."""
        return JointPolynomials.from_lists(
            [c.tolist() for c in self.time_coefficients(beta, duration)], duration
        )

    def _check(self, beta: np.ndarray) -> np.ndarray:
        beta = np.asarray(beta, dtype=float).reshape(-1)
        if beta.shape != (self.n_free,):
            raise InputError(f"expected {self.n_free} free coefficients, got {beta.size}")
        return beta
