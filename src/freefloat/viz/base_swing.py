"""How far the spacecraft turns on the way, read from a plan's samples (for the summary).

A goal a few degrees off may be reached by a motion that swings the spacecraft much further
on the way (Canadarm2 holding a 5 t payload: 82.5 deg for a 2.46 deg goal), which matters for
pointing, communication and power: the summary says how far, and when, and with a bound
``[constraints.base_swing]``, the bound and the largest turn its check found between the
samples.
"""

from __future__ import annotations

import math

import numpy as np

from ..physics.attitude import geodesic_angle
from ..plans.format import Plan

__all__ = ["base_swing_line"]


def base_swing_line(p: Plan) -> str:
    """The largest turn of the spacecraft from its start attitude over the samples (deg)."""
    quaternions = np.asarray(p.samples.base_quaternion_xyzw, dtype=float)
    start = np.asarray(p.base.start_quaternion_xyzw, dtype=float)
    turns = [geodesic_angle(start, q) for q in quaternions]
    k = int(np.argmax(turns))
    goal = geodesic_angle(start, np.asarray(p.base.target_quaternion_xyzw, dtype=float))
    return (
        f"  spacecraft      turns up to {math.degrees(turns[k]):.3g} deg from its start "
        f"attitude on the way (at t = {float(p.samples.t[k]):.4g} s, the largest of "
        f"{len(turns)} samples{_bound(p)}); its goal lies {math.degrees(goal):.3g} deg from it"
    )


def _bound(p: Plan) -> str:
    """``; 4 deg at most by the check ...``: the bound set, and the check's largest turn."""
    bounds = [c.parameters["max_deg"] for c in p.constraints if c.name == "base_swing"]
    checks = [c for c in p.verification.checks if c.name == "base_swing"]
    if not bounds or not checks:
        return ""
    largest = bounds[0] + math.degrees(checks[0].value)
    return (
        f"; the check's largest {largest:.7g} deg, at most {bounds[0]:.10g} deg allowed "
        "([constraints.base_swing])"
    )
