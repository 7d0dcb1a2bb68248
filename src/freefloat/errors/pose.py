"""Errors of one configuration: outside its limits, in collision, outside a pose's constraint.

A start or goal outside its joint limits, closer than the clearance margin or breaking a
constraint of the pose alone, and a joint locked outside its limits.

Units as in every message: deg at the edges (m for prismatic joints), m for distances.
"""

from __future__ import annotations

from ..excerpts import apart
from .base import FreeFloatError


class JointLimitError(FreeFloatError):
    """A joint position outside its URDF limits; carries the joint and its interval."""

    def __init__(
        self,
        joint: str,
        value: float,
        lower: float,
        upper: float,
        where: str,
        unit: str = "deg",
        scale: float = 1.0,
    ) -> None:
        self.joint = joint
        self.value = value
        self.lower = lower
        self.upper = upper
        self.where = where
        shown = value * scale
        super().__init__(
            f"{where}: joint {joint!r} = {apart(shown, lower * scale, upper * scale)} {unit} is "
            f"outside its limits [{lower * scale:.6g}, {upper * scale:.6g}] {unit}"
        )


class CollisionError(FreeFloatError):
    """A start or goal configuration closer than the clearance margin; carries the pair.

    Attributes:
        where: ``"start"`` or ``"goal"``.
        pair: the two bodies, ``"a / b"``.
        clearance: their signed distance (m; negative when they overlap).
        margin: the required clearance (m).
        chosen: whether those joints came from inverse kinematics of an end-effector goal
            (the message then asks to move that goal).
        why: what else the reader should know of the pair ("" when nothing).
        fixed: no joint values change the pair's distance (then no joints are asked to move).
        keep_out: the pair includes a keep-out object (an SRDF does not spare those).
    """

    def __init__(
        self,
        where: str,
        pair: str,
        clearance: float,
        margin: float,
        chosen: bool = False,
        why: str = "",
        fixed: bool = False,
        keep_out: bool = False,
    ) -> None:
        self.where = where
        self.pair = pair
        self.clearance = float(clearance)
        self.margin = float(margin)
        self.chosen = chosen
        self.fixed = fixed
        self.keep_out = keep_out
        state = "overlap by" if clearance < 0 else "are"
        amount = f"{abs(clearance):.4g} m" + ("" if clearance < 0 else " apart")
        if fixed:
            way = "move or shrink the keep-out object" if keep_out else "disable it in an SRDF"
            move = f"no joint values change this pair's distance: {way} "
        elif chosen:
            move = f"move the end-effector goal (inverse kinematics chose the {where} joints) "
        else:
            move = f"move the {where} joints "
        super().__init__(
            f"{where} configuration: {pair} {state} {amount}, below the clearance margin "
            f"{margin:g} m; {move}or lower [safety] margin_m" + (f" ({why})" if why else "")
        )


class EndpointError(FreeFloatError):
    """A start or goal configuration that breaks a path constraint; no path can keep it.

    Attributes:
        where: ``"start"`` or ``"goal"``.
        constraint: the constraint's name (its scenario table ``[constraints.<name>]``).
        excess: how far beyond it the configuration is (in the constraint's unit).
        detail: the constraint's own account (an angle, a distance).
        chosen: whether those joints came from inverse kinematics of an end-effector goal.
    """

    def __init__(
        self, where: str, constraint: str, excess: float, detail: str, chosen: bool = False
    ) -> None:
        self.where = where
        self.constraint = constraint
        self.excess = float(excess)
        self.detail = detail
        self.chosen = chosen
        move = (
            "move the end-effector goal (inverse kinematics chose the goal joints)"
            if chosen
            else f"move the {where} joints"
        )
        ends = "starts" if where == "start" else "ends"
        super().__init__(
            f"{where} configuration breaks {constraint} ({detail}), where every path {ends}; "
            f"{move} or loosen [constraints.{constraint}]"
        )


class GoalAttitudeError(FreeFloatError):
    """A start or goal attitude that breaks a constraint of the spacecraft's attitude.

    Every path starts and ends at rest there, so no path keeps the constraint.

    Attributes:
        constraint: the constraint's name (its scenario table ``[constraints.<name>]``).
        excess: how far beyond it the attitude is (in the constraint's unit).
        detail: the constraint's own account (the turn from the start, the bound).
        where: ``"goal"``, ``"start"``; for a correction ``"measured"`` (where it starts)
            or ``"plan's goal"`` (where it ends).
    """

    def __init__(self, constraint: str, excess: float, detail: str, where: str = "goal") -> None:
        self.constraint = constraint
        self.excess = float(excess)
        self.detail = detail
        self.where = where
        table = f"[constraints.{constraint}]"
        kept = f": no correction from this measured attitude keeps the plan's {table}"
        said = {
            "goal": f"where every path ends; choose a goal attitude it allows or loosen {table}",
            "start": f"where every path starts; change the start attitude or loosen {table}",
            "measured": f"where the correcting motion starts{kept}",
            "plan's goal": "where the correcting motion from the measured attitude (its start) "
            f"ends{kept}",
        }[where]
        super().__init__(f"{where} attitude breaks {constraint} ({detail}), {said}")


class LockedJointError(FreeFloatError):
    """A joint locked at a value outside its limits (or a goal that moves a locked joint).

    Attributes:
        joint: the joint's name.
        value: the locked value (deg for angular joints, m for prismatic ones).
        lower, upper: its limits (same unit).
        unit: ``"deg"`` or ``"m"``.
    """

    def __init__(
        self, joint: str, value: float, lower: float, upper: float, unit: str, why: str = ""
    ) -> None:
        self.joint = joint
        self.value = float(value)
        self.lower = float(lower)
        self.upper = float(upper)
        self.unit = unit
        reason = why or f"outside its limits [{lower:.6g}, {upper:.6g}] {unit}"
        super().__init__(
            f"joint {joint!r} locked at {apart(value, lower, upper)} {unit}: {reason}; lock it "
            "within "
            f"[{lower:.6g}, {upper:.6g}] {unit}"
        )
