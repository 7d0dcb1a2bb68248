"""The ``freefloat`` command line.

Angles are printed in degrees. Every expected failure (a :class:`FreeFloatError`) is printed
as one line ``freefloat: error: ...`` and exits with code 2, with no traceback and no file
written. The plan summary lives in :mod:`freefloat.viz.summary` and the work itself in the
layers below.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

from . import __version__
from ._exits import HungUp, Terminated, error_line, flush_output, handle_signals, silence_output
from .errors import FreeFloatError, InputError, InputLimitError, VelocityLimitError
from .files import check_output
from .pipeline import plan
from .plans.format import Plan
from .problem.build import planar_yaw_branch, problem_from_scenario
from .problem.limits import MAX_ANGLE_DEG, MAX_LENGTH_M, MAX_MAGNITUDE, check_number, check_samples
from .problem.objectives import OBJECTIVES
from .problem.scenario import Scenario, default_scenario_path
from .progress import TIMINGS, configure, stage
from .reachable import DEFAULT_BUDGET as DEFAULT_REACH_BUDGET
from .solvers.options import DEFAULT_TOLERANCE, TOLERANCE_RANGE_RAD, SolveOptions
from .verify.checks import REPLAY_STEPS_LIMIT, verify_plan
from .verify.stepping import MAX_REPLAY_STEPS
from .viz.summary import cartesian_report, robot_label, summary

if TYPE_CHECKING:
    from .robot.compose import ServicerSpec
    from .robot.payload import Payload

_robot_label = robot_label  # the name the tests know

__all__ = ["main"]

DEFAULT_OUT_DIR = Path("freefloat-out")


def _load_scenario(path: str | None) -> Scenario:
    with stage("read scenario"):
        return Scenario.from_toml(path if path else default_scenario_path())


def _cmd_plan(args: argparse.Namespace) -> int:
    from .robust.plan_robustness import with_robustness

    scenario = _load_scenario(args.scenario)
    if args.allow_full_turns:
        scenario = dataclasses.replace(scenario, allow_full_turns=True)
    result = plan(
        scenario,
        SolveOptions(tolerance=args.tolerance),
        samples=args.samples,
        objective=args.objective,
    )
    cartesian = cartesian_report(scenario, result)
    with stage("sensitivity"):
        result = with_robustness(result, scenario.robot)
    if args.output:
        output = Path(args.output)
    elif args.scenario:
        output = Path(f"{Path(args.scenario).stem}.plan.json")
    else:
        output = DEFAULT_OUT_DIR / "plan.json"
    written = result.save(output)
    after: list[str] = []
    if not args.scenario and not args.output:
        # The main job: the worked example with its playback page and plots.
        from .viz.playback import write_html
        from .viz.plots import save_figures

        with stage("write playback page"):
            html = write_html(result, DEFAULT_OUT_DIR / "plan.html")
        after.append(f"  playback        {html}")
        with stage("write plots"):
            figures = save_figures(result, DEFAULT_OUT_DIR / "plots")
        after.append(
            f"  plots           {figures[0].parent} ({len(figures)} files: "
            f"{', '.join(p.name for p in figures)})"
        )
    text = summary(
        result,
        written,
        robot_label=robot_label(scenario),
        wall_time_s=time.perf_counter() - args.started,
        timings=dict(TIMINGS),
        extra_lines=cartesian,
    )
    print("\n".join([text, *after]))
    return 0


def _checked_plan(args: argparse.Namespace) -> Plan:
    """The plan file of ``show`` or ``plot``, verified unless ``--no-verify``.

    Raises:
        PlanFileError: unreadable, breaks the schema or a limit, disagrees with its
            recomputation, or fails a check (with the hint to ``--no-verify``).
    """
    from .errors import PlanFileError, PlanMismatchError
    from .plans.schema import load_plan_file

    loaded = load_plan_file(args.plan)
    if args.no_verify:
        return loaded
    hint = f"freefloat verify {args.plan} shows the checks; --no-verify {args.command}s it anyway"
    try:
        with stage("verify"):
            verification = verify_plan(loaded)
    except PlanMismatchError as exc:
        raise PlanFileError(f"{args.plan}: {exc}; {hint}") from None
    if not verification.passed:
        raise PlanFileError(
            f"{args.plan}: the plan fails verification ({', '.join(verification.failures)}); "
            + hint
        )
    return loaded


def _cmd_show(args: argparse.Namespace) -> int:
    from .viz.playback import serve, write_html

    loaded = _checked_plan(args)
    if args.html:
        with stage("write playback page"):
            written = write_html(loaded, args.html, args.speed)
        print(f"freefloat show: wrote {written}")
    else:
        serve(loaded, args.speed)
    return 0


def _cmd_plot(args: argparse.Namespace) -> int:
    from .viz.plots import save_figures

    loaded = _checked_plan(args)
    with stage("write plots"):
        written = save_figures(loaded, args.output, svg=args.svg)
    print(f"freefloat plot: {len(written)} files in {Path(args.output).resolve()}")
    for path in written:
        print(f"  {path.name}")
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    from .export import EXPORTS, export

    if args.format not in EXPORTS:
        raise InputError(f"unknown --format {args.format!r}; valid: {', '.join(EXPORTS)}")
    rate = None
    if args.rate is not None:
        try:
            rate = float(args.rate)
        except ValueError:
            raise InputError(f"--rate must be a positive number of Hz, got {args.rate!r}") from None
        if not (math.isfinite(rate) and rate > 0):
            raise InputError(f"--rate must be a positive number of Hz, got {args.rate}")
    loaded = Plan.load(args.plan)
    with stage(f"export {args.format}"):
        written = export(loaded, args.output, args.format, rate)
    source = "the plan's samples" if rate is None else f"resampled at {rate:g} Hz"
    print(f"freefloat export: wrote {written} ({args.format}, {source})")
    return 0


def _export_names() -> list[str]:
    from .export import EXPORTS

    return list(EXPORTS)


def _cmd_bounds(args: argparse.Namespace) -> int:
    scenario = _load_scenario(args.scenario)
    problem = problem_from_scenario(scenario.resolved(), check_bounds=False)
    if problem.bounds is None or problem.yaw_change is None:
        return _spatial_bounds(scenario, args)
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
    if args.replay_steps < 1:
        raise InputError(f"--replay-steps must be at least 1, got {args.replay_steps}")
    if args.replay_steps > REPLAY_STEPS_LIMIT:
        raise InputError(
            f"--replay-steps must be at most {REPLAY_STEPS_LIMIT}, got {args.replay_steps}"
        )
    from .plans.schema import load_plan_file

    loaded = load_plan_file(args.plan)  # schema and limits first, naming the bad field
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
    from .robot.compose import compose, write_composed
    from .robot.model import load_robot
    from .robot.payload import Payload

    def _compose_payload(args: argparse.Namespace) -> Payload | None:
        """The ``--payload-*`` options as a validated ``Payload``, or None without a mass."""
        from .errors import InputError

        extra = [args.payload_com, args.payload_inertia, args.payload_box]
        if args.payload_mass is None:
            if any(v is not None for v in extra):
                raise InputError(
                    "--payload-com, --payload-inertia and --payload-box need --payload-mass"
                )
            return None
        inertia = args.payload_inertia
        if inertia is None:
            if args.payload_box is None:
                raise InputError(
                    "--payload-mass needs --payload-inertia IXX IYY IZZ IXY IXZ IYZ [kg m^2] "
                    "(or --payload-box X Y Z [m] for a uniform box)"
                )
            x, y, z = args.payload_box
            m = args.payload_mass / 12.0
            inertia = [m * (y * y + z * z), m * (x * x + z * z), m * (x * x + y * y), 0, 0, 0]
        ixx, iyy, izz, ixy, ixz, iyz = (float(v) for v in inertia)
        return Payload(
            mass=args.payload_mass,
            com_xyz=tuple(args.payload_com or (0.0, 0.0, 0.0)),
            inertia=(ixx, iyy, izz, ixy, ixz, iyz),
            box=tuple(args.payload_box) if args.payload_box is not None else None,
        )

    spec = _servicer_spec(args, _compose_payload(args))
    with stage("compose servicer"):
        composed = compose(spec)
        path = write_composed(composed, args.output)
        robot = load_robot(path, composed.end_effectors)
    print(f"freefloat compose: wrote {path}")
    if composed.srdf is not None:
        print(f"  with {path.with_suffix('.srdf').name}: each arm's SRDF pairs, prefixed")
    for name, value in composed.locked.items():
        shown = value if name in composed.prismatic else math.degrees(value)
        print(f"  locked {name} at {shown:.6g} {'m' if name in composed.prismatic else 'deg'}")
    tips = ", ".join(repr(e) for e in robot.end_effectors)
    print(
        f"  {robot.n} joints ({', '.join(robot.joint_names)}), total mass "
        f"{robot.total_mass:.3f} kg, end effector{'s' if len(robot.end_effectors) > 1 else ''} "
        f"{tips}"
    )
    if spec.payload is not None:
        print(
            f"  captured payload {spec.payload.mass:g} kg fixed to {robot.end_effector!r} "
            "(link 'captured_payload')"
        )
    return 0


def _servicer_spec(args: argparse.Namespace, payload: Payload | None) -> ServicerSpec:
    """The ``compose`` options as a spec: one ``--arm`` with its ``--mount`` per arm."""
    from .errors import InputError
    from .robot.compose import ArmSpec, ServicerSpec

    count = len(args.arm)
    rpys = args.mount_rpy or [[0.0, 0.0, 0.0]] * count
    prefixes = args.prefix or [""] * count
    given_per_arm = (("--mount", args.mount), ("--mount-rpy", rpys), ("--prefix", prefixes))
    for option, given in given_per_arm:
        if len(given) != count:
            raise InputError(f"give {option} once per --arm ({count}), got {len(given)}")
    arms = [
        ArmSpec(arm, tuple(mount), tuple(math.radians(a) for a in rpy), prefix)
        for arm, mount, rpy, prefix in zip(args.arm, args.mount, rpys, prefixes, strict=True)
    ]
    if count > 1:
        arms = [
            dataclasses.replace(a, prefix=a.prefix or f"arm{i + 1}_") for i, a in enumerate(arms)
        ]
    locks: list[list[str | tuple[str, float]]] = [[] for _ in arms]
    for item in args.lock or ():
        name, _, degrees = item.partition("=")
        value = 0.0
        if degrees:
            try:
                amount = float(degrees)
            except ValueError:
                raise InputError(f"--lock {item}: give JOINT or JOINT=DEG") from None
            value = math.radians(check_number(amount, f"--lock {name}", MAX_ANGLE_DEG, "deg"))
        owner = next((i for i, a in enumerate(arms) if name.startswith(a.prefix)), None)
        if owner is None:
            raise InputError(
                f"--lock {name}: name a joint with its arm's prefix "
                f"({', '.join(a.prefix for a in arms)})"
            )
        local = name[len(arms[owner].prefix) :]
        locks[owner].append((local, value) if degrees else local)
    arms = [
        dataclasses.replace(a, lock=tuple(lock), keep_gripper=args.keep_gripper)
        for a, lock in zip(arms, locks, strict=True)
    ]
    first = arms[0]
    return ServicerSpec(
        arm=first.arm,
        base_mass=args.base_mass,
        base_size=tuple(args.base_size),
        base_inertia=tuple(args.base_inertia) if args.base_inertia else None,
        mount=first.mount,
        mount_rpy=first.mount_rpy,
        lock=first.lock,
        keep_gripper=args.keep_gripper,
        payload=payload,
        more_arms=tuple(arms[1:]),
        prefix=first.prefix,
    )


def _spatial_bounds(scenario: Scenario, args: argparse.Namespace) -> int:
    from .solvers.reach import describe, reach_set

    extra = scenario.extra if scenario.extra is not None else [2] * scenario.robot.n
    problem = problem_from_scenario(scenario.resolved(), extra=extra, check_bounds=False)
    angle = math.radians(args.max_angle)
    options = SolveOptions(max_evaluations=args.budget)
    estimate = reach_set(problem, None, angle, None, options, confirm=False)
    print(f"freefloat bounds: {scenario.robot.name} (spatial) -- INNER ESTIMATE")
    for line in describe(estimate, scenario.robot.joint_names, angle, problem.goal_quaternion):
        print(f"  {line}")
    if args.plot:
        from .viz.reach_plot import save_reach_figure

        written = save_reach_figure(estimate, args.plot, title=scenario.robot.name)
        print(f"  figure: {written.resolve()}")
    return 0


def _cmd_sensitivity(args: argparse.Namespace) -> int:
    from .problem.uncertainty import Uncertainty
    from .robust.plan_robustness import plan_sensitivity
    from .viz.robustness import sensitivity_table

    uncertainty = Uncertainty(args.mass_pct / 100.0, args.com_mm / 1000.0, args.inertia_pct / 100.0)
    with stage("sensitivity"):
        loaded, result = plan_sensitivity(args.plan, uncertainty)
    print(f"freefloat sensitivity: {args.plan} ({Path(loaded.robot.urdf).name}), final attitude")
    print("\n".join(sensitivity_table(result)))
    return 0


def _cmd_correct(args: argparse.Namespace) -> int:
    from .robust.plan_robustness import correct_plan

    with stage("plan correction"):
        result, residual = correct_plan(args.plan, args.base_zyx_deg)
    output = Path(args.output) if args.output else Path(args.plan).with_suffix(".correct.json")
    written = result.save(output)
    print(f"freefloat correct: turns the spacecraft back by {math.degrees(residual):.4g} deg")
    print(summary(result, written, wall_time_s=time.perf_counter() - args.started))
    return 0


def _cmd_reach(args: argparse.Namespace) -> int:
    from .progress import counted
    from .reachable import reachable
    from .solvers.reach import default_directions
    from .viz.reach_text import reach_lines

    scenario = _load_scenario(args.scenario)
    with counted("reach", len(default_directions())) as advance:
        report = reachable(
            scenario,
            travel_factor=args.travel,
            budget=args.budget,
            progress=lambda i, n, d: advance(
                f"axis {' '.join(f'{x:+.2f}' for x in d.axis)}: {math.degrees(d.reached):.3f} deg"
                f" ({d.evaluations} evaluations)"
            ),
        )
    print("\n".join(reach_lines(report)))
    if args.plot:
        from .viz.reach_plot import save_reach_figure

        written = save_reach_figure(report.estimate(), args.plot, title=report.robot)
        print(f"figure: {written.resolve()}")
    return 0


def _cmd_check(args: argparse.Namespace) -> int:
    from .configuration import check_configuration, parse_joints

    scenario = _load_scenario(args.scenario)
    report = check_configuration(scenario, parse_joints(args.at, scenario))
    print(f"freefloat check: {scenario.robot.name} at {args.at}")
    print(f"  {'joint':<24}{'value':>12}{'lower':>12}{'upper':>12}{'room':>12}")
    for j in report.joints:
        scale, unit = (math.degrees, "deg") if j.angular else (float, "m")
        cells = "".join(f"{scale(v):>12.3f}" for v in (j.value, j.lower, j.upper, j.room))
        flag = "" if j.room >= 0.0 else "  OUTSIDE"
        print(f"  {j.name:<24}{cells}  {unit}{flag}")
    if report.margin is None:
        print("  clearance: not checked (no collision pairs, or [safety] check = false)")
    else:
        print(f"  closest pairs (signed distance; margin {report.margin:g} m):")
        for name, distance in report.pairs:
            print(f"    {name:<50}{distance:>10.4f} m")
        state = "keeps" if report.clear else "is below"
        print(f"  clearance {report.pairs[0][1]:.4f} m {state} the margin {report.margin:g} m")
    verdict = "ok" if report.within_limits and report.clear else "NOT OK"
    print(f"  configuration: {verdict}")
    return 0 if verdict == "ok" else 1


def _cmd_sweep(args: argparse.Namespace) -> int:
    from .sweep import SweepRow, SweepSpec, connect, plot_sweep, sweep
    from .sweep.plots import check_plottable

    spec = SweepSpec.from_toml(args.sweep)
    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers must be at least 1, got {args.workers}")
    if args.plots:
        if spec.replay:
            raise InputError("--plots draws feasibility maps of plans; a replay sweep has none")
        check_plottable(spec)
    client = connect(args.scheduler) if args.scheduler is not None else None
    try:
        rows = sweep(spec, workers=args.workers, client=client, output=args.output)
    finally:
        if client is not None:
            client.close()
    if spec.replay:
        import numpy as np

        from .robust.distribution import error_distribution
        from .sweep.replay import ReplayRow
        from .viz.robustness import distribution_lines

        print(f"freefloat sweep: {len(rows)} replays of {spec.scenario_path.name}")
        vectors = np.array(
            [
                [r.error_x_rad, r.error_y_rad, r.error_z_rad]
                for r in rows
                if isinstance(r, ReplayRow) and r.status == "replayed"
            ],
            dtype=float,
        )
        print("\n".join(distribution_lines(error_distribution(vectors), len(rows))))
        print(f"  results         {Path(args.output).resolve()}")
        return 0
    counts = {s: sum(r.status == s for r in rows) for s in ("planned", "infeasible", "failed")}
    print(
        f"freefloat sweep: {len(rows)} jobs over {', '.join(spec.keys)}: "
        + ", ".join(f"{n} {s}" for s, n in counts.items())
    )
    print(f"  results         {Path(args.output).resolve()}")
    if args.plots:
        written = plot_sweep(spec, [r for r in rows if isinstance(r, SweepRow)], args.plots)
        print(f"  plots           {', '.join(str(p) for p in written)}")
    return 0


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line ``freefloat: error: ...`` (exit code 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"freefloat: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``freefloat`` command."""
    parser = _Parser(
        prog="freefloat",
        description="Point-to-point motion planning for free-floating space manipulators. "
        "Angles on the command line and in scenario files are in degrees.",
    )
    parser.add_argument("--version", action="version", version=f"freefloat {__version__}")
    commands = parser.add_subparsers(
        dest="command", required=True, metavar="COMMAND", parser_class=_Parser
    )

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
    p_plan.add_argument(
        "--objective",
        choices=list(OBJECTIVES),
        default=None,
        help="which path is best among those that reach the goal (default: the scenario's "
        "[path] objective, else min_norm); min_effort: least integral of squared torques",
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
        help="print the reachable yaw-change interval (planar) or an inner estimate (spatial)",
        description="Planar bounds (docs/method.md section 6): per joint the extremes of dyaw/dq "
        "and the interval of yaw changes a simple motion can reach, in degrees. For a spatial "
        "robot: a constructive inner estimate; from the quintic path's attitude, continuation "
        "goes as far as it can about six axis directions and eight diagonals within the joint "
        "limits, with the scenario's freedom (default two free coefficients per joint). "
        "freefloat reach prints the drift attitude, an outer bound and goal attitudes to paste.",
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
        help="spatial: residual evaluations per direction (default 300)",
    )
    p_bounds.add_argument(
        "scenario", nargs="?", help="scenario TOML file (default: worked example)"
    )
    p_bounds.set_defaults(func=_cmd_bounds)

    p_reach = commands.add_parser(
        "reach",
        help="print the drift attitude and the attitudes a simple motion can reach",
        description="Where the plain quintic path leaves the spacecraft (the drift attitude), "
        "an outer bound on the turn of every simple motion (joint travel at most --travel times "
        "its start-goal span; 1: every joint monotone), and per direction the largest turn from "
        "the drift attitude reached by a solved path, with the goal attitude to paste into the "
        "scenario (docs/reach.md). The scenario's goal attitude is ignored.",
    )
    p_reach.add_argument("scenario", nargs="?", help="scenario TOML file (default: worked example)")
    p_reach.add_argument(
        "--travel",
        type=float,
        default=1.0,
        metavar="K",
        help="outer bound for joint travel at most K x the start-goal span (default 1: monotone)",
    )
    p_reach.add_argument(
        "--budget",
        type=int,
        default=DEFAULT_REACH_BUDGET,
        help="residual evaluations per direction of the inner estimate "
        f"(default {DEFAULT_REACH_BUDGET}; a count); 0: the drift attitude and the outer bound "
        "only (well under a second)",
    )
    p_reach.add_argument("--plot", metavar="FILE", help="also draw it (PNG, SVG or PDF)")
    p_reach.set_defaults(func=_cmd_reach)

    p_check = commands.add_parser(
        "check",
        help="check one configuration: joint limits, closest pairs, clearance",
        description="Joint values against the URDF limits (room to the nearer one), the "
        "closest body pairs of the collision model and the smallest clearance against the "
        "scenario's margin, at the start, the goal or given joint values. Exit code 0 when "
        "within the limits and clear, 1 otherwise.",
    )
    p_check.add_argument("scenario", help="scenario TOML file")
    p_check.add_argument(
        "--at",
        default="start",
        metavar="start|goal|J1,J2,...",
        help="the configuration: start (default), goal, or one value per joint, "
        "comma-separated (deg; m for prismatic joints)",
    )
    p_check.set_defaults(func=_cmd_check)

    p_verify = commands.add_parser(
        "verify",
        help="re-run the independent checks of a plan file",
        description="Re-run a plan's checks from the file alone (a freefloat.plan/4 file "
        "carries its URDF and its SHA-256; a URDF file at its path must still be that one). "
        "The file is "
        "checked against the plan schema and its limits first, then every number in it (free "
        "parameters, samples, torques, base and end-effector paths, solver residuals, the "
        "verification figures) is recomputed from the URDF, duration and coefficients and must "
        "agree; then the checks run: momentum along the samples, independent attitude "
        "integration, forward-dynamics replay under the planned torques, boundary conditions, "
        "limits. Exit code 0 if all pass, 1 if a check fails, 2 for an unreadable plan or a "
        "number that disagrees with its recomputation (the field is named).",
    )
    p_verify.add_argument("plan", help="plan JSON file")
    p_verify.add_argument(
        "--replay-steps",
        type=int,
        default=MAX_REPLAY_STEPS,
        help="most RK4 steps the replay may take, 1 to "
        f"{REPLAY_STEPS_LIMIT}; it doubles its steps from 16 until its own "
        f"error estimate settles the verdict (default {MAX_REPLAY_STEPS})",
    )
    p_verify.set_defaults(func=_cmd_verify)

    p_compose = commands.add_parser(
        "compose",
        help="mount one or more arms on a box spacecraft and write one validated URDF",
        description="Compose a servicer: example-robot-data arms (panda, ur5, kinova, "
        "xarm7, z1) or URDF files, mounted on a uniform box spacecraft (--arm A --mount ... "
        "--arm B --mount ...). Gripper and finger joints are locked (at 0, or mid-range when "
        "0 is outside their limits) unless --keep-gripper. Angles in degrees.",
    )
    p_compose.add_argument(
        "--arm",
        required=True,
        action="append",
        help="arm name or URDF path; repeat for more arms, each with its --mount",
    )
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
        action="append",
        metavar=("X", "Y", "Z"),
        help="arm root in the spacecraft frame [m] (once per --arm)",
    )
    p_compose.add_argument(
        "--mount-rpy",
        type=float,
        nargs=3,
        action="append",
        metavar=("R", "P", "Y"),
        help="arm root roll, pitch, yaw [deg] (once per --arm; default 0 0 0)",
    )
    p_compose.add_argument(
        "--prefix",
        action="append",
        help="put before each link and joint name of the arm (once per --arm; with several "
        "arms default arm1_, arm2_...)",
    )
    p_compose.add_argument(
        "--lock",
        nargs="*",
        metavar="JOINT[=DEG]",
        help="more joints to lock, at 0 or at DEG (with several arms, prefixed names)",
    )
    p_compose.add_argument(
        "--keep-gripper", action="store_true", help="keep gripper and finger joints movable"
    )
    p_compose.add_argument(
        "--payload-mass",
        type=float,
        metavar="KG",
        help="captured payload fixed to the end effector",
    )
    p_compose.add_argument(
        "--payload-com",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        help="payload centre of mass in the end-effector frame [m] (default: 0 0 0)",
    )
    p_compose.add_argument(
        "--payload-inertia",
        type=float,
        nargs=6,
        metavar=("IXX", "IYY", "IZZ", "IXY", "IXZ", "IYZ"),
        help="payload inertia about its centre of mass [kg m^2] "
        "(default: the uniform --payload-box's)",
    )
    p_compose.add_argument(
        "--payload-box",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        help="payload box (visual and collision), centred on its centre of mass [m]",
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
    _add_no_verify(p_show, "show")
    p_show.set_defaults(func=_cmd_show)

    p_export = commands.add_parser(
        "export",
        help="write a plan as CSV, MCAP (Foxglove) or a ROS 2 bag",
        description="Export a plan: csv (one row per instant, units in the header), mcap "
        "(ROS 2 messages for Foxglove) or ros2-bag (a rosbag2 folder): the joint trajectory, "
        "joint states over time, the base pose on /tf and the end effector. Without --rate "
        "the plan's samples are written; with --rate every quantity is recomputed at that "
        "rate from the plan's polynomials and robot. No ROS installation is needed.",
    )
    p_export.add_argument("plan", help="plan JSON file")
    p_export.add_argument(
        "--format", required=True, metavar="FORMAT", help=" | ".join(_export_names())
    )
    p_export.add_argument("--rate", metavar="HZ", help="resample at HZ samples per second")
    p_export.add_argument(
        "-o", "--output", required=True, metavar="FILE", help="file (folder for ros2-bag)"
    )
    p_export.set_defaults(func=_cmd_export)

    p_plot = commands.add_parser(
        "plot",
        help="write figures of a plan (PNG, optionally SVG)",
        description="Write one figure per topic (end effector, base attitude and rate, joint "
        "positions, rates and torques) and an overview sheet.",
    )
    p_plot.add_argument("plan", help="plan JSON file")
    p_plot.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    p_plot.add_argument("--svg", action="store_true", help="also write SVG files")
    _add_no_verify(p_plot, "draw")
    p_plot.set_defaults(func=_cmd_plot)

    p_sens = commands.add_parser(
        "sensitivity",
        help="how far the spacecraft ends off its goal when the mass properties are wrong",
        description="Exact first-order sensitivity of a plan's final attitude to every body's "
        "mass, centre of mass and inertia, along the plan's fixed joint paths: per body the "
        "attitude error each uncertainty causes (worst case), and the combined RMS and worst "
        "case, in degrees (docs/robustness.md).",
    )
    p_sens.add_argument("plan", help="plan JSON file")
    p_sens.add_argument("--mass-pct", type=float, default=5.0, help="mass uncertainty, %% (5)")
    p_sens.add_argument("--com-mm", type=float, default=10.0, help="centre of mass, mm (10)")
    p_sens.add_argument(
        "--inertia-pct", type=float, default=10.0, help="inertia components, %% (10)"
    )
    p_sens.set_defaults(func=_cmd_sensitivity)

    p_correct = commands.add_parser(
        "correct",
        help="plan a motion back to the same joints that turns the spacecraft to its goal",
        description="After a plan ran and the spacecraft ended at a measured attitude off its "
        "goal: plan a second motion from the plan's goal joints back to the same joints that "
        "turns the spacecraft from the measured attitude to the goal, within the plan's limits "
        "and clearance; refused with the reachable angle when one motion cannot turn that far.",
    )
    p_correct.add_argument("plan", help="plan JSON file (the motion that was run)")
    p_correct.add_argument(
        "--base-zyx-deg",
        type=float,
        nargs=3,
        required=True,
        metavar=("Y", "P", "R"),
        help="measured spacecraft attitude: yaw, pitch, roll [deg]",
    )
    p_correct.add_argument("-o", "--output", help="plan file to write (default PLAN.correct.json)")
    p_correct.set_defaults(func=_cmd_correct)

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

    for sub in [parser, *commands.choices.values()]:
        _add_common_flags(sub)
    return parser


def _add_no_verify(parser: argparse.ArgumentParser, verb: str) -> None:
    """--no-verify of show and plot."""
    parser.add_argument(
        "--no-verify",
        action="store_true",
        help=f"{verb} the plan without verifying it first (by default a plan that fails "
        "verification or whose numbers disagree with their recomputation from its URDF is "
        "refused)",
    )


def _add_common_flags(parser: argparse.ArgumentParser) -> None:
    """-v/--verbose and -q/--quiet, before or after the command name."""
    parser.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=argparse.SUPPRESS,
        help="log stage timings (-v) and details (-vv) on stderr",
    )
    parser.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        default=argparse.SUPPRESS,
        help="no progress display and no warnings; errors and results only",
    )


