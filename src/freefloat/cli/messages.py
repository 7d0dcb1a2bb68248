"""The library's messages as the command line says them: angles in degrees, a headline."""

from __future__ import annotations

import math

from ..errors import FreeFloatError, UnreachableAttitudeError, VelocityLimitError

__all__ = ["error_message", "in_degrees"]


def in_degrees(exc: FreeFloatError) -> str:
    """The error's message, with angular rates in deg/s where the library speaks rad/s."""
    if isinstance(exc, VelocityLimitError) and exc.unit == "rad":
        return exc.message_in(math.degrees(1.0), "deg")
    return str(exc)


def error_message(exc: FreeFloatError) -> str:
    """The error's line after ``error:`` (:func:`in_degrees`), a refused goal attitude's headed.

    An unreached goal attitude's message starts with its figures ("reachable up to ..."): the
    command line says first what it is.
    """
    said = in_degrees(exc)
    if isinstance(exc, UnreachableAttitudeError):
        return f"goal attitude not reached: {said}"
    return said
