"""Limits on a plan file, checked before any work: size, shape, finiteness, magnitudes.

A plan file is input like any other: it may be hostile. :func:`check_plan_file_kind` refuses
what is not a regular file or is larger than :data:`MAX_PLAN_BYTES` before a byte is read;
:func:`check_plan_values` checks the parsed document (either format) before it becomes a
:class:`~freefloat.plans.format.Plan`: every number finite and of sane magnitude, every list
as long as the others say, the duration, polynomial degree, sample count, joint count and
integration steps within the stated maxima below. Each refusal is one line naming the field
and quoting at most a short excerpt of the bad value.

Units: seconds, rad or m for joint values; a polynomial term ``c_k t^k`` is measured by its
size at ``t = T`` (rad or m).
"""

from __future__ import annotations

import math
import os
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..errors import PlanFileError, excerpt

__all__ = [
    "MAX_DEGREE",
    "MAX_DURATION",
    "MAX_INTEGRATION_STEPS",
    "MAX_JOINTS",
    "MAX_MAGNITUDE",
    "MAX_PLAN_BYTES",
    "MAX_SAMPLES",
    "MAX_SOLUTIONS",
    "MAX_TERM",
    "MIN_DURATION",
    "UNIT_NORM_TOLERANCE",
    "check_plan_file_kind",
    "check_plan_values",
    "excerpt",
]

#: Largest plan file read (bytes): 200 MiB, about 200 000 samples of a seven-joint arm.
MAX_PLAN_BYTES = 200 * 1024 * 1024
#: Motion time range (s): a millisecond to about eleven days.
MIN_DURATION, MAX_DURATION = 1e-3, 1e6
#: Highest polynomial degree of a joint path (the planner uses 5 to 11; the orthonormal basis
#: of format 4 stays exact far beyond).
MAX_DEGREE = 30
#: Most joints in a plan.
MAX_JOINTS = 64
#: Most samples in a plan.
MAX_SAMPLES = 1_000_000
#: Most roots in the solver report.
MAX_SOLUTIONS = 100
#: Largest integration step count recorded by the solver (it uses at most 4096).
MAX_INTEGRATION_STEPS = 1 << 16
#: Largest size of one polynomial term ``|c_k| T^k`` (rad or m): a million radians of travel.
MAX_TERM = 1e6
#: Largest magnitude of any number in a plan file.
MAX_MAGNITUDE = 1e100
#: How far from 1 the norm of a stated quaternion may be.
UNIT_NORM_TOLERANCE = 1e-10


def check_plan_file_kind(path: Path) -> None:
    """Refuse a plan path that is not a regular file or is too large, before reading it.

    Raises:
        PlanFileError: missing, not a regular file (a directory, FIFO, device), or larger than
            :data:`MAX_PLAN_BYTES`.
    """
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise PlanFileError(f"plan file not found: {path}") from None
    except (OSError, ValueError) as exc:
        raise PlanFileError(f"cannot read plan file {path}: {exc}") from None
    if not stat.S_ISREG(info.st_mode):
        kind = "a directory" if stat.S_ISDIR(info.st_mode) else "not a regular file"
        raise PlanFileError(f"{path}: {kind}; a plan file is a regular JSON file")
    if info.st_size > MAX_PLAN_BYTES:
        raise PlanFileError(
            f"{path}: {info.st_size / 2**20:.0f} MiB, larger than the "
            f"{MAX_PLAN_BYTES // 2**20} MiB a plan file may have"
        )


def _field(parts: list[str | int]) -> str:
    out = ""
    for part in parts:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out or "(top level)"


class _RefusalError(Exception):
    def __init__(self, field: str, problem: str) -> None:
        super().__init__(f"plan field {field!r} {problem}")


