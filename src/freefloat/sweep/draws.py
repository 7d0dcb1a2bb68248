"""Random axis values and the axes that change a robot's inertial values.

An axis may draw its values at random instead of listing them::

    values = { normal = [mean, sigma], samples = 500, seed = 1 }
    values = { uniform = [low, high], samples = 500, seed = 1 }

in the unit of the value (kg, m, kg m^2...). The random axes of a sweep are drawn together:
they must have the same ``samples``, and draw ``i`` gives every random axis its ``i``-th value
(one job per draw, times the combinations of the other axes). Each axis draws from its own
seeded generator, so a sweep file always gives the same values.

Inertial axes name a URDF link's values: ``robot.links.<link>.mass``, ``.com.0`` to ``.com.2``,
``.inertia.ixx`` (``iyy``, ``izz``, ``ixy``, ``ixz``, ``iyz``), and, for a captured payload,
``payload.mass`` (and ``payload.com.N``, ``payload.inertia.ixx``...) when the sweep replays a
plan. A draw that would leave a body unphysical (a mass <= 0, an inertia not positive definite
or breaking the triangle inequality) is drawn again, so the distribution is truncated to
physical bodies; at most :data:`REDRAWS` times the samples are drawn in all.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import (
    FreeFloatError,
    InputError,
    InputLimitError,
    ScenarioError,
    UnknownNameError,
    excerpt,
)
from ..plans.schema import load_plan_file
from ..problem.limits import MAX_MAGNITUDE, finite_number
from ..problem.scenario import Scenario
from ..robust.inertial import PARAMETERS, robot_text, with_inertials

__all__ = [
    "REDRAWS",
    "Changes",
    "check_inertial_value",
    "inertial_changes",
    "inertial_key",
    "is_random",
    "plan_source",
    "random_values",
    "scenario_urdf",
]

#: A link's new inertial values: ``{link: {key: value}}`` (kg, m, kg m^2).
Changes = dict[str, dict[str, float]]

_RANDOM_KEYS = ("normal", "uniform", "samples", "seed")
#: Most draws in all, per sample asked for (physical bodies are drawn again).
REDRAWS = 100
#: Most samples of a random axis.
MAX_SAMPLES = 100_000


def inertial_key(key: str, replay: bool) -> tuple[str, str] | None:
    """``(link, parameter)`` of an inertial axis key, or None for a scenario key.

    ``payload.*`` keys are inertial only when the sweep replays a plan (a scenario's
    ``[payload]`` table is swept as scenario keys).

    Raises:
        UnknownNameError: ``robot.links.<link>.<x>`` with an unknown parameter.
    """
    if key.startswith("robot.links."):
        rest = key.removeprefix("robot.links.")
        for parameter in PARAMETERS:
            if rest.endswith("." + parameter) and len(rest) > len(parameter) + 1:
                return rest[: -len(parameter) - 1], parameter
        raise UnknownNameError(
            "inertial sweep key", key, [f"robot.links.LINK.{p}" for p in PARAMETERS]
        )
    if replay and key.startswith("payload."):
        parameter = key.removeprefix("payload.")
        if parameter not in PARAMETERS:
            raise UnknownNameError("payload sweep key", key, [f"payload.{p}" for p in PARAMETERS])
        return "payload", parameter
    return None


def inertial_changes(keys: Sequence[tuple[str, str] | None], values: Sequence[Any]) -> Changes:
    """The ``{link: {parameter: value}}`` of the inertial axes among ``keys``."""
    out: Changes = {}
    for key, value in zip(keys, values, strict=True):
        if key is not None:
            out.setdefault(key[0], {})[key[1]] = float(value)
    return out


def _pair(raw: Any, name: str, key: str) -> tuple[float, float]:
    """Two numbers of a random axis, each at most :data:`MAX_MAGNITUDE` in magnitude."""
    if not (
        isinstance(raw, list)
        and len(raw) == 2
        and all(finite_number(v) and abs(v) <= MAX_MAGNITUDE for v in raw)
    ):
        raise ScenarioError(
            f"axis {key!r}: {name} must be two finite numbers of magnitude at most "
            f"{MAX_MAGNITUDE:g}, got {excerpt(raw)}"
        )
    return float(raw[0]), float(raw[1])


def _draw_function(raw: Mapping[str, Any], key: str) -> tuple[Any, int]:
    """(function of a generator giving one value, samples) of a random axis."""
    for name in raw:
        if name not in _RANDOM_KEYS:
            raise UnknownNameError(f"key in the random values of axis {key!r}", name, _RANDOM_KEYS)
    kinds = [k for k in ("normal", "uniform") if k in raw]
    if len(kinds) != 1:
        raise ScenarioError(
            f"axis {key!r}: random values need exactly one of normal = [mean, sigma] or "
            "uniform = [low, high]"
        )
    samples = raw.get("samples")
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise ScenarioError(
            f"axis {key!r}: samples must be an integer >= 1, got {excerpt(samples)}"
        )
    if samples > MAX_SAMPLES:
        raise InputLimitError(f"axis {key!r} samples", samples, 1, MAX_SAMPLES)
    seed = raw.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ScenarioError(f"axis {key!r}: seed must be an integer >= 0, got {excerpt(seed)}")
    a, b = _pair(raw[kinds[0]], kinds[0], key)
    if kinds[0] == "normal":
        if b < 0.0:
            raise ScenarioError(f"axis {key!r}: normal sigma must be >= 0, got {b}")
        return (lambda rng: rng.normal(a, b)), samples
    if not a <= b:
        raise ScenarioError(f"axis {key!r}: uniform needs low <= high, got [{a}, {b}]")
    return (lambda rng: rng.uniform(a, b)), samples


def is_random(raw: Any) -> bool:
    """Whether an axis's ``values`` asks for random draws."""
    return isinstance(raw, Mapping) and ("normal" in raw or "uniform" in raw)


