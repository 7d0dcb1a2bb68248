"""The plan format's versions: their tags, what each changed, and reading older ones.

Versions: ``freefloat.plan/5`` (this one) is format 4 whose ``robustness`` record counts a
captured payload as a body of its own, apart from the body holding it (a format-4 record
counts it within that body, and is recomputed so). ``freefloat.plan/4`` stores the joint paths
in the orthonormal
basis of :mod:`freefloat.problem.basis` (``path.basis = "quintic+jacobi66"``: per joint the
coefficients ``beta`` in rad, the quintic between ``request.start_joints`` and
``request.goal_joints`` implied; ``free_parameters`` and each root's are the same ``beta``) and
adds the ``path_quality`` record; it also adds every end effector, makes a plan self-contained
and records its plug-ins: ``robot.end_effectors`` (the frames, the first being
``robot.end_effector``) and ``samples.end_effector_paths`` (each one's positions, by frame;
``samples.end_effector_position`` stays the first one's); ``robot`` carries the text of the URDF
the plan was made with (``urdf_text``) and its SHA-256 (``urdf_sha256``), and a relative
``robot.urdf`` path is read from the plan file's folder; the ``constraints`` record lists every
constraint the plan honours, by registered name with its parameters, so that
``freefloat verify`` rebuilds each from the registry (clearance stays in ``safety``), and the
objective has its ``parameters``; ``safety.note`` says what clearance could not check, and
clearance is verified on the original geometry with a certificate between samples
(``clearance``, ``clearance_hull_agreement``); the optional ``robustness`` record holds the
first-order final attitude error under an uncertainty of the mass properties
(docs/robustness.md). Older files store monomials in seconds (``path.coefficients``: ascending
powers of t; ``free_parameters``: the coefficients of t^6 and up); they load with
``Plan.basis == MONOMIAL_BASIS`` and keep their format when re-written (their one end
effector's path is its only path; they carry no URDF, so they are checked against the file
their path names, as it is now; whatever their format, they are held to every limit their URDF
states, :data:`PROMISED`). ``freefloat.plan/3`` adds the ``objective`` record (what the path
minimises, its value and the freedom levels tried) and, for robots with URDF effort limits, the
``joint_effort_limits`` check. ``freefloat.plan/2`` files were minimum-norm plans (no objective
record). ``freefloat.plan/2`` stores the
verification as a list of typed checks, each with its value, tolerance, unit and the check's
own numerical error estimate. ``freefloat.plan/1`` files (freefloat 0.1) still load: their
path, samples and solver report are read as they are and their verification is dropped
(``Verification.checks`` empty, not passed), so ``freefloat verify`` recomputes it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from ..errors import PlanFileError, excerpt
from ..problem.basis import BASIS_NAME
from .guarantees import ConstraintRecord
from .records import RobotRef, Samples

__all__ = [
    "BASIS_FORMATS",
    "FORMAT",
    "FORMAT_1",
    "FORMAT_2",
    "FORMAT_3",
    "FORMAT_4",
    "MONOMIAL_BASIS",
    "PROMISED",
    "READABLE_FORMATS",
    "URDF_LIMITS",
    "as_written_in",
    "path_basis",
    "promised_constraints",
    "read_as",
    "with_every_end_effector",
]

#: Format tag of plan files written by this version.
FORMAT = "freefloat.plan/5"
#: The format before a captured payload had its own robustness row (still read and kept).
FORMAT_4 = "freefloat.plan/4"
#: The format before plan format 4 (still read, and kept when re-written).
FORMAT_3 = "freefloat.plan/3"
#: The format of freefloat 0.1 (read as format 3, its untyped verification dropped).
FORMAT_1 = "freefloat.plan/1"
#: The format before objectives and effort limits (still read, and kept when re-written).
FORMAT_2 = "freefloat.plan/2"

#: Format tags this version reads (``/1`` is converted on load).
READABLE_FORMATS = (FORMAT_1, FORMAT_2, FORMAT_3, FORMAT_4, FORMAT)
#: The formats that store the orthonormal basis, the URDF and the records of format 4.
BASIS_FORMATS = (FORMAT_4, FORMAT)

#: The constraints a file written before constraint records is held to, by format: every limit
#: its URDF states, whatever its format (a format label never chooses the limits).
#: The URDF's limits: every plan is held to them, whatever its records say.
URDF_LIMITS = ("joint_position_limits", "joint_velocity_limits", "joint_effort_limits")
PROMISED: dict[str, tuple[str, ...]] = {fmt: URDF_LIMITS for fmt in (FORMAT_1, FORMAT_2, FORMAT_3)}

#: ``Plan.basis`` of files before format 4: ascending monomial coefficients in t (s).
MONOMIAL_BASIS = "monomial"


def read_as(fmt: str) -> str:
    """The format a file of format ``fmt`` keeps in memory (``/1`` is read as ``/3``)."""
    return FORMAT_3 if fmt == FORMAT_1 else fmt


def path_basis(data: Mapping[str, Any], fmt: str, where: str) -> str:
    """The file's path basis, which must be the one of its format.

    Raises:
        PlanFileError: format 4 with monomials, or an older format with another basis.
    """
    section = data.get("path")
    basis = section.get("basis", MONOMIAL_BASIS) if isinstance(section, Mapping) else ""
    if (fmt in BASIS_FORMATS) != (basis == BASIS_NAME):
        raise PlanFileError(
            f"{where}: path basis {excerpt(basis)} does not belong to format {fmt}; "
            f"formats {FORMAT_4} and {FORMAT} store basis {BASIS_NAME!r}, older formats "
            "monomials"
        )
    return str(basis)


def promised_constraints(fmt: str) -> list[ConstraintRecord] | None:
    """The constraints a file of an older format is held to (None: formats 4 on record them)."""
    if fmt not in PROMISED:
        return None
    return [ConstraintRecord(name) for name in PROMISED[fmt]]


def with_every_end_effector(robot: RobotRef, samples: Samples) -> tuple[RobotRef, Samples]:
    """Before format 4 a plan had one end effector: make it the list, its path the only path."""
    if not robot.end_effectors:
        robot = replace(robot, end_effectors=[robot.end_effector])
    if not samples.end_effector_paths:
        paths = {robot.end_effector: samples.end_effector_position}
        samples = replace(samples, end_effector_paths=paths)
    return robot, samples


def as_written_in(record: dict[str, Any], fmt: str) -> dict[str, Any]:
    """A current plan record with only the keys a file of format ``fmt`` has (in place)."""
    if fmt in BASIS_FORMATS:
        return record
    record["robot"].pop("end_effectors")
    record["samples"].pop("end_effector_paths")
    record["objective"].pop("parameters")
    if fmt == FORMAT_2:
        del record["objective"]
    del record["constraints"]
    record.pop("robustness", None)
    return record
