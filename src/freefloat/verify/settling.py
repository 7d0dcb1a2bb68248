"""How far the clearance certificate refines, and what it keeps while it does.

An interval of one pair is *settled* when its lower bound lies within :func:`tolerance` of the
least clearance measured so far (:func:`settled_above`); the certificate refines the others
(:mod:`freefloat.verify.certificate`), its work items ordered in a heap by their bounds.
"""

from __future__ import annotations

from .clearance import ACCURACY, CHECK_TOLERANCE, SLACK_FRACTION

__all__ = [
    "EXACT",
    "LAST_LOOKS",
    "SEPARATED",
    "SPHERES",
    "TAYLOR",
    "Item",
    "Least",
    "settled_above",
    "tolerance",
]

#: Most instants measured at the end because their bound lies below the least measured.
LAST_LOOKS = 16

#: A heap item: lower bound (m), interval ends (s), pair, what its ends are (a level below),
#: speed (m/s).
Item = tuple[float, float, float, int, int, float]
#: An item's ends bounded by the spheres alone (the first pass), by the separating direction
#: or exact distances (:meth:`.Instants.lower`), measured exactly at both, or its bound
#: raised by the second-order bound over it (:mod:`.taylor`), next halved.
SPHERES, SEPARATED, EXACT, TAYLOR = 0, 1, 2, 3


def tolerance(measured: float, margin: float) -> float:
    """How far below the smallest measured clearance a settled bound may lie (m).

    :data:`ACCURACY` near the margin, a fraction :data:`SLACK_FRACTION` of the slack above it:
    a bound that close to a minimum well clear of the margin still clears it.
    """
    return max(ACCURACY, SLACK_FRACTION * (measured - margin))


def settled_above(measured: float, margin: float) -> float:
    """The bound (m) at or above which an interval is settled, ``measured`` the least yet.

    Within :func:`tolerance` of ``measured``; but not below what the ``clearance`` check
    needs while ``measured`` leaves room for it: a path 20 um clear of the margin must not
    fail because its bound was settled 100 um below its minimum. While ``measured`` clears
    the margin by :data:`CHECK_TOLERANCE`, the margin itself; while it clears the margin less
    half of that, the margin less :data:`CHECK_TOLERANCE` (what the check allows). A bound
    is never asked to come closer to ``measured`` than half that tolerance: nearer, the
    halvings needed grow without end (a wall 20 nm clear spent the 20,000 halvings).
    """
    loose = measured - tolerance(measured, margin)
    for need, room in ((margin, CHECK_TOLERANCE), (margin - CHECK_TOLERANCE, CHECK_TOLERANCE / 2)):
        if measured >= need + room:
            return max(loose, need)
    return loose


class Least:
    """The smallest clearance measured so far (m), its instant (s) and pair."""

    def __init__(self, value: float, time: float, pair: int) -> None:
        self.value, self.time, self.pair = value, time, pair

    def note(self, value: float, time: float, pair: int) -> None:
        """Keep a clearance ``value`` (m) at ``time`` (s) of ``pair`` if it is the least yet."""
        if value < self.value:
            self.value, self.time, self.pair = value, time, pair