def _in_degrees(exc: FreeFloatError) -> str:
    """The error's message, with angular rates in deg/s where the library speaks rad/s."""
    if isinstance(exc, VelocityLimitError) and "rad/s" in str(exc):
        return (
            f"joint {exc.joint!r} reaches {math.degrees(exc.peak):.4g} deg/s, above its "
            f"velocity limit {math.degrees(exc.limit):.4g} deg/s; the shortest duration that "
            f"respects every velocity limit is {exc.shortest_duration:.4g} s"
        )
    return str(exc)


#: Largest ``bounds --budget`` (residual evaluations per direction; 14 directions).
MAX_BUDGET = 100_000
#: Largest ``reach --travel`` (joint travel over the start-goal span).
MAX_TRAVEL = 100.0
#: Most local worker processes of ``sweep --workers``.
MAX_WORKERS = 1024
#: Fastest playback of ``show --speed`` (times real time).
MAX_SPEED = 1000.0


def _positive(value: float, name: str, high: float, unit: str = "") -> float:
    """A number in (0, high]; :class:`InputLimitError` naming ``name`` otherwise."""
    if isinstance(value, float) and (math.isnan(value) or value <= 0.0):
        units = f" of {unit}" if unit else ""
        raise InputError(f"{name} must be a positive number{units}, got {value:g}")
    return check_number(value, name, high, unit)


