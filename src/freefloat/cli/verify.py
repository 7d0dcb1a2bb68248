"""``freefloat verify``: re-run the independent checks of a plan file."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..plans.guarantees import Check
from ..verify.checks import REPLAY_STEPS_LIMIT, check_replay_steps, verify_plan
from ..verify.segmented import segment_count
from ..verify.stepping import MAX_REPLAY_STEPS
from .common import Commands

__all__ = ["add_parser", "check", "run"]


def add_parser(commands: Commands) -> argparse.ArgumentParser:
    """Add this command's sub-parser to ``commands``."""
    p_verify = commands.add_parser(
        "verify",
        help="re-run the independent checks of a plan file",
        description="Re-run a plan's checks from the file alone (a freefloat.plan/5 or /4 file "
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
        help="most Runge-Kutta steps the replay may take, 1 to "
        f"{REPLAY_STEPS_LIMIT}; it doubles its steps from 8 until its own "
        f"error estimate settles the verdict (default {MAX_REPLAY_STEPS})",
    )
    p_verify.set_defaults(func=run, check=check)
    return p_verify


def check(args: argparse.Namespace) -> None:
    """Refuse a replay cap the library refuses, naming the option, before reading the plan."""
    check_replay_steps(args.replay_steps, "--replay-steps")


def run(args: argparse.Namespace) -> int:
    """Print every check of the plan file; 0 when all pass, 1 otherwise."""
    from ..plans.schema import load_plan_file

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
            f"{check.error_estimate:>12.1e}  {check.verdict}"
        )
    print(f"  {'verification':<34}{'passed' if result.passed else 'FAILED':>12}")
    undecided = [c.name for c in result.checks if c.verdict == "no verdict"]
    if undecided:  # passed, but not by these: their own error covers the tolerance
        hint = "; more --replay-steps may decide them" if "replay" in "".join(undecided) else ""
        print(
            f"  without a verdict (their own error spans the tolerance): "
            f"{', '.join(undecided)}{hint}"
        )
    segments = segment_count(result["replay_joints"].detail)
    if segments:  # the replay from rest could not decide: say what was made instead
        print(
            f"  the replay was made in {segments} segments, each from the path's state at its "
            "start, figures scaled to the whole motion (from rest it could not decide)"
        )
    from ..problem.constraints import CONSTRAINTS

    rows = [check for check in result.checks if check.name in CONSTRAINTS]
    if rows:
        print("  a path constraint's value is its worst excess over its limit, negative where")
        chosen = next((c for c in rows if c.name == "clearance"), rows[0])  # the most read
        print(f"  it holds ({_reading(chosen)})")
        if chosen.name == "clearance" and chosen.detail:  # plan prints the same line
            print(f"  {'clearance':<16}{chosen.detail}")
    return 0 if result.passed else 1


def _reading(check: Check) -> str:
    """How to read one constraint row, with its own figure (to 3 digits) in its unit."""
    value, unit = check.value, check.unit
    if check.name == "clearance":
        if value <= 0.0:  # the certificate's lower bound of the smallest distance
            return (
                f"clearance {value:.3g} m: the smallest distance is at least {-value:.3g} m "
                "beyond the margin"
            )
        return f"clearance {value:.3g} m: the smallest distance may be {value:.3g} m short of it"
    if value <= 0.0:
        return f"{check.name} {value:.3g} {unit}: the tightest is {-value:.3g} {unit} inside it"
    return f"{check.name} {value:.3g} {unit}: the worst goes {value:.3g} {unit} beyond it"
