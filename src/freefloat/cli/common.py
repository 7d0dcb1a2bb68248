"""What the command modules share: the scenario and plan they read, limits, output checks."""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import FileError, InputError, ScenarioError
from ..files import check_output
from ..plans.format import Plan
from ..problem.limits import check_number
from ..problem.scenario import (
    Scenario,
    default_scenario_path,
    shipped_scenario,
    shipped_scenario_names,
)
from ..problem.scenario_tables import read_toml
from ..progress import stage
from ..robot.locations import is_path_like
from ..verify.checks import require_verified

if TYPE_CHECKING:
    Commands = argparse._SubParsersAction[argparse.ArgumentParser]
else:
    Commands = argparse._SubParsersAction

__all__ = [
    "DEFAULT_OUT_DIR",
    "FIGURE_SUFFIXES",
    "MAX_BUDGET",
    "Commands",
    "add_no_verify",
    "check_figure",
    "check_not_read",
    "check_outputs",
    "checked_plan",
    "load_scenario",
    "plan_reads",
    "positive",
    "scenario_reads",
]

#: Where ``freefloat plan`` without a scenario writes the worked example.
DEFAULT_OUT_DIR = Path("freefloat-out")
#: Largest ``bounds --budget`` and ``reach --budget`` (residual evaluations per continuation
#: pass of a direction).
MAX_BUDGET = 100_000


def load_scenario(path: str | None) -> Scenario:
    """The scenario file at ``path``, or the worked example's without one.

    A bare name (no folder, no suffix) that is no file here but a shipped scenario's
    (``panda_servicer``) is that scenario, as in a sweep file; ``panda_servicer.toml`` is
    always a file, never the shipped one. A missing file's error lists the shipped names.
    """
    with stage("read scenario"):
        if not path:
            return Scenario.from_toml(default_scenario_path())
        named = Path(path)
        here = os.path.lexists(named.expanduser())  # a broken link is a file named so
        bare = named.name == path and not named.suffix  # "panda_servicer", no more
        if bare and not here and (shipped := shipped_scenario(path)):
            return Scenario.from_toml(shipped)
        try:
            return Scenario.from_toml(path)
        except ScenarioError as exc:
            if here:
                raise
            names = ", ".join(shipped_scenario_names())
            raise ScenarioError(f"{exc}; or name a shipped scenario: {names}") from None


#: What ``--no-verify`` does with a plan that fails verification, per command.
_ANYWAY = {"sensitivity": "assesses", "correct": "corrects"}


def checked_plan(args: argparse.Namespace, before: Callable[[Plan], None] | None = None) -> Plan:
    """The plan file a command reads (``show``, ``correct``...), verified unless ``--no-verify``.

    ``before``: called with the plan read, before it is verified (a check of the command's own
    options against it, so that a refusal costs no verification).

    Raises:
        PlanFileError: unreadable, breaks the schema or a limit, disagrees with its
            recomputation, or fails a check (with the hint to ``--no-verify``).
    """
    from ..plans.schema import load_plan_file

    loaded = load_plan_file(args.plan)
    check_not_read(args, plan_reads(loaded))
    if before is not None:
        before(loaded)
    if args.no_verify:
        return loaded
    verb = _ANYWAY.get(args.command, f"{args.command}s")
    hint = f"freefloat verify {args.plan} shows the checks; --no-verify {verb} it anyway"
    with stage("verify"):
        require_verified(loaded, str(args.plan), hint)
    return loaded


def add_no_verify(parser: argparse.ArgumentParser, verb: str) -> None:
    """--no-verify of the commands that read a plan file (show, plot, export...)."""
    parser.add_argument(
        "--no-verify",
        action="store_true",
        help=f"{verb} the plan without verifying it first (by default a plan that fails "
        "verification or whose numbers disagree with their recomputation from its URDF is "
        "refused)",
    )


def positive(value: float, name: str, high: float, unit: str = "") -> float:
    """A number in (0, high]; :class:`InputLimitError` naming ``name`` otherwise."""
    if isinstance(value, float) and (math.isnan(value) or value <= 0.0):
        units = f" of {unit}" if unit else ""
        raise InputError(f"{name} must be a positive number{units}, got {value:g}")
    return check_number(value, name, high, unit, low=0.0)


#: The figure formats ``--plot FILE`` writes, by the file name's suffix.
FIGURE_SUFFIXES = (".png", ".svg", ".pdf")


