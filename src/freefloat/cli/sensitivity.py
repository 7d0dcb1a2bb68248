"""``freefloat sensitivity``: the final attitude's error when the mass properties are wrong."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..problem.limits import check_number
from ..progress import stage
from .common import Commands

__all__ = ["add_parser", "check", "run"]


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
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
    p_sens.set_defaults(func=run, check=check)
    return p_sens


def check(args: argparse.Namespace) -> None:
    """Refuse uncertainties outside 0 to 1000 (%, mm) before any work."""
    for option in ("mass_pct", "com_mm", "inertia_pct"):
        check_number(getattr(args, option), f"--{option.replace('_', '-')}", 1000.0, low=0.0)


def run(args: argparse.Namespace) -> int:
    """Print the plan's final-attitude sensitivity to its mass properties."""
    from ..problem.uncertainty import Uncertainty
    from ..robust.plan_robustness import plan_sensitivity
    from ..viz.robustness import sensitivity_table

    uncertainty = Uncertainty(args.mass_pct / 100.0, args.com_mm / 1000.0, args.inertia_pct / 100.0)
    with stage("sensitivity"):
        loaded, result = plan_sensitivity(args.plan, uncertainty)
    print(f"freefloat sensitivity: {args.plan} ({Path(loaded.robot.urdf).name}), final attitude")
    print("\n".join(sensitivity_table(result)))
    return 0
