"""A warning for a written base quaternion that looks like another convention.

Scenario files give a quaternion in the order ``[x, y, z, w]`` (Pinocchio's, SciPy's, ROS
messages'). Eigen's constructor and many papers write ``w`` first, so the identity pasted
from them, ``[1, 0, 0, 0]``, reads here as a half turn about x: a valid attitude, planned or
refused as such (on ETS-VII: refused, 148 deg of the 179 deg asked reached), and any small
turn written so reads as nearly a half turn (``[0.99996, 0, 0, 0.0087]``, 1 deg about z
``w`` first, is 179 deg about x here; on Canadarm2 it planned, unwarned, until December
2026). A quaternion far from unit length is normalised, but it seldom is what was meant
either.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import UnitsWarning

__all__ = ["NORM_SLACK", "WIDE_TURN", "warn_if_odd_quaternion"]

#: How far from 1 the norm of a written quaternion may be before a warning (rounded
#: components, 4 decimals, stay well within it).
NORM_SLACK = 1e-3
#: A written attitude that turns more than this from the identity (deg), and less than 180
#: deg less this when read ``w`` first, is warned of: a small turn written ``w`` first reads
#: as nearly a half turn (a quarter turn, written either way, is not).
WIDE_TURN = 120.0


def _turn(w: float) -> float:
    """The rotation angle (deg, 0 to 180) of a unit quaternion whose scalar part is ``w``."""
    return float(np.degrees(2.0 * np.arccos(min(1.0, abs(w)))))


def warn_if_odd_quaternion(written: np.ndarray, where: str) -> None:
    """Warn (:class:`~freefloat.errors.UnitsWarning`) of ``w`` first or a norm far from 1.

    ``w`` first: the identity written so, or any attitude that turns more than
    :data:`WIDE_TURN` from the identity and less than ``180 - WIDE_TURN`` deg when its first
    component is read as ``w`` (so a wide turn meant as written, 130 deg about x say, is
    warned of too: the warning names both readings, and the plan uses the one written).

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
    as_written, w_first = (_turn(float(written[i]) / norm) for i in (3, 0))
    if as_written > WIDE_TURN and w_first < 180.0 - WIDE_TURN:
        warnings.warn(
            f"{where} base_quaternion_xyzw = [{shown}] is a {as_written:.4g} deg turn; read "
            f"w first it would be a {w_first:.4g} deg turn: the order is x, y, z, w (the "
            "identity attitude is [0, 0, 0, 1])",
            UnitsWarning,
            stacklevel=3,
        )
        return
    if abs(norm - 1.0) > NORM_SLACK:
        warnings.warn(
            f"{where} base_quaternion_xyzw = [{shown}] has norm {norm:.6g}, not 1; it is "
            f"used divided by it (a unit quaternion; within {NORM_SLACK:g} of 1 goes unsaid)",
            UnitsWarning,
            stacklevel=3,
        )