def _check_numbers(data: Any) -> None:
    """Every number finite and at most :data:`MAX_MAGNITUDE` (iterative: any depth)."""
    stack: list[tuple[Any, list[str | int]]] = [(data, [])]
    while stack:
        value, path = stack.pop()
        if isinstance(value, list):
            try:  # fast path: numbers with a finite sum and no large entry are fine
                if math.isfinite(sum(value)) and all(abs(v) <= MAX_MAGNITUDE for v in value):
                    continue
            except (TypeError, OverflowError):
                pass
            stack.extend((v, [*path, i]) for i, v in reversed(list(enumerate(value))))
        elif isinstance(value, Mapping):
            stack.extend((v, [*path, str(k)]) for k, v in reversed(list(value.items())))
        elif isinstance(value, bool) or value is None or isinstance(value, str):
            continue
        elif isinstance(value, float) and not math.isfinite(value):
            raise _RefusalError(_field(path), f"is {excerpt(value)}; every number must be finite")
        elif isinstance(value, (int, float)) and abs(value) > MAX_MAGNITUDE:
            raise _RefusalError(
                _field(path),
                f"is {excerpt(value)}, beyond the {MAX_MAGNITUDE:g} any number may reach",
            )


def _key(data: Any, key: str, path: list[str | int]) -> Any:
    if not isinstance(data, Mapping):
        raise _RefusalError(_field(path), f"must be an object, got {excerpt(data)}")
    if key not in data:
        raise _RefusalError(_field([*path, key]), "is missing")
    return data[key]


def _number(value: Any, path: list[str | int]) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _RefusalError(_field(path), f"must be a number, got {excerpt(value)}")
    return float(value)


def _vector(value: Any, path: list[str | int], length: int | None) -> list[float]:
    if not isinstance(value, list):
        raise _RefusalError(_field(path), f"must be a list of numbers, got {excerpt(value)}")
    if length is not None and len(value) != length:
        raise _RefusalError(_field(path), f"has {len(value)} entries, expected {length}")
    return [_number(v, [*path, i]) for i, v in enumerate(value)]


def _rows(value: Any, path: list[str | int], rows: int, width: int, optional: bool) -> None:
    """A list of ``rows`` lists of ``width`` numbers (or empty when ``optional``)."""
    if not isinstance(value, list):
        raise _RefusalError(_field(path), f"must be a list of rows, got {excerpt(value)}")
    if optional and not value:
        return
    if len(value) != rows:
        raise _RefusalError(
            _field(path), f"has {len(value)} rows, expected {rows} (one per sample)"
        )
    for i, row in enumerate(value):
        if not isinstance(row, list) or len(row) != width:
            got = f"{len(row)} entries" if isinstance(row, list) else excerpt(row)
            raise _RefusalError(_field([*path, i]), f"has {got}, expected {width} numbers")
        for j, x in enumerate(row):
            if isinstance(x, bool) or not isinstance(x, (int, float)):
                raise _RefusalError(_field([*path, i, j]), f"must be a number, got {excerpt(x)}")


def _per_joint(value: Any, path: list[str | int], joints: list[str]) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise _RefusalError(_field(path), "must be an object with one entry per joint")
    if set(value) != set(joints):
        extra = [k for k in value if k not in joints]
        missing = [k for k in joints if k not in value]
        what = (
            f"names unknown joints {excerpt(extra)}"
            if extra
            else f"lacks joints {excerpt(missing)}"
        )
        raise _RefusalError(_field(path), f"{what}; expected the plan's joints {excerpt(joints)}")
    return value


def check_plan_values(data: Any, where: str = "plan") -> None:
    """Check a parsed plan file (format 1 or 2) before it is read into a plan.

    Raises:
        PlanFileError: the first field that is non-finite, out of range or inconsistent in
            length with the others, named (``where`` prefixes the message).
    """
    try:
        _check_plan_values(data)
    except _RefusalError as exc:
        raise PlanFileError(f"{where}: {exc}") from None


def _check_plan_values(data: Any) -> None:
    _check_numbers(data)
    joints = _check_robot(data)
    duration = _number(_key(data, "duration", []), ["duration"])
    if not MIN_DURATION <= duration <= MAX_DURATION:
        raise _RefusalError(
            "duration",
            f"is {excerpt(duration)} s, outside the {MIN_DURATION:g} to {MAX_DURATION:g} s "
            "a motion may last",
        )
    degrees = _check_path(data, joints, duration)
    free = _per_joint(_key(data, "free_parameters", []), ["free_parameters"], joints)
    for name, degree in zip(joints, degrees, strict=True):
        _vector(free[name], ["free_parameters", name], degree - 5)

    base = _key(data, "base", [])
    for key in ("start_quaternion_xyzw", "target_quaternion_xyzw", "achieved_quaternion_xyzw"):
        quat = _vector(_key(base, key, ["base"]), ["base", key], 4)
        norm = math.sqrt(sum(x * x for x in quat))
        if abs(norm - 1.0) > UNIT_NORM_TOLERANCE:
            raise _RefusalError(f"base.{key}", f"has norm {norm:.9g}; a unit quaternion is needed")

    _check_samples(_key(data, "samples", []), len(joints), _key(data, "robot", []))
    request = _key(data, "request", [])
    for key in ("start_joints", "goal_joints"):
        _vector(_key(request, key, ["request"]), ["request", key], len(joints))
    _check_solver(_key(data, "solver", []), joints, degrees)

    verification = data.get("verification") if data.get("format") != "freefloat.plan/1" else None
    if isinstance(verification, Mapping) and isinstance(verification.get("checks"), list):
        _check_flags(verification)


