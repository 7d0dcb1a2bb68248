"""Robustness of plans to wrong mass properties: changed models, replays, correction.

The sensitivity itself lives with the problem (:mod:`freefloat.problem.inertial_sensitivity`,
:mod:`freefloat.problem.uncertainty`); this package changes a robot's inertial values
(:mod:`.inertial`), replays a plan in a changed model (:mod:`.replay`), sums up replayed
errors (:mod:`.distribution`), plans a correcting motion (:mod:`.correction`) and works on plan
files (:mod:`.plan_robustness`).
"""

from .correction import correcting_plan
from .distribution import ErrorDistribution, error_distribution
from .inertial import PARAMETERS, LinkInertial, link_inertials, perturbed_robot, with_inertials
from .plan_robustness import plan_spread, with_robustness
from .replay import ReplayOutcome, replay_attitude

__all__ = [
    "PARAMETERS",
    "ErrorDistribution",
    "LinkInertial",
    "ReplayOutcome",
    "correcting_plan",
    "error_distribution",
    "link_inertials",
    "perturbed_robot",
    "plan_spread",
    "replay_attitude",
    "with_inertials",
    "with_robustness",
]
