"""``freefloat plot``: write figures of a plan (PNG, optionally SVG)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..progress import stage
from .common import Commands, add_no_verify, check_outputs, checked_plan

__all__ = ["add_parser", "check", "run"]


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
    p_plot = commands.add_parser(
        "plot",
        help="write figures of a plan (PNG, optionally SVG)",
        description="Write one figure per topic (end effector, base attitude and rate, joint "
        "positions, rates and torques; clearance along the path when the plan was kept clear) "
        "and an overview sheet.",
    )
    p_plot.add_argument("plan", help="plan JSON file")
    p_plot.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    p_plot.add_argument("--svg", action="store_true", help="also write SVG files")
    add_no_verify(p_plot, "draw")
    p_plot.set_defaults(func=run, check=check)
    return p_plot


def check(args: argparse.Namespace) -> None:
    """Refuse an unwritable output folder before any work."""
    check_outputs(args, ("-o", "output"), folder=True)


def run(args: argparse.Namespace) -> int:
    """Write the plan's figures into the output folder."""
    from ..viz.plots import save_figures

    loaded = checked_plan(args)
    with stage("write plots"):
        written = save_figures(loaded, args.output, svg=args.svg)
    print(f"freefloat plot: {len(written)} files in {Path(args.output).resolve()}")
    for path in written:
        print(f"  {path.name}")
    return 0
