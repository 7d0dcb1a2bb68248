"""How far inside a bound the solvers' rows ask a path to be, instant by instant.

Rows at instants hold a path there, not between them: a constraint of the pose or attitude
(the spacecraft's swing and pointing cone, the end-effector cone) asks its rows for a little
room, ``full`` (its unit), so that a path found on the rows (a start path at fixed instants,
say) does not peak beyond the bound between them. No path is known to have more room than
the roomier end has (a tool axis that cannot leave a cone's rim has none anywhere), so at
most half of that is asked anywhere (:func:`room_asked`). No path can have more room at an
end than the end itself has (the start and goal are fixed), so near an end with less than
twice that the room asked tapers to half that end's: every quantity of the pose moves from an
end as the cube of the time from it (the joints start and stop with zero velocity and
acceleration), and so does the taper,

    slack(s) = min(asked, room_e / 2 + asked (d_e(s) / TAPER_WIDTH)^3 for each end e)

with ``d_e(s)`` the normalised time from end ``e`` (``s`` or ``1 - s``), clipped to ``[0,
asked]`` (0 at an end outside the bound, where the taper reaches a little further than
:data:`TAPER_WIDTH`). A goal on a swing bound thus keeps the full room in the middle of the
motion, where a start path found on the rows would otherwise peak beyond it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["TAPER_WIDTH", "room_asked", "tapered_slack"]

#: Normalised time from an end over which the room asked tapers to that end's own.
TAPER_WIDTH = 0.25


def room_asked(start_room: float, goal_room: float, full: float) -> float:
    """The room asked away from the ends: ``full``, or half the roomier end's when less.

    Args:
        start_room: how far inside the bound the start lies (the unit; negative: outside).
        goal_room: the same for the goal.
        full: the room a constraint asks when its ends allow it.
    """
    return float(np.clip(0.5 * max(start_room, goal_room), 0.0, full))


def tapered_slack(
    instants: np.ndarray, start_room: float, goal_room: float, full: float
) -> np.ndarray:
    """(K,) the room the rows ask at normalised ``instants`` (the constraint's unit).

    Args:
        instants: (K,) normalised times in [0, 1].
        start_room: how far inside the bound the start lies (the unit; negative: outside).
        goal_room: the same for the goal.
        full: the room asked away from the ends when they allow it (:func:`room_asked`).
    """
    asked = room_asked(start_room, goal_room, full)
    s = np.asarray(instants, dtype=float)
    near_start = 0.5 * start_room + asked * (s / TAPER_WIDTH) ** 3
    near_goal = 0.5 * goal_room + asked * ((1.0 - s) / TAPER_WIDTH) ** 3
    return np.clip(np.minimum(near_start, near_goal), 0.0, asked)
