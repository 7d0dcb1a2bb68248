"""A warning for scenario joint values that look like radians (scenario files are in degrees).

Users coming from ROS often paste a joint state in radians, e.g. a UR5 start of
``[0, -1.57, 1.57, 0, 1.2, 0]``. Read as degrees it is a valid, nearly straight pose, so
nothing refuses it and the plan silently goes somewhere else. The heuristic: a ``[start]`` or
``[goal]`` table whose revolute joints are all within 2 pi (6.28) in magnitude, with at least
one value that is not a whole number. Written in degrees, poses are almost always whole or
beyond a few degrees on some joint (every shipped scenario is); a radian pose has fractional
values below 2 pi on every joint. A whole-number table (``[0, 0, 0]``, ``[0, 1, 2]``) is
accepted silently: there is no telling its unit.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping

from ..errors import UnitsWarning

__all__ = ["RADIAN_LIKE", "warn_if_radians"]

#: Largest magnitude of a joint value (as written, deg) that could be a pasted radian: 2 pi.
RADIAN_LIKE = 2.0 * math.pi


def warn_if_radians(written: Mapping[str, float], where: str) -> None:
    """Warn (:class:`~freefloat.errors.UnitsWarning`) when a joints table looks like radians.

    Args:
        written: the revolute joints' values as written in the file (meant as deg), by
            joint name; prismatic joints (m) left out.
        where: the table, ``"[start]"`` or ``"[goal]"``, or ``"--at"`` (``freefloat check``).
    """
    if not written or any(not abs(v) <= RADIAN_LIKE for v in written.values()):
        return
    fractional = [(name, v) for name, v in written.items() if v != round(v)]
    if not fractional:
        return
    name, value = max(fractional, key=lambda item: abs(item[1]))
    warnings.warn(
        UnitsWarning(
            f"{where} joints look like radians (every value within +-{RADIAN_LIKE:.2f}, "
            f"{name} = {value:g}); scenario joints are in degrees ({value:g} rad is "
            f"{math.degrees(value):.4g} deg)"
        ),
        stacklevel=2,
    )
