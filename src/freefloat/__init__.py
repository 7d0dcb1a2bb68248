"""freefloat: point-to-point motion planning for free-floating space manipulators.

A spacecraft with a robot arm, thrusters off, momentum conserved: with the arm's motors alone,
move the joints to a goal and bring the spacecraft to a goal attitude in a prescribed time.
Units: s, rad, m, kg, kg m^2 inside; degrees only at the edges (scenario files, CLI, printed
tables and the ``_deg`` fields of a plan).
"""

from ._interrupt import guard_startup as _guard_startup

_guard_startup()  # the command line only: Ctrl-C while importing is one line, exit 130

from .errors import (
    AmbiguousEndEffectorError,
    CollisionError,
    DurationLimitError,
    EffortLimitError,
    EndpointError,
    FileError,
    FreeFloatError,
    GoalAttitudeError,
    InfeasibleError,
    InputError,
    InputLimitError,
    JointLimitError,
    LockedJointError,
    ModelError,
    PlanFileError,
    PlanMismatchError,
    PluginError,
    ScenarioError,
    SolverError,
    UnitsWarning,
    UnknownNameError,
    UnreachableAttitudeError,
    UnreachableGoalError,
    VelocityLimitError,
    VerificationError,
    ViewerError,
)
from .physics.attitude import geodesic_angle, quat_from_zyx, zyx_from_quat
from .physics.dynamics import InverseDynamics, inverse_dynamics
from .physics.momentum import MomentumMap, is_planar, planar_axis
from .physics.replay import ReplayResult, replay
from .pipeline import plan, plan_from_solution
from .plans.format import Plan
from .plans.guarantees import Check, Verification
from .problem.bounds import PlanarBounds, planar_bounds
from .problem.build import build_problem, problem_from_scenario
from .problem.constraints import (
    Constraint,
    ConstraintRows,
    Excess,
    JointEffortLimits,
    JointPositionLimits,
    JointVelocityLimits,
    default_constraints,
)
from .problem.objectives import (
    OBJECTIVES,
    MinAcceleration,
    MinEffort,
    MinLength,
    MinNorm,
    Objective,
    ObjectiveValue,
    objective_named,
)
from .problem.paths import JointPolynomials, PathFamily
from .problem.residual import Problem
from .problem.scenario import Scenario, default_scenario_path
from .reachable import ReachReport, reachable
from .robot.model import Joint, Robot, load_robot, shipped_robots
from .solvers import Solution, SolveOptions, Strategy, solve
from .sweep import SweepRow, SweepSpec, sweep
from .verify.checks import verify_plan

__version__ = "0.1.0"

__all__ = [
    "OBJECTIVES",
    "AmbiguousEndEffectorError",
    "Check",
    "CollisionError",
    "Constraint",
    "ConstraintRows",
    "DurationLimitError",
    "EffortLimitError",
    "EndpointError",
    "Excess",
    "FileError",
    "FreeFloatError",
    "GoalAttitudeError",
    "InfeasibleError",
    "InputError",
    "InputLimitError",
    "InverseDynamics",
    "Joint",
    "JointEffortLimits",
    "JointLimitError",
    "JointPolynomials",
    "JointPositionLimits",
    "JointVelocityLimits",
    "LockedJointError",
    "MinAcceleration",
    "MinEffort",
    "MinLength",
    "MinNorm",
    "ModelError",
    "MomentumMap",
    "Objective",
    "ObjectiveValue",
    "PathFamily",
    "Plan",
    "PlanFileError",
    "PlanMismatchError",
    "PlanarBounds",
    "PluginError",
    "Problem",
    "ReachReport",
    "ReplayResult",
    "Robot",
    "Scenario",
    "ScenarioError",
    "Solution",
    "SolveOptions",
    "SolverError",
    "Strategy",
    "SweepRow",
    "SweepSpec",
    "UnitsWarning",
    "UnknownNameError",
    "UnreachableAttitudeError",
    "UnreachableGoalError",
    "VelocityLimitError",
    "Verification",
    "VerificationError",
    "ViewerError",
    "__version__",
    "build_problem",
    "default_constraints",
    "default_scenario_path",
    "geodesic_angle",
    "inverse_dynamics",
    "is_planar",
    "load_robot",
    "objective_named",
    "plan",
    "plan_from_solution",
    "planar_axis",
    "planar_bounds",
    "problem_from_scenario",
    "quat_from_zyx",
    "reachable",
    "replay",
    "shipped_robots",
    "solve",
    "sweep",
    "verify_plan",
    "zyx_from_quat",
]
