"""A plan file's path records read back as free coefficients, for both path bases.

Format 4 stores the coefficients ``beta`` of the orthonormal basis (:mod:`freefloat.problem.basis`)
directly. Older formats store each joint's polynomial as monomials in t (s) and, as free
parameters, its coefficients of ``t^6`` and up in the old basis ``s^j - (a3 s^3 + a4 s^4 +
a5 s^5)`` (the end conditions removed); those are converted to the same paths in the new basis
by L2 projection (exact for a path of the family, up to the rounding of high-degree monomials).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import PlanMismatchError
from ..plans.format import Plan
from ..plans.sampling import path_quality
from ..plans.versions import MONOMIAL_BASIS
from ..problem.paths import JointPolynomials, PathFamily
from ..problem.residual import Problem

__all__ = ["check_quality", "free_counts", "monomial_basis", "root_beta"]


def monomial_basis(power: int) -> np.ndarray:
    """Ascending coefficients in s of the pre-format-4 basis polynomial ``phi_power`` (>= 6)."""
    lhs = np.array([[1.0, 1.0, 1.0], [3.0, 4.0, 5.0], [6.0, 12.0, 20.0]])
    rhs = np.array([1.0, power, power * (power - 1.0)])
    out = np.zeros(power + 1)
    out[3:6] = -np.linalg.solve(lhs, rhs)
    out[power] = 1.0
    return out


def free_counts(plan: Plan) -> list[int]:
    """Free coefficients per joint, in joint order."""
    lengths = [len(plan.coefficients[name]) for name in plan.robot.joints]
    return lengths if plan.basis != MONOMIAL_BASIS else [n - 6 for n in lengths]


def root_beta(plan: Plan, family: PathFamily, free: Sequence[Sequence[float]]) -> np.ndarray:
    """``beta`` of a root whose free parameters the file lists per joint (its own basis)."""
    if plan.basis != MONOMIAL_BASIS:
        return np.concatenate([np.asarray(f, dtype=float) for f in free])
    T = plan.duration
    rows = []
    for i, values in enumerate(free):
        delta = family.goal[i] - family.start[i]
        c = np.zeros(6 + len(values))
        c[0], c[3:6] = family.start[i], delta * np.array([10.0, -15.0, 6.0])
        for k, value in enumerate(values):
            c[: 7 + k] += value * T ** (6 + k) * monomial_basis(6 + k)
        rows.append(c / T ** np.arange(len(c)))  # in s -> in t
    return family.beta_from_path(JointPolynomials.from_monomials(rows, T))


def check_quality(plan: Plan, problem: Problem, beta: np.ndarray, tolerance: float) -> None:
    """Compare the file's ``path_quality`` record (format 4) with its recomputation.

    Raises:
        PlanMismatchError: a figure differs by more than ``tolerance`` (relative, of the
            largest figure, at least 1 deg) or names another joint.
    """
    if plan.quality is None:
        return
    mine = path_quality(problem, beta)
    theirs = plan.quality
    scale = max(1.0, mine.largest_excursion, mine.deviation_rms_deg)
    pairs = [
        ("largest_excursion", theirs.largest_excursion, mine.largest_excursion),
        ("deviation_rms_deg", theirs.deviation_rms_deg, mine.deviation_rms_deg),
        *(
            (f"excursion_beyond_span.{k}", theirs.excursion_beyond_span.get(k, math.nan), v)
            for k, v in mine.excursion_beyond_span.items()
        ),
    ]
    for name, stored, again in pairs:
        if not abs(stored - again) <= tolerance * scale:
            raise PlanMismatchError(
                f"path_quality.{name}", abs(stored - again), tolerance * scale, "deg"
            )
    if set(theirs.excursion_beyond_span) != set(mine.excursion_beyond_span):
        raise PlanMismatchError(
            "path_quality.excursion_beyond_span", math.inf, 0.0, message="other joints listed"
        )
