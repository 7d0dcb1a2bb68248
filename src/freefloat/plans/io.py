"""Reading plan files: JSON text to typed records.

:func:`read_plan_json` reads a file's JSON (size-checked, duplicate keys refused);
:func:`plan_fields` turns it into the keyword arguments of a
:class:`~freefloat.plans.format.Plan`, checking the format, the limits
(:mod:`freefloat.plans.limits`) and the URDF copy. The reverse, the plan's JSON-ready
dictionary in its format, is :meth:`Plan.to_dict <freefloat.plans.format.Plan.to_dict>`. Older
formats are read and written through :mod:`freefloat.plans.versions`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..errors import PlanFileError, excerpt
from ..files import other_kind_hint
from ..problem.limits import MAX_OBSTACLES
from ..problem.objectives.base import Level
from ..robot.collision import Obstacle
from ..robot.model import MAX_URDF_BYTES
from .guarantees import (
    Check,
    ConstraintRecord,
    ObjectiveReport,
    RobustnessReport,
    SafetyReport,
    Verification,
)
from .limits import MAX_PLAN_BYTES, check_plan_file_kind, check_plan_values
from .records import (
    BaseReport,
    Feasibility,
    PathQuality,
    Request,
    RobotRef,
    Samples,
    SolutionRecord,
    SolverReport,
    sha256_hex,
)
from .versions import (
    BASIS_FORMATS,
    FORMAT_1,
    READABLE_FORMATS,
    path_basis,
    promised_constraints,
    read_as,
    with_every_end_effector,
)

__all__ = ["plan_fields", "read_plan_json"]


def plan_fields(data: Any, where: str = "plan", folder: Path | None = None) -> dict[str, Any]:
    """The keyword arguments of a :class:`~freefloat.plans.format.Plan` from its file dictionary.

    Args:
        data: the parsed file.
        where: the file's name, for messages.
        folder: the plan file's folder: a relative ``robot.urdf`` (or ``safety.srdf``)
            path is read from there (default: the working directory).

    Raises:
        PlanFileError: another format, a bad or missing key, a limit broken, or a URDF
            copy whose SHA-256 is not the one stated.
    """
    if not isinstance(data, Mapping):
        raise PlanFileError(f"{where}: not a plan file (top level is not an object)")
    fmt = data.get("format")
    if fmt not in READABLE_FORMATS:
        said = "has no 'format' field" if fmt is None else f"format {excerpt(fmt)} is not supported"
        raise PlanFileError(
            f"{where}: plan {said}; this freefloat reads "
            + " and ".join(repr(f) for f in READABLE_FORMATS)
        )
    check_plan_values(data, where)
    basis = path_basis(data, fmt, where)
    try:
        # format 1: its untyped checks are dropped, and recomputed by verify
        verification = _verification(None if fmt == FORMAT_1 else data["verification"])
        solver = data["solver"]
        fields: dict[str, Any] = {
            "robot": _robot_ref(data["robot"], fmt, folder),
            "duration": float(data["duration"]),
            "coefficients": {k: list(v) for k, v in data["path"]["coefficients"].items()},
            "free_parameters": {k: list(v) for k, v in data["free_parameters"].items()},
            "base": BaseReport(**data["base"]),
            "feasibility": Feasibility(**data["feasibility"]),
            "samples": Samples(**data["samples"]),
            "solver": SolverReport(
                **{**solver, "solutions": [SolutionRecord(**s) for s in solver["solutions"]]}
            ),
            "request": Request(
                start_joints=list(data["request"]["start_joints"]),
                goal_joints=list(data["request"]["goal_joints"]),
            ),
            "verification": verification,
            "safety": _safety(data.get("safety"), folder, where),
            "objective": _objective(data.get("objective")),
            "format": read_as(fmt),
            "constraints": _constraints(data, fmt, where),
            "robustness": _robustness(data.get("robustness") if fmt in BASIS_FORMATS else None),
            "basis": basis,
            "quality": _quality(data.get("path_quality")),
        }
        fields["robot"], fields["samples"] = with_every_end_effector(
            fields["robot"], fields["samples"]
        )
        return fields
    except _CopyError as exc:
        raise PlanFileError(f"{where}: {exc}") from None
    except (KeyError, TypeError, AttributeError, ValueError) as exc:
        raise PlanFileError(f"{where}: corrupt plan file (bad or missing {exc})") from None


def _verification(data: Mapping[str, Any] | None) -> Verification:
    """The ``verification`` section (the ``passed`` flags are recomputed from the figures)."""
    if data is None:
        return Verification()
    checks = []
    for item in data.get("checks", []):
        fields = {k: v for k, v in item.items() if k != "passed"}
        checks.append(
            Check(
                name=str(fields["name"]),
                value=float(fields["value"]),
                tolerance=float(fields["tolerance"]),
                unit=str(fields["unit"]),
                error_estimate=float(fields.get("error_estimate", 0.0)),
                detail=str(fields.get("detail", "")),
            )
        )
    return Verification(tuple(checks))


class _CopyError(Exception):
    """The URDF copy of a plan does not match its stated SHA-256."""


def _beside(path: str, folder: Path | None) -> str:
    """``path`` read from ``folder`` when relative (``~`` expanded)."""
    expanded = Path(path).expanduser()
    if expanded.is_absolute() or folder is None:
        return str(expanded)
    return str(folder / expanded)


def _robot_ref(data: Mapping[str, Any], fmt: str, folder: Path | None) -> RobotRef:
    """The ``robot`` record: its path read from the plan's folder, its URDF copy checked."""
    ref = RobotRef(**{**data, "urdf": _beside(str(data["urdf"]), folder)})
    if fmt in BASIS_FORMATS and not ref.urdf_text:
        raise _CopyError(
            f"plan field 'robot.urdf_text' is missing or empty; {fmt} files carry their URDF"
        )
    if len(ref.urdf_text) > MAX_URDF_BYTES:  # characters: at most as many as its bytes
        raise _CopyError(
            f"plan field 'robot.urdf_text' holds {len(ref.urdf_text)} characters, beyond the "
            f"{MAX_URDF_BYTES} bytes a URDF file may have"
        )
    if ref.end_effectors and ref.end_effectors[0] != ref.end_effector:
        raise _CopyError(
            f"plan field 'robot.end_effector' ({excerpt(ref.end_effector)}) is not the first of "
            f"'robot.end_effectors' ({excerpt(ref.end_effectors[0])}), as a plan writes them"
        )
    if ref.urdf_text and sha256_hex(ref.urdf_text) != ref.urdf_sha256:
        raise _CopyError(
            f"plan field 'robot.urdf_sha256' ({excerpt(ref.urdf_sha256, 20)}) is not the SHA-256 "
            f"of 'robot.urdf_text' ({sha256_hex(ref.urdf_text)[:16]}...): the URDF copy was "
            "changed after the plan was made"
        )
    return ref


