"""``freefloat correct``: a motion back to the same joints that turns the spacecraft to its goal."""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from ..problem.limits import MAX_ANGLE_DEG, check_number
from ..progress import stage
from ..viz.summary import summary
from .common import (
    Commands,
    add_no_verify,
    check_not_read,
    check_outputs,
    checked_plan,
    plan_reads,
)

__all__ = ["add_parser", "check", "run"]


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
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
    add_no_verify(p_correct, "correct")
    p_correct.set_defaults(func=run, check=check)
    return p_correct


def check(args: argparse.Namespace) -> None:
    """Refuse a bad measured attitude and an unwritable output before any work."""
    for value in args.base_zyx_deg:
        check_number(value, "--base-zyx-deg", MAX_ANGLE_DEG, "deg")
    check_outputs(args, ("-o", "output"))
    if args.output:  # not over the robot the plan reads, refused before the work
        from ..plans.schema import load_plan_file

        check_not_read(args, plan_reads(load_plan_file(args.plan)))


def run(args: argparse.Namespace) -> int:
    """Plan the correcting motion and write it."""
    from ..robust.plan_robustness import correct_plan

    loaded = checked_plan(args)  # verified, as show, plot and export do, unless --no-verify
    with stage("plan correction"):
        found = correct_plan(loaded, args.base_zyx_deg)
    if found.plan is None:
        print(
            f"freefloat correct: the measured attitude is {math.degrees(found.turn):.3g} deg "
            f"from the plan's goal, within the attitude tolerance "
            f"({math.degrees(found.tolerance):.3g} deg): nothing to correct, no plan written"
        )
        return 0
    output = Path(args.output) if args.output else Path(args.plan).with_suffix(".correct.json")
    written = found.plan.save(output)
    print(f"freefloat correct: turns the spacecraft back by {math.degrees(found.turn):.4g} deg")
    print(
        summary(
            found.plan, written, wall_time_s=time.perf_counter() - args.started, command="correct"
        )
    )
    return 0
