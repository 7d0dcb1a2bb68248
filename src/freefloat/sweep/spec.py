"""Sweep files: a base scenario and the axes to vary, read from TOML.

A sweep speaks the scenario's units (degrees for angles, metres, kilograms, seconds)::

    scenario = "worked_example.toml"   # relative to this file, or a shipped scenario name
    samples = 201                      # optional: samples per plan (>= 2)
    [[axis]]
    key = "goal.base_zyx_deg.0"        # dotted key into the scenario's TOML tables;
                                       # list positions as numbers
    values = { start = -55.0, stop = 25.0, num = 81 }   # evenly spaced, both ends included
    [[axis]]
    key = "goal.joints.q2"
    values = [60.0, 90.0, 120.0]       # or explicit values

Every combination of the axes (their product, the last axis fastest) is one job. Each key
must name a value present in the base scenario (a number, string or boolean: joint angles,
attitudes, duration, and the parameters of an inline ``[robot]`` servicer such as
``robot.base_mass`` or ``robot.mount.0``); every value of every axis is checked by building
the scenario it gives before any job runs.

Mass properties (docs/robustness.md): ``robot.links.<link>.mass`` (``.com.0``,
``.inertia.ixx``...) changes a URDF link's inertial values, and ``values`` may be random draws
(:mod:`freefloat.sweep.draws`). With ``plan = "FILE.plan.json"`` instead of ``scenario``, a
sweep replays that plan's fixed joint paths in each changed model instead of planning (its
axes are inertial ones, ``payload.*`` naming the captured payload's link) and reports where
the spacecraft ends (:mod:`freefloat.sweep.replay`).
"""

from __future__ import annotations

import copy
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FreeFloatError, InputLimitError, ScenarioError, UnknownNameError, excerpt
from ..problem.limits import check_samples, finite_number
from ..problem.scenario import Scenario, shipped_scenario, shipped_scenario_names
from ..problem.scenario_tables import read_toml
from .draws import (
    Changes,
    check_inertial_value,
    inertial_changes,
    inertial_key,
    is_random,
    plan_source,
    random_values,
    scenario_urdf,
)
from .keys import leaf, put, split_key

__all__ = ["Axis", "Job", "SweepSpec", "Value"]

#: A value an axis can take: what the scenario's TOML holds at that key.
Value = float | int | str | bool

_SWEEP_KEYS = ("scenario", "plan", "samples", "axis")
_AXIS_KEYS = ("key", "values")
_RANGE_KEYS = ("start", "stop", "num")
#: Most jobs of one sweep (the product of the axis lengths): a sweep is validated value by
#: value before it runs, and 100000 worked-example plans take about three hours on one core.
MAX_SWEEP_JOBS = 100_000


@dataclass(frozen=True)
class Axis:
    """One varied scenario value.

    Attributes:
        key: the dotted key as written, e.g. ``"goal.base_zyx_deg.0"``.
        path: the key split into table names and list positions.
        values: the values it takes, in the scenario file's units (degrees for angles).
        inertial: ``(link, parameter)`` for an axis of a link's inertial values, else None.
        random: whether the values are random draws (drawn together with the other random
            axes: one job per draw, not per combination).
    """

    key: str
    path: tuple[str | int, ...]
    values: tuple[Value, ...]
    inertial: tuple[str, str] | None = None
    random: bool = False


