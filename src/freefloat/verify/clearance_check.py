"""Verification's clearance checks: the certificate on the original geometry, and agreement.

Two checks for a plan kept clear (:mod:`freefloat.verify.clearance`):

- ``clearance``: the margin minus the certified lower bound of clearance over every instant,
  measured on the URDF's own meshes and primitives (m; passes at <= 0 within 1e-6 m);
- ``clearance_hull_agreement``: how far the solver's hull distances stray outside what the
  meshes allow (m; passes at <= 1e-6 m, GJK's tolerance): a hull reporting more clearance
  than its mesh, or less than the mesh minus the hull's slack, fails it. Compared at the
  smallest clearance's instant, every body's hull at least once
  (:mod:`freefloat.verify.hull_agreement`).
"""

from __future__ import annotations

from ..plans.guarantees import Check
from ..problem.constraints.clearance import Clearance
from ..robot.geometry import BuiltPerSource
from ..robot.model import Robot
from .certificate import certify
from .clearance import CHECK_TOLERANCE, HULL_TOLERANCE, ClearanceCertificate, MeshClearance
from .motion import PolynomialMotion
from .path_eval import FilePath

__all__ = ["clearance_certificate", "clearance_checks", "mesh_clearance"]

#: Tolerance of the ``clearance`` check (m).
TOLERANCE = CHECK_TOLERANCE


def mesh_clearance(robot: Robot, constraint: Clearance) -> MeshClearance:
    """The original-geometry model of the pairs a clearance constraint checks.

    Built once per source in a process (:class:`~freefloat.robot.geometry.BuiltPerSource`).
    """
    return _MODELS.get(robot, constraint.model.srdf, constraint.model.obstacles)


def clearance_certificate(
    robot: Robot, constraint: Clearance, path: FilePath
) -> ClearanceCertificate:
    """The certificate of a plan file's joint paths (:mod:`.path_eval`)."""
    motion = PolynomialMotion(path, path.duration, path.degree, path.positions)
    return certify(mesh_clearance(robot, constraint), motion, constraint.margin, constraint.model)


def clearance_checks(robot: Robot, constraint: Clearance, path: FilePath) -> list[Check]:
    """The ``clearance`` and ``clearance_hull_agreement`` checks of a path (see module doc)."""
    if not constraint.applies_to(robot):
        return []
    cert = clearance_certificate(robot, constraint, path)
    return [
        Check("clearance", float(cert.margin - cert.lower_bound), TOLERANCE, "m", 0.0, cert.detail),
        Check(
            "clearance_hull_agreement",
            float(max(cert.hull_excess, -1.0)),
            HULL_TOLERANCE,
            "m",
            0.0,
            cert.hull_detail,
        ),
    ]


#: Original-geometry models per source (URDF, kinematic tree, mesh files, SRDF, obstacles).
_MODELS: BuiltPerSource[MeshClearance] = BuiltPerSource(MeshClearance)
