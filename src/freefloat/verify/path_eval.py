"""A plan's joint paths evaluated from the file alone, independently of the planner's code.

The planner holds paths as Chebyshev series (:mod:`freefloat.problem.paths`); verification
evaluates the file's own definition instead, so that an error in either shows as a
disagreement:

- format 4 (``path.basis = "quintic+jacobi66"``): the quintic between the requested start and
  goal plus ``sum_n beta_n c_n s^3 (1 - s)^3 P_n^(6,6)(2 s - 1)``, with the Jacobi polynomials
  as rescaled Gegenbauer polynomials (their own recurrence; the tests hold them to
  :func:`scipy.special.eval_jacobi`), ``c_n`` from its closed form, and the derivatives from
  ``d/dx P_n^(a,b) = (n + a + b + 1) / 2 P_{n-1}^(a+1,b+1)`` and the product rule;
- older formats: the stored monomials in t, by Horner's rule (:func:`numpy.polynomial`).

Units: t in s; positions rad (m), rates per s, accelerations per s^2.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..plans.format import Plan
from ..plans.versions import MONOMIAL_BASIS

__all__ = ["FilePath", "file_path"]


@functools.cache
def _scales(count: int) -> np.ndarray:
    """``c_n = sqrt((2 n + 13) (n + 12)! n!) / (n + 6)!`` for n = 0 .. count - 1 (read-only)."""
    out = np.array(
        [
            math.exp(
                0.5 * (math.log(2 * k + 13) + math.lgamma(k + 13) + math.lgamma(k + 1))
                - math.lgamma(k + 7)
            )
            for k in range(count)
        ]
    )
    out.setflags(write=False)
    return out


def _jacobi(n: np.ndarray, shift: int, x: np.ndarray) -> np.ndarray:
    """``P_{n - shift}^(6 + shift, 6 + shift)(x)`` (zero where ``n < shift``), (len(x), len(n)).

    A symmetric Jacobi polynomial is a Gegenbauer polynomial rescaled,
    ``P_m^(a,a)(x) = (a + 1)_m / (2 a + 1)_m C_m^(a + 1/2)(x)``, and the Gegenbauer
    polynomials follow their own recurrence ``m C_m = 2 (m + l - 1) x C_{m-1} - (m + 2 l - 2)
    C_{m-2}`` (``l = a + 1/2``, ``C_0 = 1``, ``C_1 = 2 l x``): another route than the planner's
    Jacobi recurrence on Chebyshev coefficients (:func:`~freefloat.problem.basis.basis_chebyshev`).
    """
    a = 6 + shift
    lam = a + 0.5
    m = n - shift
    count = max(int(m.max()) + 1, 1) if len(m) else 1
    values = np.empty((len(x), count))
    values[:, 0] = 1.0
    if count > 1:
        values[:, 1] = 2.0 * lam * x
    for k in range(2, count):
        values[:, k] = (
            2.0 * (k + lam - 1.0) * x * values[:, k - 1] - (k + 2.0 * lam - 2.0) * values[:, k - 2]
        ) / k
    # (a + 1)_j / (2 a + 1)_j, by log-gamma
    ratio = np.exp(
        np.array([math.lgamma(a + 1 + j) - math.lgamma(2 * a + 1 + j) for j in range(count)])
        - (math.lgamma(a + 1) - math.lgamma(2 * a + 1))
    )
    table = values * ratio
    picked = table[:, np.clip(m, 0, count - 1)]
    return np.where(m[None, :] >= 0, picked, 0.0)


@dataclass(frozen=True)
class FilePath:
    """The joint paths of one plan file (see the module docstring)."""

    duration: float
    start: np.ndarray
    goal: np.ndarray
    beta: list[np.ndarray] | None
    monomials: list[np.ndarray] | None

    @property
    def degree(self) -> int:
        """The highest polynomial degree of the joint paths."""
        if self.monomials is not None:
            return max(len(c) for c in self.monomials) - 1
        assert self.beta is not None
        return 5 + max(len(b) for b in self.beta)

    def positions(self, t: np.ndarray) -> np.ndarray:
        """Joint values (len(t), N) at times ``t`` (s): those of :meth:`__call__`, alone."""
        t = np.asarray(t, dtype=float)
        if self.monomials is not None:
            poly = np.polynomial.polynomial
            return np.stack([poly.polyval(t, poly.polyder(c, 0)) for c in self.monomials], -1)
        assert self.beta is not None
        s = t / self.duration
        x = 2.0 * s - 1.0
        q = self.start + np.outer(10 * s**3 - 15 * s**4 + 6 * s**5, self.goal - self.start)
        b = s**3 * (1 - s) ** 3
        longest = np.arange(len(self.jacobi_weights))
        q += (b[:, None] * _jacobi(longest, 0, x)) @ self.jacobi_weights
        return q

    @functools.cached_property
    def jacobi_weights(self) -> np.ndarray:
        """(L, N) weights of the Jacobi terms (rad or m), L the most terms of any joint.

        Joint i's ``c_n beta_n`` in column i, zero beyond its own terms.
        """
        assert self.beta is not None
        out = np.zeros((max(len(beta) for beta in self.beta), len(self.beta)))
        for i, beta in enumerate(self.beta):
            out[: len(beta), i] = _scales(len(beta)) * beta
        return out

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint values, rates and accelerations, each (len(t), N), at times ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        if self.monomials is not None:
            poly = np.polynomial.polynomial
            return tuple(  # type: ignore[return-value]
                np.stack([poly.polyval(t, poly.polyder(c, k)) for c in self.monomials], -1)
                for k in range(3)
            )
        assert self.beta is not None
        T = self.duration
        s = t / T
        x = 2.0 * s - 1.0
        blend = (10 * s**3 - 15 * s**4 + 6 * s**5, 30 * s**2 - 60 * s**3 + 30 * s**4)
        blend2 = 60 * s - 180 * s**2 + 120 * s**3
        delta = self.goal - self.start
        q = self.start + np.outer(blend[0], delta)
        qd = np.outer(blend[1], delta) / T
        qdd = np.outer(blend2, delta) / T**2
        b = s**3 * (1 - s) ** 3
        b1 = 3 * s**2 * (1 - s) ** 3 - 3 * s**3 * (1 - s) ** 2
        b2 = 6 * s * (1 - s) ** 3 - 18 * s**2 * (1 - s) ** 2 + 6 * s**3 * (1 - s)
        # The polynomials depend on n alone: evaluated once for the longest joint, every joint
        # weighting them by its column of coefficients (zero beyond its own).
        weights = self.jacobi_weights
        longest = np.arange(len(weights))
        p0 = _jacobi(longest, 0, x)
        p1 = (longest + 13) * _jacobi(longest, 1, x)  # d/ds = 2 d/dx
        p2 = (longest + 13) * (longest + 14) * _jacobi(longest, 2, x)
        q += (b[:, None] * p0) @ weights
        qd += ((b1[:, None] * p0 + b[:, None] * p1) @ weights) / T
        qdd += ((b2[:, None] * p0 + 2 * b1[:, None] * p1 + b[:, None] * p2) @ weights) / T**2
        return q, qd, qdd


def file_path(plan: Plan) -> FilePath:
    """The plan's joint paths as its file defines them."""
    names = plan.robot.joints
    stored = [np.asarray(plan.coefficients[name], dtype=float) for name in names]
    monomial = plan.basis == MONOMIAL_BASIS
    return FilePath(
        duration=plan.duration,
        start=np.asarray(plan.request.start_joints, dtype=float),
        goal=np.asarray(plan.request.goal_joints, dtype=float),
        beta=None if monomial else stored,
        monomials=stored if monomial else None,
    )
