"""``freefloat show``: watch a plan in the browser (MeshCat), or write its page."""

from __future__ import annotations

import argparse

from ..errors import InputLimitError
from ..progress import stage
from .common import Commands, add_no_verify, check_outputs, checked_plan, positive

__all__ = ["MAX_SPEED", "MIN_SPEED", "add_parser", "check", "run"]

#: Fastest and slowest playback of ``show --speed`` (times real time); slower than the
#: slowest, the page's animation times overflow (1e-300: every key at infinity).
MAX_SPEED = 1000.0
MIN_SPEED = 1e-3


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
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
    add_no_verify(p_show, "show")
    p_show.set_defaults(func=run, check=check)
    return p_show


def check(args: argparse.Namespace) -> None:
    """Refuse a bad speed and an unwritable page before any work (docs/limits.md)."""
    positive(args.speed, "--speed", MAX_SPEED)
    if args.speed < MIN_SPEED:
        raise InputLimitError("--speed", args.speed, MIN_SPEED, MAX_SPEED)
    check_outputs(args, ("--html", "html"))


def run(args: argparse.Namespace) -> int:
    """Serve the plan in MeshCat until Ctrl-C (exit 130, by main), or write its standalone page."""
    from ..viz.playback import serve, write_html

    loaded = checked_plan(args)
    if args.html:
        with stage("write playback page"):
            written = write_html(loaded, args.html, args.speed)
        print(f"freefloat show: wrote {written}")
    else:
        serve(loaded, args.speed)
    return 0