def _obstacle(data: Mapping[str, Any]) -> Obstacle:
    """One keep-out object of the ``safety`` section (m, rad; at the origin unless placed)."""
    xyz, rpy = data.get("xyz", (0.0, 0.0, 0.0)), data.get("rpy", (0.0, 0.0, 0.0))
    return Obstacle(
        str(data["name"]),
        str(data["shape"]),
        tuple(float(v) for v in data["size"]),
        (float(xyz[0]), float(xyz[1]), float(xyz[2])),
        (float(rpy[0]), float(rpy[1]), float(rpy[2])),
    )


def _safety(data: Any, folder: Path | None = None, where: str = "plan") -> SafetyReport:
    """The ``safety`` section (absent in files written before it existed: not checked).

    Its keep-out objects are held to a scenario's rules: at most
    :data:`~freefloat.problem.limits.MAX_OBSTACLES`, each named, no name twice.
    """
    if data is None:
        return SafetyReport()
    obstacles = [_obstacle(o) for o in data.get("obstacles", [])]
    names = [o.name for o in obstacles]
    if len(obstacles) > MAX_OBSTACLES or "" in names or len(set(names)) != len(names):
        raise PlanFileError(
            f"{where}: plan field 'safety.obstacles' must hold at most {MAX_OBSTACLES} keep-out "
            f"objects with distinct non-empty names, as a scenario's, got {excerpt(names)}"
        )
    return SafetyReport(
        checked=bool(data["checked"]),
        margin_m=float(data["margin_m"]),
        srdf=None if data.get("srdf") is None else _beside(str(data["srdf"]), folder),
        obstacles=obstacles,
        note=str(data.get("note", "")),
    )


