"""Seeded fuzzing of plan files (issue 14): ``freefloat verify`` either accepts a harmless change
or refuses in one line, exit 2; never a traceback, a warning, a wrong accept or a long wait.

Each example mutates one place of the worked example's plan (planned once for the module): a
number nudged or replaced (NaN, infinities, huge, tiny, another type), a key deleted, a list
truncated, extended or reordered. An accepted file must equal the original within the
tolerances of :mod:`freefloat.verify.recompute`, except in what verify cannot recompute: the
solver's history, the checks' detail text and the safety record (input), and optional
sections that may be absent.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import time
import warnings
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from freefloat.cli import main

Path_ = tuple[str | int, ...]

#: What verify cannot recompute (the solver's history, descriptive text, the safety input).
HISTORY = {
    ("solver", key)
    for key in (
        "method",
        "iterations",
        "evaluations",
        "wall_time_s",
        "solve_time_s",
        "sample_time_s",
        "verify_time_s",
        "strategy",
        "tried",
        "full_turns",
    )
} | {("objective", "levels")}  # the search's history: not recomputable from the file
#: Lists files written before they were recorded lack: empty is as good as absent.
OPTIONAL = {("robot", "joint_kinds"), ("samples", "tau"), ("samples", "base_angular_velocity")}
SPECIAL = [
    math.nan,
    math.inf,
    -math.inf,
    1e308,
    -1e308,
    1e-300,
    0.0,
    10**400,
    "x",
    None,
    True,
    [],
    {},
]
NUDGES = [1e-15, 1e-12, 1e-9, 1e-6, 1e-3, 0.1, 1.0]


def _paths(value: Any, prefix: Path_ = ()) -> list[Path_]:
    out = [prefix] if prefix else []
    if isinstance(value, dict):
        for key, item in value.items():
            out += _paths(item, (*prefix, key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            out += _paths(item, (*prefix, index))
    return out


def _get(doc: Any, path: Path_) -> Any:
    for part in path:
        doc = doc[part]
    return doc


def _numbers(value: Any, prefix: Path_ = ()) -> dict[Path_, Any]:
    if isinstance(value, dict):
        out: dict[Path_, Any] = {}
        for key, item in value.items():
            out.update(_numbers(item, (*prefix, key)))
        return out
    if isinstance(value, list):
        out = {}
        for index, item in enumerate(value):
            out.update(_numbers(item, (*prefix, index)))
        return out if value else {prefix: "[]"}
    return {prefix: value}


def _ignored(path: Path_) -> bool:
    return (
        path[:2] in HISTORY
        or path[:1] == ("safety",)
        or (path[:2] == ("verification", "checks") and path[-1:] == ("detail",))
        or path == ("format",)
        # a plan verifies from the URDF copy it carries: the path only says where the file
        # was (a file found there must have the copy's SHA-256, tested in test_plan_urdf_copy)
        or path == ("robot", "urdf")
        # a minimum-norm plan's start value is the norm of the search's first root, a record of
        # how the plan was found: verify only holds it to be at least the value (known gap)
        or path == ("objective", "start_value")
    )


def _slack(original: dict, path: Path_, scales: dict[Path_, float]) -> float:
    """How far an accepted number may be from the original (tolerances of the recomputation)."""
    if path[:2] == ("verification", "checks") and len(path) == 4:
        check = original["verification"]["checks"][path[2]]
        if path[3] in ("value", "error_estimate"):
            return 1e-3 * check["tolerance"] + 3.0 * check.get("error_estimate", 0.0)
        return 1e-9 * abs(check["tolerance"])
    if path[:1] == ("solver",):
        return 3e-9  # residuals, integration error, path lengths (rad)
    if path[:2] == ("feasibility", "yaw_change_bounds_deg"):
        return 2e-6
    if path[:2] not in scales:
        field = _get(original, path[:2])
        scales[path[:2]] = max([1.0, *(abs(v) for v in _numbers(field).values() if _is_number(v))])
    return 1e-8 * scales[path[:2]]


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _in_name_order(doc: dict) -> dict:
    """The plan with its constraint records in name order: a set, whose order means nothing
    (verify rebuilds each by name; duplicates are refused)."""
    records = doc.get("constraints")
    if not isinstance(records, list) or not all(isinstance(r, dict) for r in records):
        return doc
    return {**doc, "constraints": sorted(records, key=lambda r: str(r.get("name")))}


def _harmless(original: dict, mutated: dict) -> list[str]:
    """Differences an accepted file must not have (empty: harmless)."""
    mine, theirs = _numbers(_in_name_order(original)), _numbers(_in_name_order(mutated))
    problems: list[str] = []
    scales: dict[Path_, float] = {}
    for path, value in theirs.items():
        if _ignored(path) or (value == "[]" and path in OPTIONAL):
            continue
        if path not in mine:
            problems.append(f"{path}: added {value!r}")
            continue
        before = mine[path]
        if _is_number(before) and _is_number(value):
            if not abs(float(value) - float(before)) <= _slack(original, path, scales):
                problems.append(f"{path}: {before!r} -> {value!r}")
        elif before != value:
            problems.append(f"{path}: {before!r} -> {value!r}")
    return problems


@pytest.fixture(scope="module")
def original(worked_plan) -> dict:
    return json.loads(worked_plan.to_json())


@pytest.fixture(scope="module")
def places(original) -> dict[Path_, list[Path_]]:
    """Every place in the plan, grouped by section (so the long sample lists do not dominate)."""
    groups: dict[Path_, list[Path_]] = {}
    for path in _paths(original):
        groups.setdefault(path[:2], []).append(path)
    return groups


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


def _mutate(data: st.DataObject, doc: dict, places: dict[Path_, list[Path_]]) -> str:
    group = data.draw(st.sampled_from(sorted(places, key=repr)), label="section")
    path = data.draw(st.sampled_from(places[group]), label="place")
    parent, key = _get(doc, path[:-1]), path[-1]
    value = parent[key]
    kinds = ["special"]
    if _is_number(value):
        kinds += ["scale", "shift"]
    if isinstance(parent, dict):
        kinds.append("delete")
    if isinstance(value, list) and value:
        kinds += ["truncate", "extend", "reverse"]
    kind = data.draw(st.sampled_from(kinds), label="kind")
    if kind == "special":
        parent[key] = data.draw(st.sampled_from(SPECIAL), label="value")
    elif kind == "scale":
        nudge = data.draw(st.sampled_from(NUDGES), label="nudge")
        parent[key] = value * (1.0 + data.draw(st.sampled_from([nudge, -nudge]), label="sign"))
    elif kind == "shift":
        parent[key] = value + data.draw(st.sampled_from(NUDGES + [-x for x in NUDGES]))
    elif kind == "delete":
        del parent[key]
    elif kind == "truncate":
        parent[key] = value[: data.draw(st.integers(0, len(value) - 1), label="keep")]
    elif kind == "extend":
        parent[key] = [*value, value[-1]]
    else:
        parent[key] = value[::-1]
    return f"{kind} at {path}"


@settings(
    max_examples=300,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_verify_accepts_only_harmless_changes_and_refuses_in_one_line(
    original, places, folder, data
):
    doc = json.loads(json.dumps(original))
    what = _mutate(data, doc, places)
    path = folder / "mutated.json"
    path.write_text(json.dumps(doc))
    out, err = io.StringIO(), io.StringIO()
    clock = time.perf_counter()
    with (
        warnings.catch_warnings(record=True) as caught,
        contextlib.redirect_stdout(out),
        contextlib.redirect_stderr(err),
    ):
        warnings.simplefilter("always")
        code = main(["verify", str(path)])
    seconds = time.perf_counter() - clock
    lines = err.getvalue().splitlines()
    event(f"exit {code}")
    assert isinstance(code, int), what
    assert seconds < 5.0, f"{what}: {seconds:.1f} s"
    assert not caught, f"{what}: warnings {[str(w.message) for w in caught]}"
    if code == 0:
        assert lines == [], f"{what}: {lines}"
        assert _harmless(original, doc) == [], f"{what}: accepted a harmful change"
    else:
        assert code == 2, f"{what}: exit {code}, {lines}"
        assert len(lines) == 1 and lines[0].startswith("freefloat: error: "), f"{what}: {lines}"
        assert len(lines[0]) < 500, f"{what}: {lines[0][:200]}..."


def test_a_list_too_long_is_refused_before_the_schema_walks_it(original, folder, monkeypatch):
    """95 million entries in samples.t (a 181 MiB file, under the 200 MiB limit) kept verify
    busy for minutes in the schema's walk over every entry: a list longer than a plan's
    1 000 000 samples is refused before it, naming the field (the schema never called)."""
    import freefloat.plans.schema as schema_module
    from freefloat.errors import PlanFileError
    from freefloat.plans.limits import MAX_SAMPLES
    from freefloat.plans.schema import load_plan_file

    def walked(*args, **kwargs):  # pragma: no cover - must not be reached
        raise AssertionError("the schema walked the long list")

    doc = json.loads(json.dumps(original))
    doc["samples"]["t"] = doc["samples"]["t"] + [0.0] * MAX_SAMPLES
    path = folder / "long.json"
    path.write_text(json.dumps(doc))
    monkeypatch.setattr(schema_module, "schema_errors", walked)
    with pytest.raises(PlanFileError) as info:
        load_plan_file(path)
    count = len(doc["samples"]["t"])
    assert str(info.value) == (
        f"{path}: samples.t has {count} entries, more than the 1000000 a plan file may have"
    )
