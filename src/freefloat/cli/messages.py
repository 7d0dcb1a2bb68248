"""The library's messages as the command line says them: angles in degrees."""

from __future__ import annotations

import math

from ..errors import FreeFloatError, VelocityLimitError

__all__ = ["in_degrees"]


def in_degrees(exc: FreeFloatError) -> str:
    """The error's message, with angular rates in deg/s where the library speaks rad/s."""
    if isinstance(exc, VelocityLimitError) and exc.unit == "rad":
        return exc.message_in(math.degrees(1.0), "deg")
    return str(exc)
