"""The model Pinocchio built, checked against the URDF that was checked.

Pinocchio merges every link fixed to a moving body into that body; a massless link with a
negative inertia, harmless on its own, makes the merged body unphysical. And the robot built
must be the robot checked: the same movable joints and the same total mass. Units: kg, kg m^2.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from ..errors import ModelError
from .urdf_checks import CheckedUrdf

__all__ = ["check_built_model"]


def check_built_model(model: pin.Model, checked: CheckedUrdf) -> None:
    """Check the model Pinocchio built against the checked file, body by body.

    Its movable joints must be the file's (same count, same names), its total mass the file's
    (relative 1e-9), and every body, after Pinocchio merged the links fixed to it, physical:
    positive mass, and a rotational inertia about its centre of mass that is positive
    semi-definite (definite for the base) within 1e-12 of its largest eigenvalue (kg m^2).

    Raises:
        ModelError: a difference or an unphysical body, named.
    """
    built = [str(name) for name in model.names[2:]]
    if sorted(built) != sorted(checked.movable_joints):
        raise ModelError(
            f"Pinocchio built joints {built} where the checked file has "
            f"{list(checked.movable_joints)}; refusing a robot other than the one checked"
        )
    mass = math.fsum(inertia.mass for inertia in model.inertias)
    if not math.isclose(mass, checked.total_mass, rel_tol=1e-9, abs_tol=1e-12):
        raise ModelError(
            f"Pinocchio built a robot of {mass:.9g} kg where the checked file says "
            f"{checked.total_mass:.9g} kg; refusing a robot other than the one checked"
        )
    for index in range(1, model.njoints):
        inertia = model.inertias[index]
        body = f"{model.names[index]!r}" if index > 1 else f"base {checked.root_link!r}"
        if not inertia.mass > 0.0:
            what = (
                f"the spacecraft (the root link {checked.root_link!r}, with the links fixed to it)"
                if index == 1
                else f"the body moved by joint {body}"
            )
            raise ModelError(f"{what} has no mass; every moving body needs a positive <mass>")
        eigenvalues = np.linalg.eigvalsh(inertia.inertia)
        lowest = float(eigenvalues.min())
        floor = -1e-12 * float(np.abs(eigenvalues).max())
        if not (lowest > 0.0 if index == 1 else lowest >= floor):
            shown = np.round(eigenvalues, 9).tolist()
            what = "base" if index == 1 else "body moved by joint"
            raise ModelError(
                f"the {what} {body}, with the links fixed to it merged, has an unphysical "
                f"rotational inertia (eigenvalues {shown} kg m^2); every body's inertia must "
                "be positive semi-definite (definite for the base)"
            )
