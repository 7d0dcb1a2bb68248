"""Warnings of a model that is legal but rarely the one meant.

A spacecraft lighter than its arm (:func:`warn_light_base`), a body whose inertia no solid has
(:func:`warn_unphysical`).
"""

from __future__ import annotations

import numpy as np

from ..progress import LOGGER
from .model import Robot
from .payload import held_payload

__all__ = ["warn_light_base", "warn_unphysical"]


def warn_light_base(robot: Robot) -> None:
    """Warn when the URDF's root, taken as the spacecraft, is lighter than the arm it carries.

    A fixed-base arm's URDF (root ``world`` or a small mounting link) planned as it is makes
    that link the spacecraft: a legal model, rarely the one meant (masses in kg, the model's).
    A captured payload does not count (:func:`_payload_mass`): a client heavier than its
    servicer is a real case, not a modelling slip.
    """
    masses = [float(inertia.mass) for inertia in robot.model.inertias[1:]]
    base, carried = masses[0], sum(masses[1:]) - _payload_mass(robot)
    if base < carried:
        LOGGER.warning(
            "the spacecraft (the URDF's root link %r, %.3g kg) is lighter than the arm it "
            "carries (%.3g kg); if the URDF describes an arm alone, add a spacecraft with "
            "freefloat compose or an inline [robot] table",
            robot.base_link,
            base,
            carried,
        )


def _payload_mass(robot: Robot) -> float:
    """The captured payload's mass (kg; :func:`.payload.held_payload`); 0 without one."""
    held = held_payload(robot)
    return 0.0 if held is None else float(held.mass)


#: Relative slack of the triangle inequality of principal moments (rounding in a URDF's digits).
TRIANGLE_SLACK = 1e-6


def warn_unphysical(robot: Robot) -> None:
    """Warn of bodies whose inertia no solid has: a principal moment above the other two's sum.

    Pinocchio takes any symmetric inertia, and so does planning; a body's moments
    (kg m^2, about its centre of mass, with the links fixed to it) that break the triangle
    inequality come from a link of the URDF that does (a model from a paper's table, say):
    the plan is that model's, said once per plan. The payload and ``--base-inertia`` checks
    refuse the same flaw in what freefloat builds itself.
    """
    flawed = []
    names = [f"the spacecraft ({robot.base_link})", *robot.model.names[2:]]
    for name, inertia in zip(names, robot.model.inertias[1:], strict=True):
        moments = np.linalg.eigvalsh(np.asarray(inertia.inertia))
        if inertia.mass > 0.0 and moments[0] + moments[1] < moments[2] * (1.0 - TRIANGLE_SLACK):
            flawed.append(f"{name} ({', '.join(f'{m:.4g}' for m in moments)} kg m^2)")
    if flawed:
        LOGGER.warning(
            "the inertia of the body moved by %s is no solid's: its largest principal moment "
            "exceeds the sum of the other two; planned as the URDF gives it",
            "; ".join(flawed),
        )