@dataclass(frozen=True)
class Job:
    """One combination of axis values: the scenario tables to plan.

    Attributes:
        index: position in the product of the axes (0-based, last axis fastest).
        values: one value per axis, in the scenario file's units.
        data: the scenario's TOML tables with the values put in.
        relative_to: folder that relative paths in ``data`` are resolved against.
        source: the base scenario file (the plan file when replaying).
        samples: samples per plan.
        changes: new inertial values of links, ``{link: {parameter: value}}``.
        replay: replay the plan ``source`` instead of planning ``data``.
    """

    index: int
    values: tuple[Value, ...]
    data: Mapping[str, Any]
    relative_to: Path
    source: Path
    samples: int
    changes: Changes = field(default_factory=dict)
    replay: bool = False


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: base scenario tables and axes.

    Attributes:
        base: the base scenario's TOML tables (degrees, as in the file).
        scenario_path: the base scenario file.
        axes: the varied values; their product is the set of jobs.
        samples: samples per plan (>= 2).
        source: the sweep file, if any.
        replay: ``scenario_path`` is a plan file to replay in each changed model.
    """

    base: Mapping[str, Any]
    scenario_path: Path
    axes: tuple[Axis, ...]
    samples: int = 201
    source: Path | None = None
    replay: bool = False

    @classmethod
    def from_toml(cls, path: str | Path) -> SweepSpec:
        """Read and validate a sweep file (see the module docstring).

        Raises:
            ScenarioError: unreadable file, bad TOML, bad values, a base scenario that fails.
            UnknownNameError: an unknown key of the sweep file or of the scenario (names the
                valid ones).
        """
        path = Path(path).expanduser().resolve()
        data = read_toml(path, "sweep")
        try:
            return cls.from_dict(data, relative_to=path.parent, source=path)
        except FreeFloatError as exc:
            exc.naming(path)  # the sweep file first, unless the message names it already
            raise

    @classmethod
    def from_dict(
        cls, data: Mapping[str, Any], relative_to: Path | None = None, source: Path | None = None
    ) -> SweepSpec:
        """Build and validate a sweep from its parsed TOML tables.

        Every axis key is resolved against the base scenario and every value of every axis
        is put into a copy of it and parsed as a scenario, so that bad input is refused
        here, before any job runs.
        """
        for key in data:
            if key not in _SWEEP_KEYS:
                raise UnknownNameError("key in the sweep file", key, _SWEEP_KEYS)
        replay = "plan" in data
        name = data.get("plan" if replay else "scenario")
        if not isinstance(name, str) or ("plan" in data and "scenario" in data):
            raise ScenarioError(
                'the sweep file needs scenario = "FILE.toml" (relative to the sweep file, or '
                'a shipped scenario name), or plan = "FILE.plan.json" to replay a plan'
            )
        folder = (relative_to or Path.cwd()).resolve()
        if replay:
            scenario_path, base, urdf = plan_source(name, folder)
        else:
            scenario_path = _scenario_path(name, folder)
            if source is not None and scenario_path == Path(source).resolve():
                raise ScenarioError(
                    f"the sweep's scenario {name!r} is the sweep file itself; name the "
                    "scenario file the axes vary"
                )
            base = read_toml(scenario_path, "scenario")
            urdf = None
        samples = data.get("samples", 201)
        if isinstance(samples, bool) or not isinstance(samples, int) or samples < 2:
            raise ScenarioError(f"samples must be an integer >= 2, got {excerpt(samples)}")
        check_samples(samples)
        tables = data.get("axis")
        if not isinstance(tables, list) or not tables:
            raise ScenarioError(
                "the sweep file needs at least one [[axis]] table with key and values"
            )
        axes = tuple(_axis(table, i, base, replay) for i, table in enumerate(tables))
        if any(axis.inertial is not None for axis in axes) and urdf is None:
            urdf = scenario_urdf(base, scenario_path)
        axes = _drawn(axes, tables, urdf)
        spec = cls(base, scenario_path, axes, samples, source, replay)
        if spec.size > MAX_SWEEP_JOBS:
            raise InputLimitError("jobs of the sweep", spec.size, 1, MAX_SWEEP_JOBS)
        seen: set[tuple[str | int, ...]] = set()
        for axis in axes:
            if axis.path in seen:
                raise ScenarioError(f"axis key {axis.key!r} is given twice")
            seen.add(axis.path)
        spec._check_values(urdf)
        return spec

    @property
    def keys(self) -> tuple[str, ...]:
        """The axis keys, in order."""
        return tuple(axis.key for axis in self.axes)

    @property
    def size(self) -> int:
        """Number of jobs (the grid axes' product, times the draws of the random axes).

        Counted, not listed: 1e15 combinations were listed before the job limit was met.
        """
        draws = max((len(a.values) for a in self.axes if a.random), default=1)
        return math.prod(len(a.values) for a in self.axes if not a.random) * draws

    def _combinations(self) -> list[tuple[Value, ...]]:
        """Axis values of every job: grid axes combined (last fastest), random ones drawn."""
        grid: list[Sequence[Value]] = [a.values if not a.random else (0,) for a in self.axes]
        draws = max((len(a.values) for a in self.axes if a.random), default=1)
        out = []
        for *values, draw in itertools.product(*grid, range(draws)):
            pairs = zip(self.axes, values, strict=True)
            out.append(tuple(a.values[int(draw)] if a.random else v for a, v in pairs))
        return out

    def jobs(self) -> list[Job]:
        """Every job, in index order (last axis fastest, the draws of random axes last)."""
        return [self.job(index, values) for index, values in enumerate(self._combinations())]

    def job(self, index: int, values: Sequence[Value]) -> Job:
        """The job that puts ``values`` (one per axis) into the base scenario."""
        data = copy.deepcopy(dict(self.base))
        for axis, value in zip(self.axes, values, strict=True):
            if axis.inertial is None:
                put(data, axis.path, value)
        return Job(
            index,
            tuple(values),
            data,
            self.scenario_path.parent,
            self.scenario_path,
            self.samples,
            changes=inertial_changes([a.inertial for a in self.axes], values),
            replay=self.replay,
        )

    def _check_values(self, urdf: str | None) -> None:
        """Parse the scenario for every value of every axis (others at their base value).

        Inertial values are put into the robot's URDF (``urdf``) and must be physical.
        """
        for axis in self.axes:
            for value in axis.values:
                if axis.inertial is not None:
                    assert urdf is not None
                    check_inertial_value(urdf, axis.key, axis.inertial, value)
                    continue
                data = copy.deepcopy(dict(self.base))
                put(data, axis.path, value)
                try:
                    Scenario.from_dict(
                        data, relative_to=self.scenario_path.parent, source=self.scenario_path
                    )
                except FreeFloatError as exc:
                    raise ScenarioError(f"axis {axis.key!r} = {value!r}: {exc}") from None


def _drawn(axes: tuple[Axis, ...], tables: list[Any], urdf: str | None) -> tuple[Axis, ...]:
    """The axes with the random ones' values drawn (together, physical bodies only)."""
    chosen = [i for i, axis in enumerate(axes) if axis.random]
    if not chosen:
        return axes
    drawn = random_values(
        [(axes[i].key, tables[i]["values"], axes[i].inertial) for i in chosen], urdf
    )
    out = list(axes)
    for i, values in zip(chosen, drawn, strict=True):
        out[i] = replace(axes[i], values=values)
    return tuple(out)


def _scenario_path(name: str, folder: Path) -> Path:
    """A scenario file relative to the sweep file, else a shipped scenario by name."""
    candidate = (folder / name).expanduser()
    if candidate.is_file():
        return candidate.resolve()
    shipped = shipped_scenario(name)
    if shipped is not None:
        return shipped
    raise ScenarioError(
        f"scenario {name!r} is neither a file next to the sweep file ({candidate}) nor a shipped "
        f"scenario ({', '.join(shipped_scenario_names())})"
    )


def _axis(table: Any, position: int, base: Mapping[str, Any], replay: bool = False) -> Axis:
    where = f"[[axis]] {position + 1}"
    if not isinstance(table, Mapping):
        raise ScenarioError(f"{where} must be a table with key and values")
    for name in table:
        if name not in _AXIS_KEYS:
            raise UnknownNameError(f"key in {where}", name, _AXIS_KEYS)
    key = table.get("key")
    if not isinstance(key, str):
        raise ScenarioError(f'{where} needs key = "dotted.key" (e.g. "goal.joints.q2")')
    inertial = inertial_key(key, replay)
    if inertial is None and replay:
        raise ScenarioError(
            f"axis {key!r}: a plan replay sweeps inertial keys (robot.links.LINK.mass, "
            "robot.links.LINK.com.0, robot.links.LINK.inertia.ixx, payload.mass ...)"
        )
    path = (key,) if inertial is not None else split_key(key, base)
    current = 0.0 if inertial is not None else leaf(base, path)
    if "values" not in table:
        raise ScenarioError(f"axis {key!r} needs values = [...] or {{ start, stop, num }}")
    raw = table["values"]
    values: tuple[Value, ...]
    if is_random(raw):
        if not isinstance(current, (int, float)) or isinstance(current, bool):
            raise ScenarioError(f"axis {key!r}: random values need a number at that key")
        return Axis(key, path, (), inertial, random=True)  # drawn with the other random axes
    if isinstance(raw, Mapping):
        values = _range(raw, key)
    elif isinstance(raw, list) and raw:
        values = tuple(raw)
    else:
        raise ScenarioError(
            f"axis {key!r} values must be a non-empty list or {{ start, stop, num }}, got "
            f"{excerpt(raw)}"
        )
    numeric = isinstance(current, (int, float)) and not isinstance(current, bool)
    for value in values:
        if numeric:
            ok = isinstance(value, (int, float)) and not isinstance(value, bool)
            if ok and not finite_number(value):
                raise ScenarioError(f"axis {key!r} values must be finite, got {excerpt(value)}")
            if isinstance(current, int) and isinstance(value, float):
                ok = False
        else:
            ok = type(value) is type(current)
        if not ok:
            raise ScenarioError(
                f"axis {key!r} values must be of the scenario's type ({type(current).__name__}, "
                f"like {excerpt(current)}), got {excerpt(value)}"
            )
    if len(set(values)) != len(values):
        raise ScenarioError(f"axis {key!r} repeats a value")
    if inertial is not None:
        values = tuple(float(v) for v in values)
    return Axis(key, path, values, inertial)


def _range(raw: Mapping[str, Any], key: str) -> tuple[float, ...]:
    for name in raw:
        if name not in _RANGE_KEYS:
            raise UnknownNameError(f"key in the range of axis {key!r}", name, _RANGE_KEYS)
    missing = [name for name in _RANGE_KEYS if name not in raw]
    if missing:
        raise ScenarioError(f"axis {key!r} range needs start, stop and num (missing {missing})")
    start, stop, num = raw["start"], raw["stop"], raw["num"]
    for name, value in (("start", start), ("stop", stop)):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ScenarioError(f"axis {key!r} range {name} must be a number, got {excerpt(value)}")
        if not finite_number(value):
            raise ScenarioError(f"axis {key!r} range {name} must be finite, got {excerpt(value)}")
    if isinstance(num, bool) or not isinstance(num, int) or num < 1:
        raise ScenarioError(f"axis {key!r} range num must be an integer >= 1, got {excerpt(num)}")
    if num > MAX_SWEEP_JOBS:
        raise InputLimitError(f"axis {key!r} range num", num, 1, MAX_SWEEP_JOBS)
    if num == 1:
        return (float(start),)
    with np.errstate(over="ignore", invalid="ignore"):
        values = np.linspace(float(start), float(stop), num)
    if not np.all(np.isfinite(values)):  # its step overflows the floats
        raise ScenarioError(
            f"axis {key!r} range from {start:g} to {stop:g} overflows the floats; give a "
            "narrower range"
        )
    return tuple(float(v) for v in values)
