"""``freefloat bounds``: the reachable yaw-change interval (planar) or an inner estimate."""

from __future__ import annotations

import argparse
import math

import numpy as np

from ..errors import InputError, InputLimitError
from ..parallel import check_jobs
from ..problem.build import ONE_JOINT_TOLERANCE, planar_yaw_branch, problem_from_scenario
from ..problem.scenario import Scenario
from ..solvers.options import SolveOptions
from .common import MAX_BUDGET, Commands, check_figure, load_scenario, positive
from .reach import add_jobs, direction_line

__all__ = ["add_parser", "check", "run"]


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
    p_bounds = commands.add_parser(
        "bounds",
        help="print the reachable yaw-change interval (planar) or an inner estimate (spatial)",
        description="Planar bounds (docs/method.md section 6): per joint the extremes of dyaw/dq "
        "and the interval of yaw changes a simple motion can reach, in degrees. For a spatial "
        "robot: a constructive inner estimate; from the quintic path's attitude, continuation "
        "goes as far as it can about six axis directions and eight diagonals within the joint "
        "limits, with the scenario's freedom (default two free coefficients per joint). "
        "freefloat reach prints the drift attitude, an outer bound and goal attitudes to paste: "
        "its turns are confirmed as plan solves them, so it may report less than this "
        "estimate, which goes as far as its budget allows without that confirmation.",
    )
    p_bounds.add_argument(
        "--plot", metavar="FILE", help="spatial: also draw the estimate (PNG, SVG or PDF)"
    )
    p_bounds.add_argument(
        "--max-angle",
        type=float,
        default=30.0,
        help="spatial: the rotation to head for in each direction, deg (default 30)",
    )
    p_bounds.add_argument(
        "--budget",
        type=int,
        default=300,
        help="spatial: residual evaluations per direction, in one pass (default 300; "
        "reach's --budget is per pass of plan's own search)",
    )
    add_jobs(p_bounds)
    p_bounds.add_argument(
        "scenario",
        nargs="?",
        help="scenario TOML file, or a shipped scenario's name (default: worked example)",
    )
    p_bounds.set_defaults(func=run, check=check)
    return p_bounds


def check(args: argparse.Namespace) -> None:
    """Refuse bad numbers and an unwritable figure before any work (docs/limits.md)."""
    positive(args.max_angle, "--max-angle", 180.0, "deg")
    if not 1 <= args.budget <= MAX_BUDGET:
        raise InputLimitError("--budget", args.budget, 1, MAX_BUDGET)
    check_jobs(args.jobs, "--jobs")
    check_figure(args)


def run(args: argparse.Namespace) -> int:
    """Print the planar bounds, or a spatial robot's inner estimate."""
    scenario = load_scenario(args.scenario)
    problem = problem_from_scenario(scenario.resolved(), check_bounds=False)
    if scenario.robot.n == 1 and not problem.planar:  # no estimate to make: one attitude
        reached = [float(v) for v in problem.achieved(np.zeros(problem.n_free))]
        print(f"freefloat bounds: {scenario.robot.name} (spatial), one joint: every path")
        print(f"  reaches base_quaternion_xyzw = {reached}")
        return 0
    if problem.bounds is None or problem.yaw_change is None:
        return spatial_bounds(scenario, args)
    if args.plot:  # before any line is printed: nothing drawn would be silently dropped
        raise InputError(
            f"--plot draws a spatial robot's estimate; {scenario.robot.name} is planar: its "
            "bounds are the interval printed here, and freefloat reach --plot draws them"
        )
    if scenario.robot.n == 1:  # no interval: every path makes the one change
        assert problem.bounds_interval is not None  # planar: its bounds are set
        return _one_joint(scenario.robot.name, problem.bounds_interval[0], problem.yaw_change)
    bounds = problem.bounds
    delta = problem.family.goal - problem.family.start
    print(f"freefloat bounds: {scenario.robot.name} (planar), simple point-to-point motion")
    print(
        f"  {'joint':<12}{'g_min':>12}{'g_max':>12}{'move':>14}{'yaw from [deg]':>17}"
        f"{'to [deg]':>12}"
    )
    for i, joint in enumerate(scenario.robot.joints):
        lo, hi = sorted((bounds.g_min[i] * delta[i], bounds.g_max[i] * delta[i]))
        move = f"{math.degrees(delta[i]):.3f} deg" if joint.angular else f"{delta[i]:.4f} m"
        print(
            f"  {joint.name:<12}{bounds.g_min[i]:>12.6f}{bounds.g_max[i]:>12.6f}{move:>14}"
            f"{math.degrees(lo):>17.3f}{math.degrees(hi):>12.3f}"
        )
    lo, hi = bounds.interval(delta)
    branch = planar_yaw_branch(problem.yaw_change, lo, hi)
    print(f"  reachable yaw change: ({math.degrees(lo):.3f}, {math.degrees(hi):.3f}) deg")
    verdict = "feasible" if branch is not None else "outside the bounds: no simple path"
    shown = math.degrees(problem.yaw_change if branch is None else branch)
    print(f"  requested yaw change: {shown:.3f} deg -> {verdict}")
    return 0


def _one_joint(name: str, change: float, asked: float) -> int:
    """A one-joint planar robot's bounds: the one yaw change (rad) every path makes."""
    print(f"freefloat bounds: {name} (planar), one joint: every path makes the same yaw change")
    print(f"  yaw change: {math.degrees(change):.6f} deg (along every path)")
    off = math.remainder(asked - change, 2.0 * math.pi)
    verdict = "feasible" if abs(off) <= ONE_JOINT_TOLERANCE else "not that one: no path"
    print(f"  requested yaw change: {math.degrees(change + off):.6f} deg -> {verdict}")
    return 0


def spatial_bounds(scenario: Scenario, args: argparse.Namespace) -> int:
    """A spatial robot's inner estimate of its reachable attitudes (and its figure)."""
    from .._blas import one_blas_thread
    from ..parallel import default_jobs, where_run
    from ..problem.constraints import Clearance, scenario_constraints
    from ..progress import LOGGER, counted
    from ..reachable import inner_family
    from ..solvers.reach import default_directions, reach_set
    from ..viz.reach_text import estimate_lines

    scenario = scenario.resolved()
    scenario.write_robot()  # an inline servicer: its URDF and SRDF (clearance reads it)
    problem = inner_family(scenario)
    constraints = scenario_constraints(scenario)
    angle = math.radians(args.max_angle)
    options = SolveOptions(max_evaluations=args.budget)
    count = len(default_directions())
    jobs = default_jobs(count) if args.jobs is None else args.jobs
    LOGGER.info("bounds: %d directions %s", count, where_run(jobs, count))
    with counted("bounds", count) as advance, one_blas_thread():
        estimate = reach_set(
            problem,
            None,
            angle,
            constraints,
            options,
            lambda i, n, d: advance(direction_line(d)),
            deferred=[c for c in constraints if isinstance(c, Clearance)],
            confirm=False,
            jobs=jobs,
        )
    print(f"freefloat bounds: {scenario.robot.name} (spatial) -- INNER ESTIMATE")
    names = [c.name for c in constraints if not c.lazy]
    lines = estimate_lines(
        estimate, scenario.robot.joint_names, angle, problem.goal_quaternion, names
    )
    for line in lines:
        print(f"  {line}")
    if args.plot:
        from ..viz.reach_plot import save_reach_figure

        written = save_reach_figure(estimate, args.plot, title=scenario.robot.name)
        print(f"  figure: {written.resolve()}")
    return 0
