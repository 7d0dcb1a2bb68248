"""``freefloat plan``: plan a scenario and write the plan file."""

from __future__ import annotations

import argparse
import dataclasses
import math
import time
from pathlib import Path

from ..errors import CollisionError, EndpointError, InputError, InputLimitError, JointLimitError
from ..files import check_output
from ..pipeline import plan
from ..plans.format import Plan
from ..problem.limits import check_samples
from ..problem.objectives import OBJECTIVES
from ..problem.residual import INTEGRATION_TOLERANCE
from ..progress import LOGGER, TIMINGS, stage
from ..solvers.options import DEFAULT_TOLERANCE, TOLERANCE_RANGE_RAD, SolveOptions
from ..viz.summary import cartesian_report, robot_label, summary, unlimited_line
from ..viz.turn_notes import long_way_line
from .common import (
    DEFAULT_OUT_DIR,
    Commands,
    check_not_read,
    check_outputs,
    load_scenario,
    scenario_reads,
)

__all__ = ["add_parser", "check", "run", "tolerance_rad"]

#: Why the attitude tolerance has its range (in the unit of the option the user gave).
_WHY = (
    "the attitude integration certifies plans to {:g} {unit} and verification holds them "
    "to {:g} {unit}"
)


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
    p_plan = commands.add_parser(
        "plan",
        help="plan a scenario and write the plan file",
        description="Plan joint paths that bring the base to its goal attitude; print a "
        "summary and write the plan (JSON). Without SCENARIO, plan the shipped worked example "
        "into ./freefloat-out/ with its playback page (plan.html) and plots (plots/).",
    )
    p_plan.add_argument(
        "scenario",
        nargs="?",
        help="scenario TOML file, or a shipped scenario's name (default: worked example)",
    )
    p_plan.add_argument(
        "-o",
        "--output",
        help="plan file to write, its folder made if missing (default: the scenario file's "
        "name with .plan.json in the current folder, e.g. ./panda_servicer.plan.json; "
        "freefloat-out/plan.json, with its page and plots, for the worked example)",
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
        "--tolerance-deg",
        type=float,
        metavar="DEG",
        help=f"attitude tolerance in deg (default {math.degrees(DEFAULT_TOLERANCE):.3g} deg, "
        f"that is {DEFAULT_TOLERANCE:g} rad)",
    )
    p_plan.add_argument(
        "--tolerance",
        type=float,
        metavar="RAD",
        help="attitude tolerance in rad (deprecated: use --tolerance-deg)",
    )
    p_plan.set_defaults(func=run, check=check)
    return p_plan


def check(args: argparse.Namespace) -> None:
    """Refuse bad numbers and an unwritable output before any work (docs/limits.md)."""
    check_samples(args.samples, "--samples")
    tolerance_rad(args)
    if args.tolerance is not None:
        LOGGER.warning(
            "--tolerance is in rad and deprecated; give --tolerance-deg %g instead",
            math.degrees(args.tolerance),
        )
    check_outputs(args, ("-o", "output"))
    if not args.scenario and not args.output:  # the main job's page and plots too
        from ..viz.plots import figure_paths

        check_output(DEFAULT_OUT_DIR / "plan.json", "the plan")
        check_output(DEFAULT_OUT_DIR / "plan.html", "the playback page")
        check_output(DEFAULT_OUT_DIR / "plots", "the plots' folder", folder=True)
        for path in figure_paths(DEFAULT_OUT_DIR / "plots"):
            check_output(path, "a figure")


def tolerance_rad(args: argparse.Namespace) -> float:
    """The attitude tolerance (rad) of ``--tolerance-deg`` (deg) or ``--tolerance`` (rad).

    Without either, :data:`DEFAULT_TOLERANCE`; a degree value within printing precision of
    an end of the range is held to that end.

    Raises:
        InputError: both options are given.
        InputLimitError: the value is outside :data:`TOLERANCE_RANGE_RAD`, named in the unit
            of the option given.
    """
    low, high = TOLERANCE_RANGE_RAD
    if args.tolerance_deg is None:
        if args.tolerance is None:
            return DEFAULT_TOLERANCE
        if not low <= args.tolerance <= high:  # NaN fails too
            why = _WHY.format(INTEGRATION_TOLERANCE, high, unit="rad")
            raise InputLimitError("--tolerance", args.tolerance, low, high, "rad", why=why)
        return float(args.tolerance)
    if args.tolerance is not None:
        raise InputError(
            "give the attitude tolerance once: --tolerance-deg DEG (or the deprecated "
            "--tolerance RAD), not both"
        )
    low_deg, high_deg = math.degrees(low), math.degrees(high)
    slack = 1e-5  # the range printed with six digits is accepted at both ends
    if not low_deg * (1 - slack) <= args.tolerance_deg <= high_deg * (1 + slack):
        why = _WHY.format(math.degrees(INTEGRATION_TOLERANCE), high_deg, unit="deg")
        raise InputLimitError(
            "--tolerance-deg", args.tolerance_deg, low_deg, high_deg, "deg", why=why
        )
    return min(max(math.radians(args.tolerance_deg), low), high)


def run(args: argparse.Namespace) -> int:
    """Plan the scenario, write the plan (and for the worked example its page and plots)."""
    from ..robust.plan_robustness import with_robustness

    scenario = load_scenario(args.scenario)
    check_not_read(args, scenario_reads(scenario))
    if args.allow_full_turns:
        scenario = dataclasses.replace(scenario, allow_full_turns=True)
    try:
        result = plan(
            scenario,
            SolveOptions(tolerance=tolerance_rad(args)),
            samples=args.samples,
            objective=args.objective,
        )
    except (JointLimitError, CollisionError, EndpointError) as exc:  # the file's ends, named first
        if scenario.source is None:
            raise
        raise exc.naming(scenario.source) from None
    cartesian = cartesian_report(scenario, result)
    with stage("sensitivity"):
        result = with_robustness(result, scenario.robot)
    after: list[str] = []
    if args.output or args.scenario:
        output = Path(args.output or f"{Path(args.scenario).stem}.plan.json")
        written = result.save(output)
    else:
        written = _main_job(result, after)
    text = summary(
        result,
        written,
        robot_label=robot_label(scenario),
        wall_time_s=time.perf_counter() - args.started,
        timings=dict(TIMINGS),
        extra_lines=cartesian,
        limit_lines=[
            unlimited_line(scenario.robot),
            long_way_line(
                scenario.robot,
                result.request.start_joints,
                result.request.goal_joints,
                result.solver.full_turns,
            ),
        ],
    )
    print("\n".join([text, *after]))
    return 0


def _main_job(result: Plan, after: list[str]) -> Path:
    """The main job's outputs: the plan, its playback page and plots, in one folder at once.

    Written into a staging folder and moved into :data:`DEFAULT_OUT_DIR` together
    (:func:`~freefloat.staged.staged_folder`): an interruption leaves no plan without its
    page and plots. Appends their lines to ``after``; returns the plan file's path.
    """
    from ..staged import staged_folder
    from ..viz.playback import write_html
    from ..viz.plots import save_figures

    folder = DEFAULT_OUT_DIR.resolve()
    with staged_folder(folder) as staging:
        result.save(staging / "plan.json")
        with stage("write playback page"):
            write_html(result, staging / "plan.html")
        with stage("write plots"):
            figures = save_figures(result, staging / "plots")
    after.append(f"  playback        {folder / 'plan.html'}")
    after.append(
        f"  plots           {folder / 'plots'} ({len(figures)} files: "
        f"{', '.join(p.name for p in figures)})"
    )
    return folder / "plan.json"
