"""``freefloat sensitivity``: the final attitude's error when the mass properties are wrong."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..problem.limits import check_number
from ..progress import stage
from .common import Commands, add_no_verify, checked_plan

__all__ = ["add_parser", "check", "run"]

#: The uncertainty options (attribute names) with their units; a captured payload may have
#: each of its own (``--payload-mass-pct`` ...).
_SIZES = {"mass_pct": "%%", "com_mm": "mm", "inertia_pct": "%%"}


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
    for key, unit in _SIZES.items():
        option = key.replace("_", "-")
        p_sens.add_argument(
            f"--payload-{option}",
            type=float,
            help=f"a captured payload's own, {unit} (default: as --{option})",
        )
    add_no_verify(p_sens, "assess")
    p_sens.set_defaults(func=run, check=check)
    return p_sens


def check(args: argparse.Namespace) -> None:
    """Refuse uncertainties outside 0 to 1000 (%, mm) before any work."""
    for key in _SIZES:
        for name in (key, f"payload_{key}"):
            if getattr(args, name) is not None:
                check_number(getattr(args, name), f"--{name.replace('_', '-')}", 1000.0, low=0.0)


def run(args: argparse.Namespace) -> int:
    """Print the plan's final-attitude sensitivity to its mass properties."""
    from ..problem.uncertainty import Uncertainty
    from ..robust.plan_robustness import plan_sensitivity
    from ..viz.robustness import sensitivity_table

    payload = None
    if any(getattr(args, f"payload_{key}") is not None for key in _SIZES):
        payload = Uncertainty(*_sizes(args, "payload_"))
    uncertainty = Uncertainty(*_sizes(args), payload=payload)
    checked = checked_plan(args)  # verified, as show, plot and export do, unless --no-verify
    with stage("sensitivity"):
        loaded, result = plan_sensitivity(checked, uncertainty)
    print(f"freefloat sensitivity: {args.plan} ({Path(loaded.robot.urdf).name}), final attitude")
    print("\n".join(sensitivity_table(result)))
    return 0


def _sizes(args: argparse.Namespace, prefix: str = "") -> tuple[float, float, float]:
    """Mass and inertia fractions and the centre of mass (m) of the options with ``prefix``.

    A payload option not given takes the general one's value.
    """

    def given(option: str) -> float:
        value = getattr(args, prefix + option)
        return float(getattr(args, option) if value is None else value)

    return given("mass_pct") / 100.0, given("com_mm") / 1000.0, given("inertia_pct") / 100.0
