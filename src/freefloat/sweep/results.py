"""A sweep's results file: one CSV row per job, written as jobs finish, read back to resume.

``index``, one column per axis (the axis key), then the columns of the row class
(:class:`~freefloat.sweep.jobs.SweepRow` for plans, :class:`~freefloat.sweep.replay.ReplayRow`
for replays), then ``inputs``: a digest of what every job reads besides its axis values
(:func:`inputs_digest`). Floats round-trip exactly. A file read back is checked row by row:
the sweep's columns, axis values and inputs (a row of an edited base scenario or robot is not
resumed as one of this sweep), numbers that are numbers, statuses the rows have, and a
planned row whose attitude error a plan can have (an edited file is refused, naming the line).
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import os
from collections.abc import Sequence
from dataclasses import fields
from pathlib import Path
from typing import Any

from ..errors import ScenarioError
from ..files import atomic_write_text
from ..problem.scenario import Scenario
from ..robust.inertial import robot_text
from ..verify.plan_checks import TOLERANCES
from .jobs import SweepRow
from .replay import ReplayRow
from .spec import Job, SweepSpec

__all__ = [
    "PLANNED_ATTITUDE_RAD",
    "Appender",
    "Row",
    "inputs_digest",
    "read_rows",
    "row_class",
    "write_rows",
]

Row = SweepRow | ReplayRow


def _cell(value: Any) -> str:
    """CSV text of a value: floats round-trip exactly (shortest repr); None is empty."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def row_class(spec: SweepSpec) -> type[SweepRow] | type[ReplayRow]:
    """The rows a sweep gives: :class:`SweepRow` (plans) or :class:`ReplayRow` (replays)."""
    return ReplayRow if spec.replay else SweepRow


#: The last column: the digest of the sweep's inputs (:func:`inputs_digest`).
INPUTS = "inputs"


def _header(spec: SweepSpec) -> list[str]:
    return ["index", *spec.keys, *row_class(spec).result_columns(), INPUTS]


def inputs_digest(spec: SweepSpec) -> str:
    """16 hex digits of what every job reads besides its axis values.

    The base scenario's tables, its robot's URDF (the text it is loaded from, inline or
    read) and SRDF (given, beside the URDF, or a composed servicer's), the samples; for a
    replay sweep, the plan file.
    """
    digest = hashlib.sha256()
    tables = json.dumps([spec.base, spec.samples, spec.replay], sort_keys=True, default=str)
    digest.update(tables.encode())
    if spec.replay:
        digest.update(spec.scenario_path.read_bytes())
        return digest.hexdigest()[:16]
    scenario = Scenario.from_dict(
        spec.base, relative_to=spec.scenario_path.parent, source=spec.scenario_path
    )
    digest.update(robot_text(scenario.robot).encode())
    srdf = scenario.safety.srdf
    if scenario.srdf_text is not None:
        digest.update(scenario.srdf_text.encode())
    elif srdf is not None and srdf.expanduser().is_file():
        digest.update(srdf.expanduser().read_bytes())
    return digest.hexdigest()[:16]


def _line(cells: Sequence[str]) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(cells)
    return buffer.getvalue()


def _row_cells(row: Row, inputs: str) -> list[str]:
    return [
        str(row.index),
        *(_cell(v) for v in row.values),
        *(_cell(getattr(row, name)) for name in row.result_columns()),
        inputs,
    ]


def _parse_row(cells: Sequence[str], job: Job, kind: type[Row], where: str) -> Row:
    """One row of a results file read back, each cell as the runner writes it.

    Raises:
        ScenarioError: a number that is not one (or not finite), a status the rows never
            have, or a planned row whose attitude error no plan has (the file was edited).
    """
    values: dict[str, Any] = {}
    for f, text in zip(fields(kind)[2:], cells, strict=True):
        if f.name in ("status", "message", "objective"):
            values[f.name] = text
            continue
        try:
            values[f.name] = float(text) if text else None
        except ValueError:
            values[f.name] = math.nan
        if values[f.name] is not None and not math.isfinite(values[f.name]):
            raise ScenarioError(f"{where}: {f.name} {text!r} is not a finite number{_EDITED}")
    row = kind(index=job.index, values=job.values, **values)
    if row.status not in kind.statuses:
        raise ScenarioError(
            f"{where}: status {row.status!r} is none of {', '.join(kind.statuses)}{_EDITED}"
        )
    error = row.attitude_error_rad
    if row.status == "planned" and (error is None or error > PLANNED_ATTITUDE_RAD):
        raise ScenarioError(
            f"{where}: a planned row whose attitude error {_text_of(error)} rad exceeds the "
            f"{PLANNED_ATTITUDE_RAD:g} rad every plan keeps{_EDITED}"
        )
    return row


