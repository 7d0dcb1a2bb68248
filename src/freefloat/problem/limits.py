"""freefloat's stated limits on its inputs, checked before any work starts.

Each limit is a named constant here (listed in docs/limits.md) and each
refusal is an :class:`~freefloat.errors.InputLimitError` that names the value, the limit and
its unit, quoting at most a short excerpt of the value. Why these values:

- :data:`DURATION_RANGE_S`: rates scale as 1/T and accelerations and torques as 1/T^2, so a
  duration of 1e-300 s (or 1e300 s) overflows the torques and the integration step control;
  1 ms to 11.6 days covers every manoeuvre of a space manipulator with room to spare.
- :data:`MAX_ANGLE_DEG`: a joint angle or an Euler angle beyond ten whole turns is a typing
  error, and beyond about 1e15 deg its sine and cosine lose every digit.
- :data:`MAX_LENGTH_M`: positions, sizes and prismatic joint values; a kilometre is far beyond
  any spacecraft and keeps squared lengths (inertias) far from overflow.
- :data:`MAX_MAGNITUDE`: any other number of a scenario (masses in kg, inertias in kg m^2,
  quaternion components).
- :data:`MAX_EXTRA_COEFFICIENTS`: free coefficients per joint, so a polynomial degree of at
  most 12 (5 + 7); a monomial basis on [0, 1] of higher degree is ill-conditioned, and each
  coefficient costs memory for every node of the attitude integration (a count of 1000000 asked
  for 6.3 GB).
- :data:`MAX_JOINTS`: the planner's cost grows faster than linearly with the joint count (the
  planar map has N (N + 1) / 2 terms, the freedom search up to N + 2 attempts, every Jacobian
  N columns per free coefficient), but its work is bounded by counts (residual evaluations per
  freedom distribution, continuation steps, objective evaluations 4000 / N), not by time.
  24 covers two 7-joint arms with grippers or a 7-joint arm on a boom; measured in
  ``scripts/bench.py --multi-arm-only`` and docs/multi_arm.md (Robonaut 2's 14 joints plan in
  well under 2 s, generated 24-joint chains plan or are refused within their budget).
- :data:`MAX_SAMPLES`: memory and file size grow with the samples (100001 samples of the
  worked example: 18 s, 0.8 GB, a 58 MB file).
"""

from __future__ import annotations

import math
from typing import Any

from ..errors import InputError, InputLimitError, excerpt

__all__ = [
    "DURATION_RANGE_S",
    "MAX_ANGLE_DEG",
    "MAX_EXTRA_COEFFICIENTS",
    "MAX_JOINTS",
    "MAX_LENGTH_M",
    "MAX_MAGNITUDE",
    "MAX_OBSTACLES",
    "MAX_SAMPLES",
    "MAX_SCENARIO_BYTES",
    "check_duration",
    "check_extra",
    "check_joint_count",
    "check_number",
    "check_samples",
    "finite_number",
]

#: Largest scenario or sweep file read (bytes): a scenario is a page of text.
MAX_SCENARIO_BYTES = 1_000_000
#: Accepted motion durations T (s).
DURATION_RANGE_S = (1e-3, 1e6)
#: Largest magnitude of an angle in a scenario: joint angles, Euler angles (deg).
MAX_ANGLE_DEG = 3600.0
#: Largest magnitude of a length in a scenario: positions, sizes, prismatic joints (m).
MAX_LENGTH_M = 1000.0
#: Largest magnitude of any other number in a scenario (kg, kg m^2, quaternion components).
MAX_MAGNITUDE = 1e9
#: Most free coefficients per joint beyond the quintic (polynomial degree at most 25; the
#: orthonormal basis keeps the end conditions exactly at any degree).
MAX_EXTRA_COEFFICIENTS = 20
#: Most keep-out objects of a scenario: each adds a pair per arm body to every query (3000
#: took 34 s to plan a UR5 servicer, 15000 over two minutes; 1 MB of TOML holds 15000).
MAX_OBSTACLES = 64
#: Most movable joints the planner takes (two 7-joint arms with grippers fit).
MAX_JOINTS = 24
#: Most samples of a plan (``--samples``, ``samples =`` of a sweep, an export's ``--rate``
#: times the duration): 10001 samples of the Panda servicer are a 12.5 MB plan file written in
#: about 4 s; a plan's polynomials give any other instant exactly.
MAX_SAMPLES = 10001


