"""The library's messages as the command line says them: angles in degrees."""

from __future__ import annotations

import math

from ..errors import FreeFloatError, VelocityLimitError

__all__ = ["in_degrees"]


def in_degrees(exc: FreeFloatError) -> str:
    """The error's message, with angular rates in deg/s where the library speaks rad/s."""
    if isinstance(exc, VelocityLimitError) and "rad/s" in str(exc):
        return (
            f"joint {exc.joint!r} reaches {math.degrees(exc.peak):.4g} deg/s, above its "
            f"velocity limit {math.degrees(exc.limit):.4g} deg/s; the shortest duration that "
            f"respects every velocity limit is {exc.shortest_duration:.4g} s"
        )
    return str(exc)