#: The largest attitude error (rad) of a planned row: what verification holds a plan to.
PLANNED_ATTITUDE_RAD = TOLERANCES["attitude_independent_rad"]
_EDITED = " (an edited file?); choose another output file or delete it"


def _text_of(value: float | None) -> str:
    """A row's number as the file has it, or "none"."""
    return "none" if value is None else repr(value)


def read_rows(spec: SweepSpec, output: str | Path, inputs: str | None = None) -> dict[int, Row]:
    """The rows of an existing output file, by job index (resume); empty if there is none.

    ``inputs``: the sweep's :func:`inputs_digest`, if the caller has it (it loads the robot).

    Raises:
        ScenarioError: the file holds another sweep (other columns or job values).
    """
    path = Path(output)
    if not path.is_file():
        return {}
    text = path.read_text(encoding="utf-8-sig")  # a spreadsheet may have added a BOM
    if text and not text.endswith("\n"):  # a torn last line of an interrupted run
        text = text[: text.rfind("\n") + 1]
    lines = list(csv.reader(io.StringIO(text)))
    if not lines:
        return {}
    header = _header(spec)
    if lines[0] == header[:-1]:  # written before the inputs column: nothing to compare
        raise ScenarioError(
            f"{path} was written by an older freefloat, without the digest of the scenario and "
            "robot its rows came from, and cannot be resumed safely; choose another output "
            "file or delete it"
        )
    if lines[0] != header:
        raise ScenarioError(
            f"{path} holds another sweep (columns {', '.join(lines[0][:6])}...); choose another "
            "output file or delete it"
        )
    jobs = spec.jobs()
    rows: dict[int, Row] = {}
    n_axes = len(spec.axes)
    inputs = inputs or inputs_digest(spec)
    for number, cells in enumerate(lines[1:], start=2):
        if len(cells) != len(header) or not cells[0].isdigit() or int(cells[0]) >= len(jobs):
            raise ScenarioError(f"{path} line {number} is not a row of this sweep")
        job = jobs[int(cells[0])]
        if cells[1 : 1 + n_axes] != [_cell(v) for v in job.values]:
            raise ScenarioError(
                f"{path} line {number} has other axis values than job {job.index}; choose "
                "another output file or delete it"
            )
        if cells[-1] != inputs:
            raise ScenarioError(
                f"{path} line {number} came from another base scenario or robot (inputs "
                f"{cells[-1]}, now {inputs}: edited since?); choose another output file or "
                "delete it"
            )
        where = f"{path} line {number}"
        rows[job.index] = _parse_row(cells[1 + n_axes : -1], job, row_class(spec), where)
    return rows


def write_rows(
    spec: SweepSpec, output: str | Path, rows: Sequence[Row], inputs: str | None = None
) -> Path:
    """Write the whole output file atomically, rows sorted by index (``inputs``: as read_rows)."""
    inputs = inputs or inputs_digest(spec)
    text = _line(_header(spec)) + "".join(
        _line(_row_cells(r, inputs)) for r in sorted(rows, key=lambda r: r.index)
    )
    return atomic_write_text(output, text)


class Appender:
    """Appends whole rows to the output file (one ``write`` per row, ``O_APPEND``)."""

    def __init__(
        self, spec: SweepSpec, path: Path, rows: dict[int, Row], inputs: str | None = None
    ) -> None:
        self._inputs = inputs or inputs_digest(spec)  # before the file is opened
        path.parent.mkdir(parents=True, exist_ok=True)
        # a torn last line of an earlier run is dropped before appending
        write_rows(spec, path, list(rows.values()) if path.is_file() else [], self._inputs)
        self._fd = os.open(path, os.O_WRONLY | os.O_APPEND)

    def add(self, row: Row) -> None:
        """Append ``row`` as one whole line (one write)."""
        os.write(self._fd, _line(_row_cells(row, self._inputs)).encode("utf-8"))

    def close(self) -> None:
        """Close the file."""
        os.close(self._fd)
