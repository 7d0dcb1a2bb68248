"""Polynomial joint paths with free coefficients (docs/method.md section 4).

Joint i follows a polynomial of degree ``k_i >= 5`` in time on ``[0, T]`` with zero rate and
acceleration at both ends. Internally time is normalised, ``s = t / T`` in [0, 1]:

    q_i(s) = q_i0 + dq_i (10 s^3 - 15 s^4 + 6 s^5) + sum_{n=0..k_i-6} beta_in phi_n(s)

where ``phi_n`` (degree ``6 + n``) are the orthonormal polynomials of :mod:`.basis`: each keeps
the six boundary conditions, and ``|beta|^2 = int_0^1 |q(s) - q_quintic(s)|^2 ds`` (rad^2).
The free parameters ``beta`` (rad, or m for prismatic joints) are duration independent: the
path shape, and so the attitude reached, does not depend on T. Paths are held and evaluated as
Chebyshev series in ``x = 2 s - 1`` (stable at any degree and duration), never as monomials.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..errors import InputError
from .basis import basis_chebyshev, quintic_chebyshev
from .chebyshev_derivatives import derivative_maps, unit_interval_maps
from .chebyshev_extremes import series_extremes

__all__ = [
    "AffineSamples",
    "JointPolynomials",
    "PathFamily",
    "PathSamples",
    "boundary_errors",
    "excursions",
]

_CHEB = np.polynomial.chebyshev


def boundary_errors(
    path: JointPolynomials, start: np.ndarray, goal: np.ndarray
) -> dict[str, float]:
    """Boundary-condition errors of joint paths.

    The same evaluation a plan's verification makes of its stored path.

    Returns the largest position error against ``start`` and ``goal`` (rad or m), the largest
    end rate (per s) and acceleration (per s^2), and ``relative_max``: the largest of these
    made dimensionless by the duration and the joint travel (at least 1).
    """
    ends = path.evaluate(np.array([0.0, path.duration]))
    duration = path.duration
    travel = np.maximum(1.0, np.abs(goal - start))
    position = np.maximum(np.abs(ends.q[0] - start), np.abs(ends.q[1] - goal))
    rate = np.abs(ends.qd).max(axis=0)
    accel = np.abs(ends.qdd).max(axis=0)
    relative = np.maximum.reduce([position, rate * duration, accel * duration**2]) / travel
    return {
        "position": float(position.max()),
        "rate": float(rate.max()),
        "acceleration": float(accel.max()),
        "relative_max": float(relative.max()),
    }


def excursions(path: JointPolynomials, start: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """Per joint, how far the path goes beyond its start-goal span (rad or m, >= 0).

    From the exact extremes of each joint's polynomial: ``max(0, max q - max(q0, q1),
    min(q0, q1) - min q)``.
    """
    out = np.zeros(len(start))
    for i in range(len(start)):
        (lo, _), (hi, _) = path.extremes(i, 0)
        top, bottom = max(start[i], goal[i]), min(start[i], goal[i])
        out[i] = max(0.0, hi - top, bottom - lo)
    return out


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
    """Finished joint paths on [0, T] as Chebyshev series in normalised time.

    Attributes:
        coefficients: (N, K) Chebyshev coefficients of each joint's path in ``x = 2 t / T - 1``
            (rad or m): ``q_i(t) = sum_k coefficients[i, k] T_k(x)``. They do not depend on
            the duration: the same array with another ``duration`` is the same shape run
            faster or slower.
        duration: T (s); the paths are defined on [0, T].
    """

    coefficients: np.ndarray
    duration: float

    @classmethod
    def from_monomials(
        cls, coefficients: Sequence[Sequence[float] | np.ndarray], duration: float
    ) -> JointPolynomials:
        """From per-joint ascending coefficients in ``t`` (s) of any lengths.

        As plan files before format 4 stored them.
        """
        duration = float(duration)
        width = max(len(c) for c in coefficients)
        matrix = np.zeros((len(coefficients), width))
        for i, c in enumerate(coefficients):
            # t = T (1 + x) / 2: a polynomial in x, then its Chebyshev series
            in_x = np.polynomial.Polynomial(np.asarray(c, float)).convert(domain=[0.0, duration])
            series = _CHEB.poly2cheb(in_x.coef)
            matrix[i, : len(series)] = series
        return cls(matrix, duration)

    def monomials(self) -> np.ndarray:
        """(N, K) ascending coefficients in ``t`` (s).

        For display and old formats: they lose precision to cancellation at high degree.
        """
        out = np.zeros_like(self.coefficients)
        for i, c in enumerate(self.coefficients):
            in_x = _CHEB.cheb2poly(c)
            in_t = np.polynomial.Polynomial(in_x, domain=[0.0, self.duration]).convert(
                domain=[-1.0, 1.0]
            )
            out[i, : len(in_t.coef)] = in_t.coef
        return out

    def derivative(self, order: int) -> np.ndarray:
        """(N, K) Chebyshev coefficients in x of the ``order``-th time derivative (per s^order).

        Each order is derived once, by one product with its power of the derivative map
        (:func:`~.chebyshev_derivatives.derivative_maps`), and kept (rate bounds ask for them all).
        """
        table = self._derivative_table
        if order < len(table):
            return table[order]
        grown = list(table)
        width = self.coefficients.shape[1]
        powers = derivative_maps(width)
        scale = 2.0 / self.duration
        while len(grown) <= order:
            below = len(grown)
            if below < width:
                grown.append(self.coefficients @ powers[below].T * scale**below)
            else:  # beyond the degree: zero
                grown.append(np.zeros_like(self.coefficients))
        # replaced whole, never appended to: threads sharing a path each see a complete table
        self.__dict__["_derivative_table"] = tuple(grown)
        return grown[order]

    @cached_property
    def _derivative_table(self) -> tuple[np.ndarray, ...]:
        """The coefficients of the derivatives derived so far, by order (0: the path)."""
        return (self.coefficients,)

    def positions(self, t: np.ndarray) -> np.ndarray:
        """(len(t), N) joint values (rad or m) at times ``t`` (s): :meth:`evaluate`'s ``q``."""
        x = 2.0 * np.asarray(t, dtype=float) / self.duration - 1.0
        return _CHEB.chebvander(x, self.coefficients.shape[1] - 1) @ self.coefficients.T

    def evaluate(self, t: np.ndarray) -> PathSamples:
        """Positions (rad or m), rates (per s) and accelerations (per s^2) at times ``t`` (s)."""
        x = 2.0 * np.asarray(t, dtype=float) / self.duration - 1.0
        vander = _CHEB.chebvander(x, self.coefficients.shape[1] - 1)
        return PathSamples(*(vander @ self.derivative(order).T for order in range(3)))

    def extremes(
        self, joint: int, order: int = 0
    ) -> tuple[tuple[float, float], tuple[float, float]]:
        """Exact ``((min, t_min), (max, t_max))`` of a joint's ``order``-th derivative on [0, T].

        At its ends or at real roots of its derivative inside (:func:`.series_extremes`);
        every joint's are found at once and kept per order.
        """
        if order not in self._extreme_table:
            self._extreme_table[order] = series_extremes(self.derivative(order))
        lo, x_lo, hi, x_hi = self._extreme_table[order][joint]
        t_lo, t_hi = 0.5 * self.duration * (np.array([x_lo, x_hi]) + 1.0)
        return (float(lo), float(t_lo)), (float(hi), float(t_hi))

    @cached_property
    def _extreme_table(self) -> dict[int, np.ndarray]:
        """Every joint's extremes per derivative order (see :func:`.series_extremes`)."""
        return {}


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
        """``(joint, degree)`` of each entry of ``beta``: basis polynomial ``phi_{degree-6}``."""
        return self._index

    @cached_property
    def _basis(self) -> np.ndarray:
        """(n_free, max degree + 1) Chebyshev coefficients in x of each free basis polynomial."""
        width = max(self.degrees) + 1
        table = basis_chebyshev(max(1, width - 6))
        out = np.zeros((self.n_free, width))
        for k, (_, degree) in enumerate(self._index):
            out[k, : degree + 1] = table[degree - 6, : degree + 1]
        return out

    def chebyshev(self, beta: np.ndarray) -> np.ndarray:
        """(N, max degree + 1) Chebyshev coefficients in ``x = 2 s - 1`` of each joint's path."""
        beta = self._check(beta)
        out = self._coefficient_matrix.T.copy()
        for k, (i, _) in enumerate(self._index):
            out[i] += beta[k] * self._basis[k]
        return out

    def beta_from_path(self, path: JointPolynomials) -> np.ndarray:
        """The free parameters of a path of this family (its L2 projection on the basis, rad).

        Exact for a path of the family (the basis is orthonormal): Gauss-Legendre quadrature
        of ``(q - q_quintic) phi_n`` with enough nodes for the degrees involved.
        """
        nodes = max(path.coefficients.shape[1], max(self.degrees) + 1) + 1
        x, w = np.polynomial.legendre.leggauss(nodes)
        deviation = _CHEB.chebvander(x, path.coefficients.shape[1] - 1) @ path.coefficients.T
        deviation = deviation - self.evaluate(np.zeros(self.n_free), 0.5 * (x + 1.0)).q
        dq = self.affine_samples(0.5 * (x + 1.0)).dq
        return 0.5 * np.einsum("k,ki,kif->f", w, deviation, dq)

    @cached_property
    def _coefficient_matrix(self) -> np.ndarray:
        """(max degree + 1, N) Chebyshev coefficients of the quintic paths (beta = 0)."""
        out = np.zeros((max(self.degrees) + 1, self.n_joints))
        blend = quintic_chebyshev()
        out[: len(blend)] = np.outer(blend, self.goal - self.start)
        out[0] += self.start
        return out

    def _powers(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Chebyshev polynomials at ``x = 2 s - 1`` and their first two s-derivatives.

        Each (len(s), max degree + 1), as maps from Chebyshev coefficients.
        """
        width = max(self.degrees) + 1
        values = _CHEB.chebvander(2.0 * np.asarray(s, dtype=float) - 1.0, width - 1)
        first, second = unit_interval_maps(width)
        return values, values @ first, values @ second

    def linear_map(self, s: np.ndarray) -> tuple[PathSamples, np.ndarray, np.ndarray]:
        """``(base, dq, dqs)`` of :meth:`affine_samples`: ``q = base.q + dq @ beta``, ...."""
        full = self.affine_samples(s)
        return full.base, full.dq, full.dqs

    def affine_samples(self, s: np.ndarray) -> AffineSamples:
        """The path and both its s-derivatives at instants ``s`` as affine functions of beta.

        The last few instant sets asked for are kept, the least recently used forgotten first.
        """
        s = np.asarray(s, dtype=float)
        key = s.tobytes()
        found = self._affine.pop(key, None)
        if found is None and len(self._affine) >= 8:
            self._affine.pop(next(iter(self._affine)))
        self._affine[key] = found = self._affine_samples(s) if found is None else found
        return found

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
        c = self.chebyshev(beta).T
        values, first, second = self._powers(np.asarray(s, dtype=float))
        return PathSamples(values @ c, first @ c, second @ c)

    def at_times(self, beta: np.ndarray, t: np.ndarray, duration: float) -> PathSamples:
        """Positions (rad or m), rates (per s) and accelerations (per s^2) at times ``t`` (s)."""
        n = self.evaluate(beta, np.asarray(t, dtype=float) / duration)
        return PathSamples(n.q, n.qd / duration, n.qdd / duration**2)

    def embed(self, other: PathFamily, beta: np.ndarray) -> np.ndarray | None:
        """``beta`` of ``other`` as free coefficients of this family (new ones zero).

        The path is unchanged: each free coefficient multiplies the same basis polynomial in
        both families (the basis polynomials do not depend on the family's degrees). None when
        this family lacks one of ``other``'s coefficients or the two join different
        configurations.
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
        """The path at ``beta`` on [0, ``duration``] (s)."""
        return JointPolynomials(self.chebyshev(beta), float(duration))

    def _check(self, beta: np.ndarray) -> np.ndarray:
        beta = np.asarray(beta, dtype=float).reshape(-1)
        if beta.shape != (self.n_free,):
            raise InputError(f"expected {self.n_free} free coefficients, got {beta.size}")
        return beta
