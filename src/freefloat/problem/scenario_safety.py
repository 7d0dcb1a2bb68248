"""A scenario's ``[safety]``, ``[[obstacles]]`` and ``[constraints.<name>]`` tables, read.

Pure parsing (metres, degrees at this edge, radians inside): key checks and limits, no file
written. The format is described in :mod:`freefloat.problem.scenario`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import InputError, InputLimitError, ScenarioError, UnknownNameError, excerpt
from ..robot.collision import Obstacle
from .constraints.base import Constraint
from .constraints.registry import constraint_from_record, default_constraints
from .limits import MAX_LENGTH_M, MAX_OBSTACLES, check_number
from .robot_table import check_keys, number, numbers, scenario_errors, triple

__all__ = ["OBSTACLE_KEYS", "SAFETY_KEYS", "Safety", "constraint_tables", "safety_tables"]

#: Keys of ``[safety]`` and of each ``[[obstacles]]`` table.
SAFETY_KEYS = ("margin_m", "srdf", "check")
OBSTACLE_KEYS = ("name", "box", "sphere", "capsule", "xyz", "rpy_deg")


@dataclass(frozen=True)
class Safety:
    """What the plan must keep clear of.

    Attributes:
        margin: required clearance between checked bodies (m).
        srdf: SRDF whose disabled pairs are not checked; None: the known SRDF of a composed
            example-robot-data arm, or none.
        obstacles: keep-out objects fixed to the spacecraft.
        check: whether clearance is a constraint at all (``[safety] check = false`` turns it
            off; verification then reports no clearance check).
    """

    margin: float = 0.01
    srdf: Path | None = None
    obstacles: tuple[Obstacle, ...] = ()
    check: bool = True


def safety_tables(table: Any, obstacles: Any, relative_to: Path | None) -> Safety:
    """``[safety]`` and ``[[obstacles]]`` (metres, degrees) as a :class:`Safety`."""
    table = {} if table is None else table
    if not isinstance(table, Mapping):
        raise ScenarioError("[safety] must be a table")
    check_keys(table, SAFETY_KEYS, "[safety]")
    given = table.get("margin_m", 0.01)
    if isinstance(given, (int, float)) and not isinstance(given, bool) and given < 0.0:
        raise ScenarioError(f"[safety] margin_m must be >= 0 m, got {given:g}")
    margin = scenario_errors(check_number, given, "[safety] margin_m", MAX_LENGTH_M, "m", 0.0)
    srdf = None
    if "srdf" in table:
        if not isinstance(table["srdf"], str):
            raise ScenarioError(f"[safety] srdf must be a file path, got {excerpt(table['srdf'])}")
        srdf = Path(table["srdf"]).expanduser()
        if not srdf.is_absolute() and relative_to is not None:
            srdf = relative_to / srdf
        if srdf.exists() and not srdf.is_file():
            raise ScenarioError(
                f"[safety] srdf {srdf} is not a regular file (a folder, a device or a FIFO); "
                "give an SRDF file"
            )
        if not srdf.is_file():
            raise ScenarioError(f"[safety] srdf file not found: {srdf}")
    check = table.get("check", True)
    if not isinstance(check, bool):
        raise ScenarioError(f"[safety] check must be true or false, got {excerpt(check)}")
    items = [] if obstacles is None else obstacles
    if not isinstance(items, list) or not all(isinstance(o, Mapping) for o in items):
        raise ScenarioError("[[obstacles]] must be a list of tables")
    if len(items) > MAX_OBSTACLES:
        raise InputLimitError("keep-out objects ([[obstacles]])", len(items), 0, MAX_OBSTACLES)
    parsed = []
    for index, item in enumerate(items):
        where = f"[[obstacles]] #{index + 1}"
        check_keys(item, OBSTACLE_KEYS, where)
        name = item.get("name", f"obstacle_{index + 1}")
        if not isinstance(name, str) or not name:
            raise ScenarioError(f"{where}: name must be a non-empty string")
        shapes = [s for s in ("box", "sphere", "capsule") if s in item]
        if len(shapes) != 1:
            raise ScenarioError(
                f"{where} ({name}): give exactly one shape: box = [x, y, z], sphere = r or "
                "capsule = [r, length] (m)"
            )
        shape = shapes[0]
        raw = item[shape]
        if shape == "sphere":  # sizes: at least 0 (the obstacle refuses 0 itself)
            size = (number(raw, f"{where} sphere", MAX_LENGTH_M, "m", 0.0),)
        else:
            count = 3 if shape == "box" else 2
            size = tuple(numbers(raw, count, f"{where} {shape}", MAX_LENGTH_M, "m", 0.0))
        try:
            parsed.append(
                Obstacle(
                    name,
                    shape,
                    tuple(float(s) for s in size),
                    triple(item, "xyz", [0.0, 0.0, 0.0], where),
                    _radians3(triple(item, "rpy_deg", [0.0] * 3, where)),
                )
            )
        except InputError as exc:
            raise ScenarioError(str(exc)) from None
    names = [o.name for o in parsed]
    if len(set(names)) != len(names):
        raise ScenarioError(f"[[obstacles]] names must be unique, got {excerpt(names)}")
    return Safety(margin, srdf, tuple(parsed), check)


def constraint_tables(table: Any) -> tuple[Constraint, ...]:
    """``[constraints.<name>]`` tables as constraints, by the registry."""
    if not isinstance(table, Mapping):
        raise ScenarioError("[constraints] must hold one table per constraint, by name")
    out = []
    always = [c.name for c in default_constraints()]
    for name, parameters in table.items():
        if name in always:
            raise ScenarioError(f"[constraints.{name}]: always honoured, it takes no table")
        try:
            out.append(constraint_from_record(name, parameters))
        except UnknownNameError:
            raise
        except InputError as exc:
            raise ScenarioError(f"[constraints.{name}] {exc}") from None
    return tuple(out)


def _radians3(degrees: tuple[float, float, float]) -> tuple[float, float, float]:
    """Roll, pitch, yaw in degrees as radians."""
    return (math.radians(degrees[0]), math.radians(degrees[1]), math.radians(degrees[2]))
