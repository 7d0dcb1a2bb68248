"""``freefloat export``: write a plan as CSV, MCAP (Foxglove) or a ROS 2 bag."""

from __future__ import annotations

import argparse

from ..errors import InputError
from ..export import EXPORTS
from ..export.trajectory import check_rate
from ..plans.format import Plan
from ..progress import stage
from .common import Commands, add_no_verify, check_outputs, checked_plan

__all__ = ["add_parser", "check", "run"]


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
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
    p_export.add_argument("--format", required=True, metavar="FORMAT", help=" | ".join(EXPORTS))
    p_export.add_argument("--rate", metavar="HZ", help="resample at HZ samples per second")
    p_export.add_argument(
        "-o", "--output", required=True, metavar="FILE", help="file (folder for ros2-bag)"
    )
    add_no_verify(p_export, "export")
    p_export.set_defaults(func=run, check=check)
    return p_export


def check(args: argparse.Namespace) -> None:
    """Refuse an unwritable output (a folder for ``ros2-bag``) before any work."""
    check_outputs(args, ("-o", "output"), folder=args.format == "ros2-bag")


def run(args: argparse.Namespace) -> int:
    """Write the plan in the asked format, resampled when ``--rate`` is given."""
    from ..export import export

    if args.format not in EXPORTS:
        raise InputError(f"unknown --format {args.format!r}; valid: {', '.join(EXPORTS)}")
    rate = None
    if args.rate is not None:
        try:  # a number; the library refuses one that is not a positive rate
            rate = float(args.rate)
        except ValueError:
            raise InputError(f"--rate must be a positive number of Hz, got {args.rate!r}") from None

    def rate_fits(plan: Plan) -> None:  # before its verification
        if rate is not None:
            check_rate(rate, plan.duration)

    loaded = checked_plan(args, rate_fits)  # verified, as show and plot do, unless --no-verify
    with stage(f"export {args.format}"):
        written = export(loaded, args.output, args.format, rate)
    source = "the plan's samples" if rate is None else f"resampled at {rate:g} Hz"
    print(f"freefloat export: wrote {written} ({args.format}, {source})")
    return 0
