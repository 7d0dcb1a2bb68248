"""The ``freefloat`` command line.

Angles are printed in degrees. Every expected failure (a :class:`FreeFloatError`) is printed
as one line ``freefloat: error: ...`` and exits with code 2, with no traceback and no file
written.

This module is long because it holds the parser and the handler of every subcommand (plan,
bounds, verify, compose, show, plot, sweep); the work itself lives in the layers below.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from . import __version__
from .errors import FreeFloatError, InputError
from .physics.attitude import quat_conjugate, quat_log, quat_multiply
from .pipeline import plan
from .plans.format import Plan
from .problem.build import planar_yaw_branch, problem_from_scenario
from .problem.residual import Problem
from .problem.scenario import Scenario, default_scenario_path
from .solvers.options import DEFAULT_TOLERANCE, SolveOptions
from .verify.checks import verify_plan

__all__ = ["main"]

DEFAULT_OUT_DIR = Path("freefloat-out")


def _load_scenario(path: str | None) -> Scenario:
    return Scenario.from_toml(path if path else default_scenario_path())


def _attitude_table(p: Plan) -> list[str]:
    rows = [f"  {'base attitude':<16}{'yaw [deg]':>14}{'pitch [deg]':>14}{'roll [deg]':>14}"]
    for label, angles in (
        ("start", p.base.start_zyx_deg),
        ("target", p.base.target_zyx_deg),
        ("achieved", p.base.achieved_zyx_deg),
    ):
        rows.append(f"  {label:<16}" + "".join(f"{a:>14.6f}" for a in angles))
    return rows


def summary(p: Plan, output: Path | None = None) -> str:
    """The short text summary ``freefloat plan`` prints (angles in degrees)."""
    lines = [f"freefloat plan: {Path(p.robot.urdf).name}, T = {p.duration:g} s"]
    lines += _attitude_table(p)
    lines.append(f"  attitude error  {p.base.attitude_error_rad:.3e} rad")
    v = p.verification
    if v.checks:
        lines.append(
            f"  verification    {'passed' if v.passed else 'FAILED'}: independent attitude "
            f"{v['attitude_independent'].value:.1e} rad, replay "
            f"{v['replay_attitude'].value:.1e} rad, momentum {v['momentum'].value:.1e} kg m^2/s"
        )
    free = [
        f"{name}: " + ", ".join(f"t^{6 + k} {c:.9e}" for k, c in enumerate(values))
        for name, values in p.free_parameters.items()
        if values
    ]
    lines.append("  free parameters " + ("; ".join(free) if free else "(none)"))
    if p.feasibility.planar and p.feasibility.yaw_change_bounds_deg is not None:
        lo, hi = p.feasibility.yaw_change_bounds_deg
        lines.append(
            f"  planar bounds   yaw change {p.feasibility.requested_yaw_change_deg:.3f} deg in "
            f"({lo:.3f}, {hi:.3f}) deg"
        )
    s = p.solver
    lines.append(
        f"  solver          {s.method}; {len(s.solutions)} solution(s); {s.evaluations} "
        f"evaluations; {s.wall_time_s:.3f} s"
    )
    turns = {k: v for k, v in s.full_turns.items() if v}
    if turns:
        lines.append("  full turns      " + ", ".join(f"{k} {v:+d}" for k, v in turns.items()))
    if output is not None:
        lines.append(f"  plan            {output}")
    return "\n".join(lines)


def _cmd_plan(args: argparse.Namespace) -> int:
    scenario = _load_scenario(args.scenario)
    if args.allow_full_turns:
        scenario = dataclasses.replace(scenario, allow_full_turns=True)
    if not (args.tolerance > 0 and math.isfinite(args.tolerance)):
        raise InputError(f"--tolerance must be a positive number of rad, got {args.tolerance}")
    if args.samples < 2:
        raise InputError(f"--samples must be at least 2, got {args.samples}")
    result = plan(scenario, SolveOptions(tolerance=args.tolerance), samples=args.samples)
    if args.output:
        output = Path(args.output)
    elif args.scenario:
        output = Path(f"{Path(args.scenario).stem}.plan.json")
    else:
        output = DEFAULT_OUT_DIR / "plan.json"
    written = result.save(output)
    print(summary(result, written))
    if not args.scenario and not args.output:
        # The main job: the worked example with its playback page and plots.
        from .viz.playback import write_html
        from .viz.plots import save_figures

        html = write_html(result, DEFAULT_OUT_DIR / "plan.html")
        print(f"  playback        {html}")
        figures = save_figures(result, DEFAULT_OUT_DIR / "plots")
        print(
            f"  plots           {figures[0].parent} ({len(figures)} files: "
            f"{', '.join(p.name for p in figures)})"
        )
    return 0


def _cmd_show(args: argparse.Namespace) -> int:
    from .viz.playback import serve, write_html

    loaded = Plan.load(args.plan)
    if args.html:
        print(f"freefloat show: wrote {write_html(loaded, args.html, args.speed)}")
    else:
        serve(loaded, args.speed)
    return 0


def _cmd_plot(args: argparse.Namespace) -> int:
    from .viz.plots import save_figures

    loaded = Plan.load(args.plan)
    written = save_figures(loaded, args.output, svg=args.svg)
    print(f"freefloat plot: {len(written)} files in {Path(args.output).resolve()}")
    for path in written:
        print(f"  {path.name}")
    return 0


def _cmd_bounds(args: argparse.Namespace) -> int:
    scenario = _load_scenario(args.scenario)
    problem = problem_from_scenario(scenario.resolved(), check_bounds=False)
    if problem.bounds is None or problem.yaw_change is None:
        return _spatial_bounds(scenario, problem)
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


def _cmd_verify(args: argparse.Namespace) -> int:
    loaded = Plan.load(args.plan)
    result = verify_plan(loaded, replay_steps=args.replay_steps)
    print(
        f"freefloat verify: {args.plan} ({Path(loaded.robot.urdf).name}, T = {loaded.duration:g} s)"
    )
    print(f"  {'check':<34}{'value':>12}{'tolerance':>12}{'estimate':>12}  result")
    for check in result.checks:
        label = f"{check.name} [{check.unit}]"
        print(
            f"  {label:<34}{check.value:>12.3e}{check.tolerance:>12.1e}"
            f"{check.error_estimate:>12.1e}  {'ok' if check.passed else 'FAILED'}"
        )
    print(f"  {'verification':<34}{'passed' if result.passed else 'FAILED':>12}")
    return 0 if result.passed else 1


def _cmd_compose(args: argparse.Namespace) -> int:
    from .robot.compose import ServicerSpec, compose_servicer
    from .robot.model import load_robot

    spec = ServicerSpec(
        arm=args.arm,
        base_mass=args.base_mass,
        base_size=tuple(args.base_size),
        base_inertia=tuple(args.base_inertia) if args.base_inertia else None,
        mount=tuple(args.mount),
        mount_rpy=tuple(math.radians(a) for a in args.mount_rpy),
        lock=tuple(args.lock or ()),
        keep_gripper=args.keep_gripper,
    )
    path = compose_servicer(spec, args.output)
    robot = load_robot(path)
    print(f"freefloat compose: wrote {path}")
    print(
        f"  {robot.n} joints ({', '.join(robot.joint_names)}), total mass "
        f"{robot.total_mass:.3f} kg, end effector {robot.end_effector!r}"
    )
    return 0


def _spatial_bounds(scenario: Scenario, problem: Problem) -> int:
    from .physics.momentum import MomentumMap
    from .problem.bounds import spatial_estimate

    estimate = spatial_estimate(MomentumMap(scenario.robot))
    delta = problem.family.goal - problem.family.start
    ranges = np.degrees(estimate.intervals(delta))
    wanted = np.degrees(
        quat_log(quat_multiply(quat_conjugate(problem.start_quaternion), problem.goal_quaternion))
    )
    print(f"freefloat bounds: {scenario.robot.name} (spatial) -- ESTIMATE, not a bound")
    print(f"  sampled extremes of F1 over {estimate.samples} configurations; per base axis, the")
    print("  rotation a monotone motion of the stated joint change might produce [deg]:")
    print(f"  {'axis':<6}{'from':>12}{'to':>12}{'requested':>12}")
    for k, axis in enumerate("xyz"):
        print(f"  {axis:<6}{ranges[k, 0]:>12.3f}{ranges[k, 1]:>12.3f}{wanted[k]:>12.3f}")
    print("  (requested: rotation vector from the start to the goal attitude, base frame)")
    return 0


def _cmd_sweep(args: argparse.Namespace) -> int:
    from .sweep import SweepSpec, connect, plot_sweep, sweep
    from .sweep.plots import check_plottable

    spec = SweepSpec.from_toml(args.sweep)
    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers must be at least 1, got {args.workers}")
    if args.plots:
        check_plottable(spec)
    client = connect(args.scheduler) if args.scheduler else None
    try:
        rows = sweep(spec, workers=args.workers, client=client, output=args.output)
    finally:
        if client is not None:
            client.close()
    counts = {s: sum(r.status == s for r in rows) for s in ("planned", "infeasible", "failed")}
    print(
        f"freefloat sweep: {len(rows)} jobs over {', '.join(spec.keys)}: "
        + ", ".join(f"{n} {s}" for s, n in counts.items())
    )
    print(f"  results         {Path(args.output).resolve()}")
    if args.plots:
        written = plot_sweep(spec, rows, args.plots)
        print(f"  plots           {', '.join(str(p) for p in written)}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``freefloat`` command."""
    parser = argparse.ArgumentParser(
        prog="freefloat",
        description="Point-to-point motion planning for free-floating space manipulators. "
        "Angles on the command line and in scenario files are in degrees.",
    )
    parser.add_argument("--version", action="version", version=f"freefloat {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p_plan = commands.add_parser(
        "plan",
        help="plan a scenario and write the plan file",
        description="Plan joint paths that bring the base to its goal attitude; print a "
        "summary and write the plan (JSON). Without SCENARIO, plan the shipped worked example "
        "into ./freefloat-out/ with its playback page (plan.html) and plots (plots/).",
    )
    p_plan.add_argument("scenario", nargs="?", help="scenario TOML file (default: worked example)")
    p_plan.add_argument(
        "-o",
        "--output",
        help="plan file to write (default: SCENARIO.plan.json,"
        " or freefloat-out/plan.json for the worked example)",
    )
    p_plan.add_argument(
        "--allow-full-turns",
        action="store_true",
        help="continuous joints may reach their goal the other way round",
    )
    p_plan.add_argument("--samples", type=int, default=201, help="samples in [0, T] (default 201)")
    p_plan.add_argument(
        "--tolerance",
        type=float,
        default=DEFAULT_TOLERANCE,
        help=f"attitude tolerance in rad (default {DEFAULT_TOLERANCE:g})",
    )
    p_plan.set_defaults(func=_cmd_plan)

    p_bounds = commands.add_parser(
        "bounds",
        help="print the reachable yaw-change interval (planar) or an estimate (spatial)",
        description="Planar bounds (docs/method.md section 6): per joint the extremes of dyaw/dq "
        "and the interval of yaw changes a simple motion can reach, in degrees. For a spatial "
        "robot: an estimate per base axis from sampled extremes of F1, labelled as such.",
    )
    p_bounds.add_argument(
        "scenario", nargs="?", help="scenario TOML file (default: worked example)"
    )
    p_bounds.set_defaults(func=_cmd_bounds)

    p_verify = commands.add_parser(
        "verify",
        help="re-run the independent checks of a plan file",
        description="Re-run a plan's checks from the file alone (and its URDF): momentum along "
        "the samples, independent attitude integration, forward-dynamics replay under the "
        "planned torques, boundary conditions. Exit code 0 if all pass, 1 if any fails, 2 for "
        "an unreadable plan.",
    )
    p_verify.add_argument("plan", help="plan JSON file")
    p_verify.add_argument(
        "--replay-steps", type=int, default=500, help="RK4 steps of the replay (default 500)"
    )
    p_verify.set_defaults(func=_cmd_verify)

    p_compose = commands.add_parser(
        "compose",
        help="mount an arm on a box spacecraft and write one validated URDF",
        description="Compose a servicer: an example-robot-data arm (panda, ur5, kinova, "
        "xarm7, z1) or a URDF file, mounted on a uniform box spacecraft. Gripper and finger "
        "joints are locked unless --keep-gripper. Angles in degrees.",
    )
    p_compose.add_argument("--arm", required=True, help="arm name or URDF path")
    p_compose.add_argument("--base-mass", type=float, required=True, metavar="KG")
    p_compose.add_argument(
        "--base-size",
        type=float,
        nargs=3,
        required=True,
        metavar=("X", "Y", "Z"),
        help="box edges [m]",
    )
    p_compose.add_argument(
        "--base-inertia",
        type=float,
        nargs=3,
        metavar=("IXX", "IYY", "IZZ"),
        help="principal moments [kg m^2] (default: uniform box)",
    )
    p_compose.add_argument(
        "--mount",
        type=float,
        nargs=3,
        required=True,
        metavar=("X", "Y", "Z"),
        help="arm root in the spacecraft frame [m]",
    )
    p_compose.add_argument(
        "--mount-rpy",
        type=float,
        nargs=3,
        default=[0.0, 0.0, 0.0],
        metavar=("R", "P", "Y"),
        help="arm root roll, pitch, yaw [deg]",
    )
    p_compose.add_argument("--lock", nargs="*", metavar="JOINT", help="more joints to lock at zero")
    p_compose.add_argument(
        "--keep-gripper", action="store_true", help="keep gripper and finger joints movable"
    )
    p_compose.add_argument("-o", "--output", required=True, help="URDF file to write")
    p_compose.set_defaults(func=_cmd_compose)

    p_show = commands.add_parser(
        "show",
        help="watch a plan in the browser (MeshCat)",
        description="Serve the animated plan in MeshCat and print its URL (Ctrl-C stops it), or "
        "with --html write one self-contained HTML file that plays offline.",
    )
    p_show.add_argument("plan", help="plan JSON file")
    p_show.add_argument("--html", metavar="FILE", help="write a standalone HTML file instead")
    p_show.add_argument(
        "--speed", type=float, default=1.0, help="playback speed, 1 = real time (default)"
    )
    p_show.set_defaults(func=_cmd_show)

    p_plot = commands.add_parser(
        "plot",
        help="write figures of a plan (PNG, optionally SVG)",
        description="Write one figure per topic (end effector, base attitude and rate, joint "
        "positions, rates and torques) and an overview sheet.",
    )
    p_plot.add_argument("plan", help="plan JSON file")
    p_plot.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    p_plot.add_argument("--svg", action="store_true", help="also write SVG files")
    p_plot.set_defaults(func=_cmd_plot)

    p_sweep = commands.add_parser(
        "sweep",
        help="plan every combination of scenario values and write one CSV row per job",
        description="Run a sweep file (a base scenario and axes of dotted keys into it, in the "
        "scenario's units: degrees) on local processes or a Dask cluster. Rows are written as "
        "jobs finish; re-running with the same output resumes. A failed job is a row, not an "
        "error.",
    )
    p_sweep.add_argument("sweep", help="sweep TOML file")
    p_sweep.add_argument("-o", "--output", required=True, metavar="CSV", help="results file")
    p_sweep.add_argument("--workers", type=int, help="local worker processes (default: all cores)")
    p_sweep.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on a Dask distributed cluster, e.g. tcp://host:8786 "
        "(pip install 'freefloat[cluster]')",
    )
    p_sweep.add_argument("--plots", metavar="DIR", help="draw the feasibility map into DIR")
    p_sweep.set_defaults(func=_cmd_sweep)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit code.

    0: success; 1: ``verify`` found a failing check; 2: bad input, infeasible request or no plan.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except FreeFloatError as exc:
        print(f"freefloat: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # pragma: no cover - interactive
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
