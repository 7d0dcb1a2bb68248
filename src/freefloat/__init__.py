"""freefloat: point-to-point motion planning for free-floating space manipulators.

A spacecraft with a robot arm, thrusters off, momentum conserved: with the arm's motors alone,
move the joints to a goal and bring the spacecraft to a goal attitude in a prescribed time.
Units: s, rad, m, kg, kg m^2 inside; degrees only at the edges (scenario files, CLI, printed
tables and the ``_deg`` fields of a plan).
"""

from .attitude import geodesic_angle, quat_from_zyx, zyx_from_quat
from .bounds import PlanarBounds, planar_bounds
from .dynamics import InverseDynamics, ReplayResult, inverse_dynamics, replay
from .errors import (
    FreeFloatError,
    InfeasibleError,
    InputError,
    JointLimitError,
    ModelError,
    PlanFileError,
    ScenarioError,
    SolverError,
    UnknownNameError,
    UnreachableGoalError,
    VelocityLimitError,
    VerificationError,
)
from .model import Joint, Robot, load_robot, shipped_robots
from .momentum import MomentumMap, is_planar, planar_axis
from .paths import PathFamily
from .plan import Plan, plan, plan_from_solution
from .problem import Problem, build_problem
from .scenario import Scenario, default_scenario_path
from .solve import Solution, SolveOptions, solve
from .verify import Verification, verify_plan

__version__ = "0.1.0"

__all__ = [
    "FreeFloatError",
    "InfeasibleError",
    "InputError",
    "InverseDynamics",
    "Joint",
    "JointLimitError",
    "ModelError",
    "MomentumMap",
    "PathFamily",
    "Plan",
    "PlanFileError",
    "PlanarBounds",
    "Problem",
    "ReplayResult",
    "Robot",
    "Scenario",
    "ScenarioError",
    "Solution",
    "SolveOptions",
    "SolverError",
    "UnknownNameError",
    "UnreachableGoalError",
    "VelocityLimitError",
    "Verification",
    "VerificationError",
    "__version__",
    "build_problem",
    "default_scenario_path",
    "geodesic_angle",
    "inverse_dynamics",
    "is_planar",
    "load_robot",
    "plan",
    "plan_from_solution",
    "planar_axis",
    "planar_bounds",
    "quat_from_zyx",
    "replay",
    "shipped_robots",
    "solve",
    "verify_plan",
    "zyx_from_quat",
]
