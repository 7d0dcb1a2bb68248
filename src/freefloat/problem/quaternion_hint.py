"""A warning for a written base quaternion that looks like another convention.

Scenario files give a quaternion in the order ``[x, y, z, w]`` (Pinocchio's, SciPy's, ROS
messages'). Eigen's constructor and many papers write ``w`` first, so the identity pasted
from them, ``[1, 0, 0, 0]``, reads here as a half turn about x: a valid attitude, planned or
refused as such (on ETS-VII: refused, 148 deg of the 179 deg asked reached). A
quaternion far from unit length is normalised, but it seldom is what was meant either.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import UnitsWarning

__all__ = ["NORM_SLACK", "warn_if_odd_quaternion"]

#: How far from 1 the norm of a written quaternion may be before a warning (rounded
#: components, 4 decimals, stay well within it).
NORM_SLACK = 1e-3


def warn_if_odd_quaternion(written: np.ndarray, where: str) -> None:
    """Warn (:class:`~freefloat.errors.UnitsWarning`) of ``w`` first or a norm far from 1.

    Args:
        written: the four components as written in the file (non-zero).
        where: the table, ``"[start]"`` or ``"[goal]"``.
    """
    shown = ", ".join(f"{float(v):g}" for v in written)
    if written[0] != 0.0 and not np.any(written[1:]):
        warnings.warn(
            f"{where} base_quaternion_xyzw = [{shown}] is a half turn about x (the order is "
            "x, y, z, w); the identity attitude is [0, 0, 0, 1]",
            UnitsWarning,
            stacklevel=3,
        )
        return
    norm = float(np.linalg.norm(written))
    if abs(norm - 1.0) > NORM_SLACK:
        warnings.warn(
            f"{where} base_quaternion_xyzw = [{shown}] has norm {norm:.6g}, not 1; it is "
            f"used divided by it (a unit quaternion; within {NORM_SLACK:g} of 1 goes unsaid)",
            UnitsWarning,
            stacklevel=3,
        )