def _check_arguments(args: argparse.Namespace) -> None:
    """Refuse bad numbers and unwritable outputs before any work (docs/limits.md)."""
    command = args.command
    if command == "plan":
        check_samples(args.samples, "--samples")
        low, high = TOLERANCE_RANGE_RAD
        if not low <= args.tolerance <= high:  # NaN fails too
            raise InputLimitError(
                "--tolerance",
                args.tolerance,
                low,
                high,
                "rad",
                why="the attitude integration certifies plans to 1e-12 rad and verification "
                "holds them to 1e-7 rad",
            )
    elif command == "bounds":
        _positive(args.max_angle, "--max-angle", 180.0, "deg")
        if not 1 <= args.budget <= MAX_BUDGET:
            raise InputLimitError("--budget", args.budget, 1, MAX_BUDGET)
    elif command == "reach":
        check_number(args.travel, "--travel", MAX_TRAVEL, low=1.0)
        if not 0 <= args.budget <= MAX_BUDGET:
            raise InputLimitError("--budget", args.budget, 0, MAX_BUDGET)
    elif command == "compose":
        numbers: list[tuple[str, Any, float, str]] = [
            ("--base-mass", [args.base_mass], MAX_MAGNITUDE, "kg"),
            ("--base-size", args.base_size, MAX_LENGTH_M, "m"),
            ("--base-inertia", args.base_inertia, MAX_MAGNITUDE, "kg m^2"),
            ("--mount", [x for m in args.mount for x in m], MAX_LENGTH_M, "m"),
            ("--mount-rpy", [x for m in args.mount_rpy or [] for x in m], MAX_ANGLE_DEG, "deg"),
            ("--payload-mass", [args.payload_mass], MAX_MAGNITUDE, "kg"),
            ("--payload-com", args.payload_com, MAX_LENGTH_M, "m"),
            ("--payload-inertia", args.payload_inertia, MAX_MAGNITUDE, "kg m^2"),
            ("--payload-box", args.payload_box, MAX_LENGTH_M, "m"),
        ]
        for name, values, high, unit in numbers:
            for value in values or ():
                if value is not None:
                    check_number(value, name, high, unit)
    elif command == "sweep":
        if args.workers is not None and not 1 <= args.workers <= MAX_WORKERS:
            raise InputLimitError("--workers", args.workers, 1, MAX_WORKERS)
        if args.scheduler is not None and not args.scheduler.strip():
            raise InputError(
                "--scheduler is empty; give the Dask scheduler's address (tcp://host:8786), "
                "or leave the option out to run on local processes"
            )
    elif command == "show":
        _positive(args.speed, "--speed", MAX_SPEED)
    elif command == "sensitivity":
        for option in ("mass_pct", "com_mm", "inertia_pct"):
            check_number(getattr(args, option), f"--{option.replace('_', '-')}", 1000.0, low=0.0)
    elif command == "correct":
        for value in args.base_zyx_deg:
            check_number(value, "--base-zyx-deg", MAX_ANGLE_DEG, "deg")
    for option, name, folder in _OUTPUTS.get(command, ()):
        value = getattr(args, name, None)
        if value:
            is_folder = folder or (command == "export" and args.format == "ros2-bag")
            check_output(value, option, folder=is_folder)


