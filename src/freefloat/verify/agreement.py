"""How a recomputed number must agree with the plan's: tolerances and the comparison.

:func:`compare` raises :class:`~freefloat.errors.PlanMismatchError` naming the field, the worst
entry (its time and column) and the tolerance broken; the tolerances are explained in
:mod:`freefloat.verify.recompute`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import PlanMismatchError
from ..physics.attitude import geodesic_angle

__all__ = [
    "AXES",
    "BOUNDS_TOLERANCE_DEG",
    "FIGURE_FRACTION",
    "RELATIVE_TOLERANCE",
    "RESIDUAL_TOLERANCE",
    "ROBUSTNESS_TOLERANCE",
    "compare",
    "compare_terms",
    "rotation_angles",
    "scale_of",
    "unit_of",
]

#: Allowed disagreement of a recomputed number, relative to its field's scale.
RELATIVE_TOLERANCE = 1e-10
#: Allowed disagreement of the planar bounds (deg): L-BFGS-B refines the gain extremes to about
#: 1e-10, times a joint travel of a few radians, with a hundredfold margin.
BOUNDS_TOLERANCE_DEG = 1e-6
#: Allowed disagreement of a root's attitude residual (rad), plus the integration estimate.
RESIDUAL_TOLERANCE = 1e-9
#: Allowed disagreement of the robustness record's figures, relative to the figure.
ROBUSTNESS_TOLERANCE = 1e-8
#: A verification figure agrees when within this fraction of its check's tolerance (plus twice
#: the recomputed error estimate).
FIGURE_FRACTION = 1e-3

#: Column names of positions and quaternions.
AXES = ("x", "y", "z", "w")


def unit_of(kinds: Sequence[str], angular: str, linear: str) -> str:
    """``angular`` or ``linear`` or both, as the joints ``kinds`` are revolute or prismatic."""
    units = {linear if k == "prismatic" else angular for k in kinds}
    return " or ".join(sorted(units)) if units else angular


def scale_of(*arrays: np.ndarray) -> float:
    """The largest magnitude in ``arrays`` (at least 1e-300, so a tolerance is never 0)."""
    return max([1e-300, *(float(np.max(np.abs(a))) for a in arrays if np.size(a))])


def compare(
    field: str,
    stored: object,
    recomputed: object,
    tolerance: float | np.ndarray,
    unit: str = "",
    times: np.ndarray | None = None,
    columns: Sequence[str] | None = None,
) -> None:
    """Raise :class:`PlanMismatchError` where ``stored`` and ``recomputed`` differ too much."""
    a = np.asarray(stored, dtype=float)
    b = np.asarray(recomputed, dtype=float)
    if a.shape != b.shape:
        raise PlanMismatchError(
            field,
            math.inf,
            0.0,
            message=f"{a.shape} values stored, {b.shape} recomputed",
        )
    diff = np.abs(a - b)
    tol = np.broadcast_to(np.asarray(tolerance, dtype=float), diff.shape)
    bad = ~(diff <= tol)  # NaN is bad
    if not bad.any():
        return
    ratio = np.where(bad, np.nan_to_num(diff, nan=np.inf) / np.maximum(tol, 1e-300), -1.0)
    index = tuple(int(i) for i in np.unravel_index(int(np.argmax(ratio)), diff.shape))
    raise PlanMismatchError(
        field, float(diff[index]), float(tol[index]), unit, _where(index, times, columns)
    )


def _where(index: tuple[int, ...], times: np.ndarray | None, columns: Sequence[str] | None) -> str:
    parts = []
    rest = list(index)
    if times is not None and rest:
        parts.append(f"at t = {float(times[rest.pop(0)]):.6g} s")
    if columns is not None and rest:
        parts.append(f"({columns[rest.pop(0)]})")
    elif rest:
        parts.append(f"(entry {', '.join(str(i) for i in index)})")
    return " ".join(parts)


def compare_terms(
    field: str,
    stored: Sequence[float] | np.ndarray,
    coefficients: Sequence[float] | np.ndarray,
    first: int,
    duration: float,
    scale: float,
    unit: str,
) -> None:
    """Compare polynomial coefficients ``c_k`` (rad/s^k or m/s^k) from ``k = first`` on.

    Each term ``c_k T^k`` is held to :data:`RELATIVE_TOLERANCE` of the joint's largest term
    ``scale`` (rad or m).
    """
    want = np.asarray(coefficients, dtype=float)[first:]
    powers = np.arange(first, first + len(want))
    compare(
        field,
        stored,
        want,
        RELATIVE_TOLERANCE * scale / duration**powers,
        f"{unit}/s^k",
        None,
        [f"k = {k}" for k in powers],
    )


def rotation_angles(stored: np.ndarray, recomputed: np.ndarray) -> np.ndarray:
    """Per row, the angle (rad) between two attitudes, and any difference in norm."""
    angles = np.array([geodesic_angle(a, b) for a, b in zip(stored, recomputed, strict=True)])
    norms = np.abs(np.linalg.norm(stored, axis=-1) - np.linalg.norm(recomputed, axis=-1))
    out: np.ndarray = angles + norms
    return out
