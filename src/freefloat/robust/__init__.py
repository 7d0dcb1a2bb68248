"""Robustness of plans to wrong mass properties: sensitivity, perturbed replays, correction."""

from .inertial import PARAMETERS, LinkInertial, link_inertials, perturbed_robot, with_inertials
from .replay import ReplayOutcome, replay_attitude
from .sensitivity import BODY_PARAMETERS, Sensitivity, attitude_sensitivity

__all__ = [
    "BODY_PARAMETERS",
    "PARAMETERS",
    "LinkInertial",
    "ReplayOutcome",
    "Sensitivity",
    "attitude_sensitivity",
    "link_inertials",
    "perturbed_robot",
    "replay_attitude",
    "with_inertials",
]