def _objective(data: Any) -> ObjectiveReport:
    """The ``objective`` section (absent in files written before it existed: minimum norm)."""
    if data is None:
        return ObjectiveReport()
    return ObjectiveReport(
        **{
            **data,
            "levels": [Level(**level) for level in data.get("levels", [])],
        }
    )


class _DuplicateKeyError(Exception):
    """A key twice in one JSON object (carries the key)."""


def _no_duplicate_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object as a dict; a key given twice raises (``json`` would keep the last)."""
    result: dict[str, Any] = {}
    for key, value in pairs:
        if key in result:
            raise _DuplicateKeyError(key)
        result[key] = value
    return result


def _constraints(data: Mapping[str, Any], fmt: str, where: str) -> list[ConstraintRecord]:
    """The ``constraints`` record; for older formats, the constraints they promised."""
    promised = promised_constraints(fmt)
    if promised is not None:
        return promised
    records = [
        ConstraintRecord(str(item["name"]), dict(item.get("parameters", {})))
        for item in data["constraints"]
    ]
    names = [r.name for r in records]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise PlanFileError(
                f"{where}: plan field 'constraints[{i}]' names {excerpt(name)} again; each "
                "constraint is recorded once"
            )
    return records


def _robustness(data: Any) -> RobustnessReport | None:
    """The ``robustness`` section (optional; absent before ``freefloat.plan/4``)."""
    if data is None:
        return None
    return RobustnessReport(**{k: float(v) for k, v in data.items()})


def _quality(data: Any) -> PathQuality | None:
    """The ``path_quality`` section (optional; absent before ``freefloat.plan/4``)."""
    return None if data is None else PathQuality(**data)


def read_plan_json(path: str | Path) -> Any:
    """The parsed JSON of a plan file.

    The path must name a regular file of at most :data:`~freefloat.plans.limits.MAX_PLAN_BYTES`
    (checked before reading, so a FIFO or ``/dev/zero`` is refused, not read).

    A UTF-8 byte-order mark is accepted.

    Raises:
        PlanFileError: missing, not a regular file, too large, unreadable, not JSON, a key
            twice in one object, or nested too deeply to parse.
    """
    path = Path(path).expanduser()
    check_plan_file_kind(path)
    try:
        with open(path, "rb") as handle:
            raw = handle.read(MAX_PLAN_BYTES + 1)
        if len(raw) > MAX_PLAN_BYTES:
            raise PlanFileError(
                f"{path}: larger than the {MAX_PLAN_BYTES // 2**20} MiB a plan file may have"
            )
        return json.loads(raw.decode("utf-8-sig"), object_pairs_hook=_no_duplicate_keys)
    except FileNotFoundError:
        raise PlanFileError(f"plan file not found: {path}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PlanFileError(f"cannot read plan file {path}: {exc}") from None
    except json.JSONDecodeError as exc:
        hint = other_kind_hint(path, exc.doc, "plan")
        raise PlanFileError(f"{path}: not a plan file, corrupt JSON ({exc}){hint}") from None
    except RecursionError:
        raise PlanFileError(f"{path}: not a plan file, JSON nested too deeply") from None
    except _DuplicateKeyError as exc:
        raise PlanFileError(
            f"{path}: key {excerpt(exc.args[0])} appears twice in one object; a plan file "
            "states each field once"
        ) from None
    except ValueError as exc:  # an integer of thousands of digits
        raise PlanFileError(f"{path}: not a plan file ({excerpt(str(exc), 80)})") from None
