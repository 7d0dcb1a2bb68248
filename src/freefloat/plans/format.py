"""The plan: a verified motion of a free-floating space manipulator, and its file.

:class:`Plan` gathers the records of :mod:`freefloat.plans.records` (the motion) and
:mod:`freefloat.plans.guarantees` (what it honours and how that was checked); it evaluates its
joint paths and writes its file, and reads it (``freefloat.plan/5``, :mod:`freefloat.plans.io`;
older versions, :mod:`freefloat.plans.versions`). Planning a scenario into a plan lives in
:mod:`freefloat.pipeline`; checking a plan lives in :mod:`freefloat.verify`.

A plan file is written atomically (a temporary file renamed over the target), so a reader never
sees half a plan and a failure leaves nothing behind. Units: seconds, radians (metres for
prismatic joints and positions); Euler angles, marked ``_deg``, in degrees.
"""

from __future__ import annotations

import copy
import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..files import atomic_write_text
from ..problem.basis import BASIS_NAME
from ..problem.paths import JointPolynomials, PathFamily
from .guarantees import (
    ConstraintRecord,
    ObjectiveReport,
    RobustnessReport,
    SafetyReport,
    Verification,
)
from .io import plan_fields, read_plan_json
from .records import (
    SAMPLE_ARRAYS,
    BaseReport,
    Feasibility,
    PathQuality,
    Request,
    RobotRef,
    Samples,
    SolverReport,
)
from .versions import FORMAT, MONOMIAL_BASIS, as_written_in

__all__ = ["Plan"]


@dataclass(frozen=True)
class Plan:
    """A verified point-to-point motion of a free-floating space manipulator."""

    robot: RobotRef
    duration: float
    coefficients: dict[str, list[float]]
    free_parameters: dict[str, list[float]]
    base: BaseReport
    feasibility: Feasibility
    samples: Samples
    solver: SolverReport
    request: Request
    verification: Verification = field(default_factory=Verification)
    safety: SafetyReport = field(default_factory=SafetyReport)
    objective: ObjectiveReport = field(default_factory=ObjectiveReport)
    robustness: RobustnessReport | None = None
    format: str = FORMAT
    constraints: list[ConstraintRecord] = field(default_factory=list)
    basis: str = BASIS_NAME
    quality: PathQuality | None = None

    # -- evaluation -------------------------------------------------------------------------

    def path(self) -> JointPolynomials:
        """The joint paths on [0, T], from the file's basis and coefficients."""
        names = self.robot.joints
        if self.basis == MONOMIAL_BASIS:
            return JointPolynomials.from_monomials(
                [self.coefficients[name] for name in names], self.duration
            )
        family = PathFamily(
            np.asarray(self.request.start_joints, dtype=float),
            np.asarray(self.request.goal_joints, dtype=float),
            tuple(5 + len(self.coefficients[name]) for name in names),
        )
        beta = np.concatenate([np.asarray(self.coefficients[n], dtype=float) for n in names])
        return family.polynomials(beta, self.duration)

    def joint_positions(self, t: float | np.ndarray) -> np.ndarray:
        """Joint values (rad or m) at times ``t`` (s) from the plan's path."""
        t = np.asarray(t, dtype=float)
        return self.path().positions(np.atleast_1d(t)).reshape(*t.shape, -1)

    # -- file -------------------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """The plan as the JSON-ready dictionary of its file format (a deep copy)."""
        robot = asdict(self.robot)
        if not self.robot.urdf_text:
            del robot["urdf_text"], robot["urdf_sha256"]
        samples: dict[str, Any] = {
            name: getattr(self.samples, name).tolist() for name in SAMPLE_ARRAYS
        }
        samples["end_effector_paths"] = {
            k: v.tolist() for k, v in self.samples.end_effector_paths.items()
        }
        checks = self.verification.checks
        record = {
            "format": self.format,
            "robot": robot,
            "duration": self.duration,
            "path": {
                "family": "polynomial",
                **({} if self.basis == MONOMIAL_BASIS else {"basis": self.basis}),
                "coefficients": self.coefficients,
            },
            "free_parameters": self.free_parameters,
            "base": asdict(self.base),
            "feasibility": asdict(self.feasibility),
            "samples": samples,
            "solver": asdict(self.solver),
            "request": asdict(self.request),
            "verification": {
                "passed": self.verification.passed,
                "checks": [{**asdict(c), "passed": c.passed} for c in checks],
            },
            "safety": asdict(self.safety),
            "objective": asdict(self.objective),
            "constraints": [asdict(c) for c in self.constraints],
            **({} if self.robustness is None else {"robustness": asdict(self.robustness)}),
            **({} if self.quality is None else {"path_quality": asdict(self.quality)}),
        }
        return copy.deepcopy(as_written_in(record, self.format))

    def to_json(self) -> str:
        """The plan file's text (JSON, no NaN)."""
        return json.dumps(self.to_dict(), indent=1, allow_nan=False)

    def save(self, path: str | Path) -> Path:
        """Write the plan to ``path`` atomically; return the absolute path."""
        return atomic_write_text(path, self.to_json())

    @classmethod
    def load(cls, path: str | Path) -> Plan:
        """Read a plan file.

        Raises:
            PlanFileError: unreadable, not JSON, another format version, or missing keys.
        """
        path = Path(path).expanduser()
        return cls.from_dict(read_plan_json(path), str(path), path.parent)

    @classmethod
    def from_dict(cls, data: Any, where: str = "plan", folder: Path | None = None) -> Plan:
        """Build a plan from its file dictionary (arguments and errors: :func:`.io.plan_fields`)."""
        return cls(**plan_fields(data, where, folder))