#: Per command, the outputs checked before any work: (option, attribute, is a folder).
_OUTPUTS: dict[str, tuple[tuple[str, str, bool], ...]] = {
    "plan": (("-o", "output", False),),
    "bounds": (("--plot", "plot", False),),
    "reach": (("--plot", "plot", False),),
    "compose": (("-o", "output", False),),
    "plot": (("-o", "output", True),),
    "show": (("--html", "html", False),),
    "export": (("-o", "output", False),),
    "sweep": (("-o", "output", False), ("--plots", "plots", True)),
    "correct": (("-o", "output", False),),
}


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit code.

    0: success; 1: ``verify`` found a failing check; 2: bad input, infeasible request, no
    plan, or standard output cannot be written (one line ``freefloat: error: ...`` on
    stderr); 130: interrupted by Ctrl-C; 143: terminated by SIGTERM; 129: SIGHUP (one line
    each, no partial file left); 141: standard output was closed (silently).
    """
    undo = handle_signals()
    try:
        parser = build_parser()
        try:
            args = parser.parse_args(argv)
        except SystemExit as exc:  # --help, --version, or a one-line argument error
            flush_output()
            return exc.code if isinstance(exc.code, int) else 2
        configure(getattr(args, "verbose", 0), getattr(args, "quiet", False))
        args.started = time.perf_counter()
        _check_arguments(args)
        code = int(args.func(args))
        flush_output()
        return code
    except FreeFloatError as exc:
        error_line(f"error: {_in_degrees(exc)}")
        return 2
    except BrokenPipeError:  # standard output closed (| head): nothing more to say
        silence_output(1)
        return 141
    except OSError as exc:  # a stream, not a file (files raise FileError): > /dev/full
        silence_output(1)
        error_line(f"error: cannot write the output: {exc.strerror or exc}")
        return 2
    except KeyboardInterrupt:
        error_line("interrupted")
        return 130
    except Terminated:
        error_line("terminated")
        return 143
    except HungUp:
        error_line("hung up")
        return 129
    finally:
        undo()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