def _check_robot(data: Any) -> list[str]:
    """The ``robot`` record; returns the joint names."""
    robot = _key(data, "robot", [])
    joints = _key(robot, "joints", ["robot"])
    if not isinstance(joints, list) or not all(isinstance(j, str) for j in joints):
        raise _RefusalError("robot.joints", f"must be a list of joint names, got {excerpt(joints)}")
    if not 1 <= len(joints) <= MAX_JOINTS or len(set(joints)) != len(joints):
        raise _RefusalError(
            "robot.joints", f"must name 1 to {MAX_JOINTS} distinct joints, got {excerpt(joints)}"
        )
    blank = next((i for i, j in enumerate(joints) if not j.strip()), None)
    if blank is not None:
        raise _RefusalError(f"robot.joints[{blank}]", "is an empty name; every joint has a name")
    kinds = robot.get("joint_kinds", []) if isinstance(robot, Mapping) else []
    if not isinstance(kinds, list) or len(kinds) not in (0, len(joints)):
        raise _RefusalError("robot.joint_kinds", f"must list one kind per joint ({len(joints)})")
    return joints


def _check_path(data: Any, joints: list[str], duration: float) -> list[int]:
    """The ``path`` record; returns each joint's polynomial degree."""
    path = _key(data, "path", [])
    coefficients = _per_joint(
        _key(path, "coefficients", ["path"]), ["path", "coefficients"], joints
    )
    basis = path.get("basis") if isinstance(path, Mapping) else None
    return [_degree(coefficients[name], name, duration, basis is not None) for name in joints]


def _check_samples(samples: Any, n: int, robot: Any) -> None:
    """The ``samples`` record: as many rows everywhere as instants, each as wide as it says."""
    t = _key(samples, "t", ["samples"])
    if not isinstance(t, list) or not 2 <= len(t) <= MAX_SAMPLES:
        count = len(t) if isinstance(t, list) else excerpt(t)
        raise _RefusalError("samples.t", f"must list 2 to {MAX_SAMPLES} instants, got {count}")
    _vector(t, ["samples", "t"], None)
    rows = len(t)
    widths = {
        "q": n,
        "qd": n,
        "qdd": n,
        "base_position": 3,
        "base_quaternion_xyzw": 4,
        "base_zyx_deg": 3,
        "end_effector_position": 3,
    }
    for key, width in widths.items():
        _rows(_key(samples, key, ["samples"]), ["samples", key], rows, width, False)
    for key, width in (("base_angular_velocity", 3), ("tau", n)):
        if isinstance(samples, Mapping) and key in samples:
            _rows(samples[key], ["samples", key], rows, width, True)
    _check_end_effectors(robot, samples, rows)


def _check_solver(solver: Any, joints: list[str], degrees: list[int]) -> None:
    """The ``solver`` record: its step count and roots."""
    steps = solver.get("integration_steps", 0) if isinstance(solver, Mapping) else 0
    if isinstance(steps, bool) or not isinstance(steps, int):
        raise _RefusalError("solver.integration_steps", f"must be an integer, got {excerpt(steps)}")
    if not 0 <= steps <= MAX_INTEGRATION_STEPS:
        raise _RefusalError(
            "solver.integration_steps",
            f"is {excerpt(steps)}, outside 0 to {MAX_INTEGRATION_STEPS}",
        )
    solutions = _key(solver, "solutions", ["solver"])
    if not isinstance(solutions, list) or not 1 <= len(solutions) <= MAX_SOLUTIONS:
        count = len(solutions) if isinstance(solutions, list) else excerpt(solutions)
        raise _RefusalError(
            "solver.solutions",
            f"must list 1 to {MAX_SOLUTIONS} roots (the chosen first), got {count}",
        )
    for i, root in enumerate(solutions):
        where: list[str | int] = ["solver", "solutions", i, "free_parameters"]
        values = _per_joint(_key(root, "free_parameters", where[:-1]), where, joints)
        for name, degree in zip(joints, degrees, strict=True):
            _vector(values[name], [*where, name], degree - 5)


