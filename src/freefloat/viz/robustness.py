"""Text reports of a plan's robustness to its mass properties (angles in degrees)."""

from __future__ import annotations

import math

from ..plans.guarantees import RobustnessReport
from ..problem.uncertainty import AttitudeSpread, Uncertainty
from ..robust.distribution import ErrorDistribution

__all__ = ["distribution_lines", "robustness_line", "sensitivity_table"]


def distribution_lines(found: ErrorDistribution | None, jobs: int) -> list[str]:
    """The final attitude error distribution of a replay sweep (deg)."""
    if found is None:
        return [f"  no job of {jobs} was replayed (see the message column)"]
    d = math.degrees
    rms = math.sqrt(float(found.covariance.trace()))
    return [
        f"  replayed {found.count} of {jobs}; final attitude error [deg]: mean {d(found.mean):.4g},"
        f" std {d(found.std):.4g}, median {d(found.median):.4g}, 95 % {d(found.p95):.4g}, "
        f"largest {d(found.largest):.4g}",
        f"  error rotation vector: RMS spread {d(rms):.4g} deg (sqrt of the covariance's trace)",
    ]


def robustness_line(record: RobustnessReport) -> str:
    """The plan summary's one line: first-order attitude error for an uncertainty (deg)."""
    described = Uncertainty(record.mass_fraction, record.com_m, record.inertia_fraction)
    return (
        f"  robustness      {described.describe()} off: final attitude "
        f"{math.degrees(record.rms_rad):.3g} deg RMS, {math.degrees(record.worst_rad):.3g} deg "
        "worst case (first order; freefloat sensitivity)"
    )


def sensitivity_table(spread: AttitudeSpread) -> list[str]:
    """Per body the error each uncertainty causes, then the combined figures (deg)."""
    width = max(12, *(len(b.body) + 2 for b in spread.bodies))
    lines = [
        f"  uncertainty: {spread.uncertainty.describe()} (each parameter of each body)",
        f"  {'body':<{width}}{'mass [deg]':>12}{'com [deg]':>12}{'inertia [deg]':>15}"
        f"{'all, RMS [deg]':>16}",
    ]
    for body in spread.bodies:
        lines.append(
            f"  {body.body:<{width}}{math.degrees(body.mass):>12.4g}"
            f"{math.degrees(body.com):>12.4g}{math.degrees(body.inertia):>15.4g}"
            f"{math.degrees(body.rms):>16.4g}"
        )
    lines.append(
        f"  combined: RMS {math.degrees(spread.rms):.4g} deg, worst case "
        f"{math.degrees(spread.worst):.4g} deg (first order; per-body columns are worst cases)"
    )
    return lines