def random_values(
    tables: Sequence[tuple[str, Mapping[str, Any], tuple[str, str] | None]],
    urdf_text: str | None,
) -> list[tuple[float, ...]]:
    """Draw the random axes together: one tuple of values per axis, in ``tables`` order.

    Args:
        tables: per random axis its key, its ``values`` table and its inertial key (or None).
        urdf_text: the robot's URDF, to keep inertial draws physical (None: no inertial axis).

    Raises:
        ScenarioError: bad tables, unequal ``samples``, or no physical draw within the budget.
    """
    functions = [_draw_function(raw, key) for key, raw, _ in tables]
    counts = {samples for _, samples in functions}
    if len(counts) != 1:
        raise ScenarioError(
            "the random axes are drawn together: give them the same samples (got "
            + ", ".join(f"{key} {n}" for (key, _, _), (_, n) in zip(tables, functions, strict=True))
            + ")"
        )
    samples = counts.pop()
    generators = [np.random.default_rng(int(raw.get("seed", 0))) for _, raw, _ in tables]
    inertial = [key for _, _, key in tables]
    draws: list[tuple[float, ...]] = []
    attempts = 0
    while len(draws) < samples:
        attempts += 1
        if attempts > REDRAWS * samples:
            raise ScenarioError(
                f"only {len(draws)} of {samples} draws give physical bodies in "
                f"{REDRAWS * samples} attempts; narrow the distributions"
            )
        draw = tuple(float(f(g)) for (f, _), g in zip(functions, generators, strict=True))
        changes = inertial_changes(inertial, draw)
        if changes and urdf_text is not None:
            try:
                with_inertials(urdf_text, changes)
            except InputError:
                continue  # not physical: draw again
        draws.append(draw)
    return [tuple(d[i] for d in draws) for i in range(len(tables))]


def plan_source(name: str, folder: Path) -> tuple[Path, dict[str, Any], str]:
    """A plan file to replay (relative to the sweep file): its path, no tables, its URDF.

    The plan is verified first, as ``show`` and ``correct`` verify theirs: a replay of a path
    its own checks refuse would report on a motion no plan makes.

    Raises:
        PlanFileError: the file cannot be read, disagrees with its recomputation or fails a
            check.
    """
    from ..plans.robot_copy import plan_robot
    from ..verify.checks import require_verified

    path = (folder / name).expanduser().resolve()
    plan = load_plan_file(path)
    require_verified(plan, f"plan {name}", f"freefloat verify {name} shows the checks")
    return path, {}, robot_text(plan_robot(plan))


def scenario_urdf(base: Mapping[str, Any], path: Path) -> str:
    """The URDF text of the base scenario's robot (for inertial axes), written or not yet."""
    scenario = Scenario.from_dict(base, relative_to=path.parent, source=path)
    return robot_text(scenario.robot)  # the text it was loaded from, inline or read


def check_inertial_value(urdf: str, key: str, inertial: tuple[str, str], value: Any) -> None:
    """Refuse an inertial axis value that leaves its body unphysical (or names no link)."""
    link, parameter = inertial
    try:
        with_inertials(urdf, {link: {parameter: float(value)}})
    except FreeFloatError as exc:
        raise ScenarioError(f"axis {key!r} = {value!r}: {exc}") from None
