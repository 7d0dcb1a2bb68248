"""``freefloat check``: one configuration against the joint limits and the clearance."""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Sequence

from .common import Commands, load_scenario

__all__ = ["add_parser", "joined_values", "run"]

#: A value that starts negative (``-36.6,-76.4``, ``-3e1``, ``-inf,0``): argparse takes one
#: for an option unless it is a lone plain negative number.
_NEGATIVE_LIST = re.compile(r"^-(\d|\.\d|inf|nan)", re.IGNORECASE)


def joined_values(argv: Sequence[str]) -> list[str]:
    """``argv`` with ``--at -36.6,-76.4,...`` written as ``--at=-36.6,-76.4,...``.

    Joint values often start negative; without this, argparse refuses them with "expected one
    argument".
    """
    out: list[str] = []
    for token in argv:
        if out and out[-1] == "--at" and _NEGATIVE_LIST.match(token):
            out[-1] = f"--at={token}"
        else:
            out.append(token)
    return out


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
    p_check = commands.add_parser(
        "check",
        help="check one configuration: joint limits, closest pairs, clearance",
        description="Joint values against the URDF limits (room to the nearer one), the "
        "closest body pairs of the collision model and the smallest clearance against the "
        "scenario's margin, and the scenario's constraints of the pose alone (an end-effector "
        "cone), at the start, the goal or given joint values. Exit code 0 when all hold, 1 "
        "otherwise.",
    )
    p_check.add_argument("scenario", help="scenario TOML file, or a shipped scenario's name")
    p_check.add_argument(
        "--at",
        default="start",
        metavar="start|goal|J1,J2,...",
        help="the configuration: start (default), goal, or one value per joint, "
        "comma-separated (deg; m for prismatic joints)",
    )
    p_check.set_defaults(func=run, check=None)
    return p_check


def run(args: argparse.Namespace) -> int:
    """Print the configuration's joints, closest pairs and clearance; 1 when not ok."""
    from ..configuration import check_configuration, parse_joints

    scenario = load_scenario(args.scenario)
    report = check_configuration(scenario, parse_joints(args.at, scenario), args.at)
    print(f"freefloat check: {scenario.robot.name} at {args.at}")
    width = max([24, *(len(j.name) + 2 for j in report.joints)])
    digits = [_digits(math.degrees(j.room) if j.angular else j.room) for j in report.joints]
    cell = max([12, *(d + 8 for d in digits)])  # room for a sign, 4 digits and a space
    print(
        f"  {'joint':<{width}}"
        + "".join(f"{h:>{cell}}" for h in ("value", "lower", "upper", "room"))
    )
    for j, places in zip(report.joints, digits, strict=True):
        scale, unit = (math.degrees, "deg") if j.angular else (float, "m")
        cells = "".join(
            f"{scale(v):>{cell}.{places}f}" for v in (j.value, j.lower, j.upper, j.room)
        )
        flag = "" if j.room >= 0.0 else "  OUTSIDE"
        print(f"  {j.name:<{width}}{cells}  {unit}{flag}")
    if report.margin is None:
        why = "[safety] check = false" if not scenario.safety.check else "no collision pairs"
        print(f"  clearance: not checked ({why})")
    else:
        print(f"  closest pairs (signed distance; margin {report.margin:g} m):")
        for name, distance in report.pairs:
            print(f"    {name:<50}{distance:>10.4f} m")
        state = "keeps" if report.clear else "is below"
        print(f"  clearance {report.pairs[0][1]:.4f} m {state} the margin {report.margin:g} m")
    for posed in report.constraints:
        state = "holds" if posed.holds else "BROKEN"
        print(f"  {posed.name}: {posed.detail}: {state}")
    fine = report.within_limits and report.clear and report.within_constraints
    verdict = "ok" if fine else "NOT OK"
    print(f"  configuration: {verdict}")
    return 0 if verdict == "ok" else 1


def _digits(room: float) -> int:
    """Decimals that show a joint's room (deg or m): 3, more when it would print as 0."""
    digits = 3
    while room != 0.0 and round(room, digits) == 0.0 and digits < 12:
        digits += 1
    return digits
