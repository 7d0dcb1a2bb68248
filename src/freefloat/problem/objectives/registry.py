"""The objectives freefloat knows by name.

A new objective is one module with an :class:`~.base.Objective` subclass plus one entry here
(or, from another package, one ``freefloat.objectives`` entry point: :mod:`freefloat.plugins`);
scenarios (``[path] objective``), the command line (``--objective``) and plans name it.
"""

from __future__ import annotations

from ...errors import InputError, excerpt
from ...plugins import Registry, plugin_class
from .base import Objective
from .min_acceleration import MinAcceleration
from .min_effort import MinEffort
from .min_length import MinLength
from .min_norm import MinNorm

__all__ = ["DEFAULT_OBJECTIVE", "OBJECTIVES", "objective_named"]

#: Objective classes by name; with those installed packages declare in the
#: ``freefloat.objectives`` entry point group.
OBJECTIVES: Registry[type[Objective]] = Registry(
    "objective",
    {cls.name: cls for cls in (MinNorm, MinEffort, MinAcceleration, MinLength)},
    plugin_class(Objective, "objective"),
)

#: The objective when none is named: the paper's minimum norm, the smallest deviation from the
#: quintic in the orthonormal basis.
DEFAULT_OBJECTIVE = MinNorm.name


def objective_named(name: str) -> Objective:
    """A new objective of that name.

    Raises:
        InputError: the name is not one of :data:`OBJECTIVES`.
    """
    if name not in OBJECTIVES:
        raise InputError(
            f"unknown objective {excerpt(name)}; valid objectives: " + ", ".join(OBJECTIVES)
        )
    return OBJECTIVES[name]()