def _check_end_effectors(robot: Any, samples: Any, rows: int) -> None:
    """Format 4: the end-effector frames are distinct names, each with a path of ``rows``."""
    frames = robot.get("end_effectors") if isinstance(robot, Mapping) else None
    if frames is not None and (
        not isinstance(frames, list)
        or not 1 <= len(frames) <= MAX_JOINTS
        or not all(isinstance(f, str) for f in frames)
        or len(set(frames)) != len(frames)
    ):
        raise _RefusalError(
            "robot.end_effectors",
            f"must name 1 to {MAX_JOINTS} distinct frames, got {excerpt(frames)}",
        )
    paths = samples.get("end_effector_paths") if isinstance(samples, Mapping) else None
    if paths is None:
        return
    if not isinstance(paths, Mapping) or (frames is not None and sorted(paths) != sorted(frames)):
        raise _RefusalError(
            "samples.end_effector_paths",
            f"must hold one path per end effector ({excerpt(frames)}), got {excerpt(paths)}",
        )
    for frame, path in paths.items():
        _rows(path, ["samples", "end_effector_paths", frame], rows, 3, False)


def _degree(c: Any, name: str, duration: float, in_basis: bool) -> int:
    """A joint's path degree from its coefficient list, whose size is checked.

    Format 4 (``in_basis``): 0 to ``MAX_DEGREE - 5`` basis coefficients (rad or m) of basis
    functions of unit RMS; older formats: 6 to ``MAX_DEGREE + 1`` monomials in t, each term
    ``c_k T^k`` within :data:`MAX_TERM`.
    """
    where: list[str | int] = ["path", "coefficients", name]
    low, high = (0, MAX_DEGREE - 5) if in_basis else (6, MAX_DEGREE + 1)
    if not isinstance(c, list) or not low <= len(c) <= high:
        raise _RefusalError(
            _field(where),
            f"must list {low} to {high} coefficients (degree 5 to {MAX_DEGREE}), got {excerpt(c)}",
        )
    for k, value in enumerate(_vector(c, where, None)):
        term = abs(value) * (1.0 if in_basis else duration**k)
        if term > MAX_TERM:
            raise _RefusalError(
                _field([*where, k]),
                f"is {excerpt(value)}: its term reaches {term:.3g}"
                f"{'' if in_basis else ' at t = T'}, beyond the {MAX_TERM:g} "
                "(rad or m) a path term may have",
            )
    return len(c) + 5 if in_basis else len(c) - 1


def _check_flags(verification: Mapping[str, Any]) -> None:
    """The stored ``passed`` flags must state what the stored figures say."""
    verdicts = []
    for i, check in enumerate(verification["checks"]):
        where: list[str | int] = ["verification", "checks", i]
        value = _number(_key(check, "value", where), [*where, "value"])
        tolerance = _number(_key(check, "tolerance", where), [*where, "tolerance"])
        estimate = check.get("error_estimate", 0.0)
        estimate = _number(estimate, [*where, "error_estimate"])
        if tolerance < 0 or estimate < 0:
            raise _RefusalError(_field(where), "has a negative tolerance or error estimate")
        verdict = value <= tolerance + estimate
        stated = check.get("passed", verdict)
        if stated is not verdict:
            raise _RefusalError(
                _field([*where, "passed"]),
                f"is {excerpt(stated)}, but the value {value:.3g} is "
                f"{'within' if verdict else 'beyond'} tolerance + estimate "
                f"{tolerance + estimate:.3g}",
            )
        verdicts.append(verdict)
    stated = verification.get("passed")
    if stated is not (bool(verdicts) and all(verdicts)):
        raise _RefusalError(
            "verification.passed", f"is {excerpt(stated)}, but its checks say otherwise"
        )
