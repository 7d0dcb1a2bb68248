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
"""

from __future__ import annotations

import copy
import itertools
import math
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FreeFloatError, InputLimitError, ScenarioError, UnknownNameError, excerpt
from ..problem.limits import check_samples
from ..problem.scenario import Scenario, read_toml
from ..robot.model import robots_dir

if sys.version_info >= (3, 11):
    pass
else:  # pragma: no cover
    pass

__all__ = ["Axis", "Job", "SweepSpec", "Value"]

#: A value an axis can take: what the scenario's TOML holds at that key.
Value = float | int | str | bool

_SWEEP_KEYS = ("scenario", "samples", "axis")
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
    """

    key: str
    path: tuple[str | int, ...]
    values: tuple[Value, ...]


@dataclass(frozen=True)
class Job:
    """One combination of axis values: the scenario tables to plan.

    Attributes:
        index: position in the product of the axes (0-based, last axis fastest).
        values: one value per axis, in the scenario file's units.
        data: the scenario's TOML tables with the values put in.
        relative_to: folder that relative paths in ``data`` are resolved against.
        source: the base scenario file.
        samples: samples per plan.
    """

    index: int
    values: tuple[Value, ...]
    data: Mapping[str, Any]
    relative_to: Path
    source: Path
    samples: int


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: base scenario tables and axes.

    Attributes:
        base: the base scenario's TOML tables (degrees, as in the file).
        scenario_path: the base scenario file.
        axes: the varied values; their product is the set of jobs.
        samples: samples per plan (>= 2).
        source: the sweep file, if any.
    """

    base: Mapping[str, Any]
    scenario_path: Path
    axes: tuple[Axis, ...]
    samples: int = 201
    source: Path | None = None

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
            exc.args = (f"{path}: {exc}",)
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
        if not isinstance(data.get("scenario"), str):
            raise ScenarioError(
                'the sweep file needs scenario = "FILE.toml" (relative to the sweep file, or '
                "a shipped scenario name)"
            )
        folder = (relative_to or Path.cwd()).resolve()
        scenario_path = _scenario_path(data["scenario"], folder)
        base = read_toml(scenario_path, "scenario")
        samples = data.get("samples", 201)
        if isinstance(samples, bool) or not isinstance(samples, int) or samples < 2:
            raise ScenarioError(f"samples must be an integer >= 2, got {excerpt(samples)}")
        check_samples(samples)
        tables = data.get("axis")
        if not isinstance(tables, list) or not tables:
            raise ScenarioError(
                "the sweep file needs at least one [[axis]] table with key and values"
            )
        axes = tuple(_axis(table, i, base) for i, table in enumerate(tables))
        jobs = math.prod(len(axis.values) for axis in axes)
        if jobs > MAX_SWEEP_JOBS:
            raise InputLimitError("jobs of the sweep", jobs, 1, MAX_SWEEP_JOBS)
        seen: set[tuple[str | int, ...]] = set()
        for axis in axes:
            if axis.path in seen:
                raise ScenarioError(f"axis key {axis.key!r} is given twice")
            seen.add(axis.path)
        spec = cls(base, scenario_path, axes, samples, source)
        spec._check_values()
        return spec

    @property
    def keys(self) -> tuple[str, ...]:
        """The axis keys, in order."""
        return tuple(axis.key for axis in self.axes)

    @property
    def size(self) -> int:
        """Number of jobs (the product of the axis lengths)."""
        return math.prod(len(axis.values) for axis in self.axes)

    def jobs(self) -> list[Job]:
        """Every job, in index order (last axis fastest)."""
        return [
            self.job(index, values)
            for index, values in enumerate(itertools.product(*(a.values for a in self.axes)))
        ]

    def job(self, index: int, values: Sequence[Value]) -> Job:
        """The job that puts ``values`` (one per axis) into the base scenario."""
        data = copy.deepcopy(dict(self.base))
        for axis, value in zip(self.axes, values, strict=True):
            _put(data, axis.path, value)
        return Job(
            index,
            tuple(values),
            data,
            self.scenario_path.parent,
            self.scenario_path,
            self.samples,
        )

    def _check_values(self) -> None:
        """Parse the scenario for every value of every axis (others at their base value)."""
        for axis in self.axes:
            for value in axis.values:
                data = copy.deepcopy(dict(self.base))
                _put(data, axis.path, value)
                try:
                    Scenario.from_dict(
                        data, relative_to=self.scenario_path.parent, source=self.scenario_path
                    )
                except FreeFloatError as exc:
                    raise ScenarioError(f"axis {axis.key!r} = {value!r}: {exc}") from None


def _scenario_path(name: str, folder: Path) -> Path:
    """A scenario file relative to the sweep file, else a shipped scenario by name."""
    candidate = (folder / name).expanduser()
    if candidate.is_file():
        return candidate.resolve()
    shipped_dir = robots_dir() / "scenarios"
    for shipped in (shipped_dir / name, shipped_dir / f"{name}.toml"):
        if shipped.is_file():
            return shipped.resolve()
    names = sorted(p.name for p in shipped_dir.glob("*.toml"))
    raise ScenarioError(
        f"scenario {name!r} is neither a file next to the sweep file ({candidate}) nor a shipped "
        f"scenario ({', '.join(names)})"
    )


def _split(key: str, base: Mapping[str, Any]) -> tuple[str | int, ...]:
    """Resolve a dotted key against the base scenario; refuse it naming the valid keys."""
    if not key:
        raise ScenarioError('axis key must be a dotted key such as "goal.joints.q2"')
    path: list[str | int] = []
    node: Any = base
    for part in key.split("."):
        prefix = ".".join(str(p) for p in path)
        where = f"{prefix}." if prefix else ""
        if isinstance(node, Mapping):
            if part not in node:
                raise UnknownNameError("sweep key", key, [f"{where}{k}" for k in node])
            path.append(part)
            node = node[part]
        elif isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                raise UnknownNameError("sweep key", key, [f"{where}{i}" for i in range(len(node))])
            path.append(int(part))
            node = node[int(part)]
        else:
            raise ScenarioError(f"sweep key {key!r}: {prefix!r} is a value, not a table or list")
    if isinstance(node, (Mapping, list)):
        inner = node if isinstance(node, Mapping) else range(len(node))
        raise UnknownNameError(
            "sweep key (it names a table or list, not a value)",
            key,
            [f"{key}.{k}" for k in inner],
        )
    return tuple(path)


def _leaf(base: Mapping[str, Any], path: Sequence[str | int]) -> Any:
    node: Any = base
    for part in path:
        node = node[part]
    return node


def _put(data: Any, path: Sequence[str | int], value: Value) -> None:
    node = data
    for part in path[:-1]:
        node = node[part]
    node[path[-1]] = value


def _axis(table: Any, position: int, base: Mapping[str, Any]) -> Axis:
    where = f"[[axis]] {position + 1}"
    if not isinstance(table, Mapping):
        raise ScenarioError(f"{where} must be a table with key and values")
    for name in table:
        if name not in _AXIS_KEYS:
            raise UnknownNameError(f"key in {where}", name, _AXIS_KEYS)
    key = table.get("key")
    if not isinstance(key, str):
        raise ScenarioError(f'{where} needs key = "dotted.key" (e.g. "goal.joints.q2")')
    path = _split(key, base)
    current = _leaf(base, path)
    if "values" not in table:
        raise ScenarioError(f"axis {key!r} needs values = [...] or {{ start, stop, num }}")
    raw = table["values"]
    values: tuple[Value, ...]
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
            if isinstance(value, float) and not math.isfinite(value):
                raise ScenarioError(f"axis {key!r} values must be finite, got {value!r}")
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
    return Axis(key, path, values)


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
        if not math.isfinite(value):
            raise ScenarioError(f"axis {key!r} range {name} must be finite, got {value!r}")
    if isinstance(num, bool) or not isinstance(num, int) or num < 1:
        raise ScenarioError(f"axis {key!r} range num must be an integer >= 1, got {excerpt(num)}")
    if num > MAX_SWEEP_JOBS:
        raise InputLimitError(f"axis {key!r} range num", num, 1, MAX_SWEEP_JOBS)
    if num == 1:
        return (float(start),)
    return tuple(float(v) for v in np.linspace(float(start), float(stop), num))