def finite_number(value: Any) -> bool:
    """Whether ``value`` is a number (not a boolean) that a float holds finitely.

    An integer beyond the floats (a 400-digit TOML integer) is not: ``math.isfinite`` raises
    ``OverflowError`` on it.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(float(value))
    except OverflowError:
        return False


def check_number(
    value: Any,
    name: str,
    high: float = MAX_MAGNITUDE,
    unit: str = "",
    low: float | None = None,
) -> float:
    """``value`` as a float if it is a finite number within ``[low, high]``.

    Args:
        value: the value as read (a TOML number, or anything else).
        name: what it is, for messages (``"[start] joint 'q1'"``).
        high: the largest accepted value.
        unit: the unit of the value, for messages.
        low: the smallest accepted value; default ``-high``.

    Raises:
        InputError: not a number (a string, a list, a boolean...), or NaN or infinite.
        InputLimitError: outside the range (an integer too large for a float is outside it).
    """
    low = -high if low is None else low
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{name} must be a number, got {excerpt(value)}")
    try:
        number = float(value)
    except OverflowError:  # an integer beyond the floats
        raise InputLimitError(name, value, low, high, unit) from None
    if not math.isfinite(number):
        raise InputError(f"{name} must be finite, got {excerpt(value)}")
    if not low <= number <= high:
        raise InputLimitError(name, value, low, high, unit)
    return number


def check_duration(value: Any, name: str = "duration") -> float:
    """A duration (s) within :data:`DURATION_RANGE_S`.

    Raises:
        InputError: not a finite number, or not positive.
        InputLimitError: outside the range.
    """
    low, high = DURATION_RANGE_S
    duration = check_number(value, name, high, "s", low=-math.inf)
    if duration <= 0.0:
        raise InputError(f"{name} must be > 0 s, got {duration:g}")
    if duration < low:
        raise InputLimitError(name, duration, low, high, "s")
    return duration


def check_samples(count: Any, name: str = "samples") -> int:
    """A sample count, 2 to :data:`MAX_SAMPLES`.

    Raises:
        InputError: not an integer >= 2.
        InputLimitError: above the maximum.
    """
    if isinstance(count, bool) or not isinstance(count, int):
        raise InputError(f"{name} must be an integer, got {excerpt(count)}")
    if count < 2:
        raise InputError(f"{name} must be at least 2, got {count}")
    if count > MAX_SAMPLES:
        raise InputLimitError(
            name, count, 2, MAX_SAMPLES, why="a plan's polynomials give any other instant"
        )
    return count


def check_extra(count: Any, name: str) -> int:
    """A count of free coefficients for one joint, 0 to :data:`MAX_EXTRA_COEFFICIENTS`.

    Raises:
        InputError: not an integer >= 0.
        InputLimitError: above the maximum.
    """
    if isinstance(count, bool) or not isinstance(count, int) or count < 0:
        raise InputError(f"{name} must be an integer >= 0, got {excerpt(count)}")
    if count > MAX_EXTRA_COEFFICIENTS:
        raise InputLimitError(
            name,
            count,
            0,
            MAX_EXTRA_COEFFICIENTS,
            why=f"polynomial degree at most {5 + MAX_EXTRA_COEFFICIENTS}",
        )
    return count


def check_joint_count(count: int, robot: str = "the robot") -> None:
    """Refuse a robot with more movable joints than :data:`MAX_JOINTS`.

    Raises:
        InputLimitError: too many joints.
    """
    if count > MAX_JOINTS:
        raise InputLimitError(
            f"movable joints of {robot}",
            count,
            None,
            MAX_JOINTS,
            why="the planner's budget is stated for at most that many (docs/limits.md); "
            "lock joints ([robot] lock = [...] in the scenario, or freefloat compose --lock) "
            "to plan with fewer",
        )