def check_figure(args: argparse.Namespace, option: str = "--plot", name: str = "plot") -> None:
    """Refuse a figure file (``option``, when given) not named for a format it is written in.

    Raises:
        InputError: its suffix is not one of :data:`FIGURE_SUFFIXES` (none included: matplotlib
            would write ``NAME.png`` beside the name asked for).
        FileError: it cannot be written (:func:`check_outputs`).
    """
    value = getattr(args, name, None)
    if value and Path(value).suffix.lower() not in FIGURE_SUFFIXES:
        raise InputError(
            f"{option} {value!r}: a figure is written as PNG, SVG or PDF; give a file name "
            f"ending {', '.join(FIGURE_SUFFIXES)}"
        )
    check_outputs(args, (option, name))


def check_outputs(
    args: argparse.Namespace, *outputs: tuple[str, str], folder: bool = False
) -> None:
    """Refuse unwritable outputs before any work: each ``(option, attribute)`` that is given.

    Raises:
        InputError: an empty name.
        FileError: the output (a file, or a folder when ``folder``) cannot be written, or it
            is the command's own input (its plan or scenario file), which it would overwrite.
    """
    for option, name in outputs:
        value = getattr(args, name, None)
        if value is None:
            continue
        if not str(value).strip():
            raise InputError(f"{option} needs a file name, got an empty one")
        target = check_output(value, option, folder=folder)
        for source in _inputs(args):
            if target.exists() and source.exists() and target.samefile(source):
                raise FileError(
                    f"{option} {value} is the file this command reads; give another name "
                    "(it would be overwritten)",
                    str(value),
                )


#: The attributes holding a command's output files (:func:`check_not_read`).
_OUTPUTS = (("-o", "output"), ("--html", "html"))


def check_not_read(
    args: argparse.Namespace,
    reads: Iterable[Path | None],
    suffix: str = "",
    whose: str = "the robot's",
) -> None:
    """Refuse an output that is a file the command reads through its scenario or plan.

    ``reads``: the robot's URDF and SRDF a scenario or plan names (a plan's own path and the
    scenario's are checked before any work, :func:`check_outputs`). ``suffix``: the output's
    companion with this suffix is the file compared (compose's SRDF beside its URDF);
    ``whose``: what the files are, for the message.

    Raises:
        FileError: ``-o`` or ``--html`` (or its companion) is one of them (it would be
            overwritten).
    """
    for option, name in _OUTPUTS:
        value = getattr(args, name, None)
        target = Path(value).expanduser() if value else None
        if target is not None and suffix:
            target = target.with_suffix(suffix)
            value = f"{value} (and {target.name} beside it)"
        if target is None or not target.exists():
            continue
        for source in reads:
            if source is not None and source.exists() and target.samefile(source):
                raise FileError(
                    f"{option} {value} is a file this command reads ({whose} "
                    f"{source.suffix.lstrip('.').upper() or 'file'}); give another name (it "
                    "would be overwritten)",
                    str(value),
                )


def scenario_reads(scenario: Scenario) -> list[Path | None]:
    """The robot files a scenario reads, none of which an output may replace.

    The URDF it names and the one it loaded (a payload's or a lock's copy), the SRDFs beside
    them, an arm URDF it composes, and its ``[safety] srdf``.
    """
    urdfs = [Path(scenario.robot.urdf)]
    if scenario.source is not None:  # the file the scenario names, not its decorated copy
        urdfs += _named_urdfs(read_toml(scenario.source, "scenario"), scenario.source.parent)
    srdf = scenario.safety.srdf
    return [
        *urdfs,
        *(u.with_suffix(".srdf") for u in urdfs),
        None if srdf is None else Path(srdf),
    ]


def _named_urdfs(data: dict[str, Any], folder: Path) -> list[Path]:
    """The URDF files a scenario's ``robot`` (or its table's ``urdf``, ``arm``, ``arms``) names."""
    value = data.get("robot")
    table = value if isinstance(value, dict) else {}
    names = [value] if isinstance(value, str) else [table.get("urdf"), table.get("arm")]
    names += [a.get("arm") for a in table.get("arms", []) if isinstance(a, dict)]
    return [
        Path(n).expanduser() if Path(n).expanduser().is_absolute() else folder / n
        for n in names
        if isinstance(n, str) and is_path_like(n)
    ]


def plan_reads(plan: Plan) -> list[Path | None]:
    """The robot files a plan reads: its URDF and SRDF (as loaded: from the plan's folder)."""
    return [Path(name) for name in (plan.robot.urdf, plan.safety.srdf) if name]


#: The attributes holding a command's input files: an output may not overwrite them.
_INPUTS = ("plan", "scenario", "sweep", "arm")


def _inputs(args: argparse.Namespace) -> list[Path]:
    """The files the command reads (its plan, scenario, sweep or arm URDFs), as given."""
    found: list[Path] = []
    for key in _INPUTS:
        value = getattr(args, key, None)
        for item in value if isinstance(value, list) else [value]:
            if isinstance(item, str) and item and "\x00" not in item:
                found.append(Path(item).expanduser())
    return found
