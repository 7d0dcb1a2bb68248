"""The ``[payload]`` table of a scenario: a captured payload fixed to an end effector.

Mass in kg, centre of mass ``com_xyz`` in m (end-effector frame), ``inertia`` about the centre
of mass in kg m^2 (``[ixx, iyy, izz, ixy, ixz, iyz]``), or a uniform ``box`` (edges, m);
``held_by`` names the end effector that holds it (default: the scenario's first).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..errors import InputError, ScenarioError, excerpt
from ..robot.payload import Payload, check_mass
from .limits import MAX_MAGNITUDE
from .robot_table import check_keys, number, numbers, triple

__all__ = ["PAYLOAD_KEYS", "payload_holder", "payload_table"]

#: Keys of the ``[payload]`` table.
PAYLOAD_KEYS = ("mass", "com_xyz", "inertia", "box", "held_by")


def payload_table(table: Any) -> Payload | None:
    """``[payload]`` (kg, m, kg m^2) as a :class:`Payload`, or None."""
    if table is None:
        return None
    if not isinstance(table, Mapping):
        raise ScenarioError("[payload] must be a table")
    check_keys(table, PAYLOAD_KEYS, "[payload]")
    if "mass" not in table:
        raise ScenarioError("[payload] needs mass [kg]")
    try:
        mass = number(table["mass"], "[payload] mass", MAX_MAGNITUDE, "kg")
        com = triple(table, "com_xyz", [0.0, 0.0, 0.0], "[payload]")
        box = triple(table, "box", None, "[payload]") if "box" in table else None
        if "inertia" in table:
            inertia = tuple(float(v) for v in numbers(table["inertia"], 6, "[payload] inertia"))
            return Payload(mass=mass, com_xyz=com, inertia=inertia, box=box)  # type: ignore[arg-type]
        if box is not None:  # a uniform box, as compose --payload-box makes it
            return Payload.uniform_box(mass, box, com)
        check_mass(mass)  # a bad mass is named before the missing inertia
    except InputError as exc:
        raise ScenarioError(str(exc)) from None
    raise ScenarioError(
        "[payload] needs inertia = [ixx, iyy, izz, ixy, ixz, iyz] about its centre of mass "
        "[kg m^2], or a box [m] for a uniform box's"
    )


def payload_holder(held_by: Any, end_effectors: tuple[str, ...]) -> str | None:
    """The link that holds the payload: ``held_by`` (the table's value), or else the first.

    The first of ``end_effectors``, that is; None when neither names one.

    Raises:
        ScenarioError: ``held_by`` not a frame name, or not one of ``end_effectors``.
    """
    if held_by is None:
        return end_effectors[0] if end_effectors else None
    if not isinstance(held_by, str) or not held_by.strip():
        raise ScenarioError(
            f"[payload] held_by must name the end effector that holds it, got {excerpt(held_by)}"
        )
    if held_by not in end_effectors:
        raise ScenarioError(
            f"[payload] held_by {excerpt(held_by)} is not one of the scenario's end effectors: "
            f"{', '.join(repr(n) for n in end_effectors)}"
        )
    return held_by
