"""Which problems to try for a scenario: freedom distributions and full turns.

When a scenario fixes no ``[path] extra``, the planner chooses where the free coefficients
go: first on the joints nearest the base (they move the most inertia per radian), then spread
over more joints, then raised in degree; the first distribution that yields a verified
solution wins. With ``allow_full_turns``, a continuous joint may also reach its goal the other
way round (goal + 2 pi k, k = +-1, +-2), which changes the attitude a motion produces. Every
attempt is recorded, so that a failure says what was tried.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NoReturn

import numpy as np

from ..errors import (
    FreeFloatError,
    InfeasibleError,
    InputError,
    SolverError,
    UnreachableAttitudeError,
)
from ..physics.momentum import cached_planar_axis
from ..problem.build import problem_from_scenario
from ..problem.constraints import Constraint, default_constraints
from ..problem.paths import PathFamily
from ..problem.residual import Problem
from ..problem.scenario import Scenario
from ..progress import LOGGER
from .dispatch import solve
from .hints import extra_hint, finger_hint, reach_hint
from .loop_start import loop_origin, same_start
from .options import Solution, SolveOptions, Strategy
from .search_record import GoalTurns, SearchRecord

__all__ = ["SearchResult", "freedom_candidates", "search", "turn_candidates"]


@dataclass
class SearchResult:
    """The solved problem and how it was found.

    Attributes:
        problem: the problem that was solved.
        solution: its solution.
        freedom: free coefficients per joint that were used.
        full_turns: per continuous joint, the whole turns added to its goal (0 if none).
        tried: every attempt, in order.
    """

    problem: Problem
    solution: Solution
    freedom: dict[str, int]
    full_turns: dict[str, int]
    tried: list[str] = field(default_factory=list)


def freedom_candidates(
    n_joints: int, equations: int, continuation: bool = False
) -> list[list[int]]:
    """Free-coefficient distributions to try, nearest-to-base joints first.

    Planar (one equation): one coefficient on each joint in turn, then one on the first two,
    then two on the first and one on the second. Spatial (three) with the multistart search:
    one on each of the first three joints (square), then one on every joint, then two on each
    of the first three. Spatial with continuation: two on every joint, then three on every
    joint (more freedom when the branch meets a limit or a singular map).
    """
    out: list[list[int]] = []

    def add(counts: list[int]) -> None:
        counts = (counts + [0] * n_joints)[:n_joints]
        while sum(counts) < equations:  # short arms: raise the degree of the first joint
            counts[0] += 1
        if counts not in out:
            out.append(counts)

    if equations == 1:
        for i in range(n_joints):
            add([0] * i + [1])
        add([1, 1])
        add([2, 1])
    elif continuation:
        add([2] * n_joints)
        add([3] * n_joints)
    else:
        add([1, 1, 1])
        add([1] * n_joints)
        add([2, 2, 2])
    return out


def turn_candidates(scenario: Scenario) -> list[np.ndarray]:
    """Goal offsets (rad) of whole turns of one continuous joint: k = +1, -1, +2, -2."""
    robot = scenario.robot
    out = []
    for k in (1, -1, 2, -2):
        for i, joint in enumerate(robot.joints):
            if joint.kind == "continuous":
                offset = np.zeros(robot.n)
                offset[i] = 2.0 * math.pi * k
                out.append(offset)
    return out


def _describe(counts: list[int], names: list[str]) -> str:
    """Free coefficients per joint for people: ``+2 for each joint`` when all alike."""
    if len(counts) == len(names) > 1 and counts[0] > 0 and len(set(counts)) == 1:
        return f"+{counts[0]} for each joint"
    return ", ".join(f"{n}+{c}" for n, c in zip(names, counts, strict=True) if c) or "none"


def search(
    scenario: Scenario,
    options: SolveOptions,
    constraints: Sequence[Constraint] | None = None,
) -> SearchResult:
    """Solve the scenario, trying freedom distributions and (if allowed) full turns.

    Raises:
        InfeasibleError: a planar request outside the bounds (for every turn tried).
        SolverError: no attempt reached the goal attitude; lists every attempt.
        FreeFloatError: bad input found while building a problem.
    """
    robot = scenario.robot
    names = robot.joint_names
    offsets = [np.zeros(robot.n)]
    if scenario.allow_full_turns:
        offsets += turn_candidates(scenario)
    planar = cached_planar_axis(robot) is not None
    record = SearchRecord()
    for offset in offsets:
        turns = {n: round(o / (2 * math.pi)) for n, o in zip(names, offset, strict=True) if o}
        label = _turns_label(turns)
        found = _levels(scenario, options, constraints, offset, label, planar, record)
        first = record.looped.get(label)
        if found is None and first is not None:  # the other loop (each plans some)
            least = f"{label}, from the loop of the least joint motion"
            found = _levels(scenario, options, constraints, offset, least, planar, record, first)
        if found is not None:
            return found

    _refuse(
        scenario,
        len(offsets),
        record.first_error,
        (record.best, record.best_axes, record.best_error),
        record.tried,
        record.nearest_goal(),
        tuple(dict.fromkeys(record.blocked)),
    )


def _levels(
    scenario: Scenario,
    options: SolveOptions,
    constraints: Sequence[Constraint] | None,
    offset: np.ndarray,
    label: str,
    planar: bool,
    record: SearchRecord,
    after: np.ndarray | None = None,
) -> SearchResult | None:
    """The freedom levels of one goal (``offset``: its joints' whole turns, rad), in order.

    Each level starts where the one before stopped, or from the quintic path, or from a loop
    when the quintic path stays put: the loop of the least swing, or with ``after`` (the first
    pass's first loop) the loop of the least joint motion (:func:`.loop_start.loop_start`);
    the record's ``looped`` keeps each pass's first loop, by label. The first solved level's
    result; None when every level failed (each failure in ``record``), or at once when the
    second pass would start from ``after`` itself.

    Raises:
        FreeFloatError: bad input found while building a problem.
    """
    robot = scenario.robot
    names = robot.joint_names
    turns = {n: round(o / (2 * math.pi)) for n, o in zip(names, offset, strict=True) if o}
    distributions = _distributions(scenario, options, planar)
    carry: tuple[PathFamily, tuple[float, ...]] | None = None
    for level, counts in enumerate(distributions, start=1):
        extra = scenario.extra if counts is None else counts
        try:
            problem = problem_from_scenario(scenario, extra=extra, goal_offset=offset)
        except InfeasibleError as exc:
            record.tried.append(f"{label}: {exc}")
            record.first_error = record.first_error or exc
            return None  # the planar bounds do not depend on the freedom
        except InputError as exc:
            record.tried.append(f"{label}: {exc}")
            record.first_error = record.first_error or exc
            continue
        used = [sum(1 for i, _ in problem.family.free_index if i == j) for j in range(robot.n)]
        freedom = f"{label}, freedom {_describe(used, names)}"
        continued = carry is not None
        if carry is not None:  # continue where less freedom stopped (new ones start at 0)
            start = problem.family.embed(carry[0], np.asarray(carry[1]))
        else:  # the quintic path, or a loop when it stays put (a pure reorientation)
            listed = default_constraints() if constraints is None else constraints
            start = loop_origin(problem, listed, swing=after is None)
            if start is not None and label not in record.looped:  # its first loop
                if after is not None and same_start(after, start):
                    return None  # the first pass started from this very loop: nothing new
                record.looped[label] = start
        LOGGER.info(
            "solve: %s, freedom %s (level %d of %d)%s",
            label,
            _describe(used, names),
            level,
            len(distributions),
            " continued from where less freedom stopped" if continued else "",
        )
        try:
            solution = solve(problem, options, constraints, start)
        except SolverError as exc:
            LOGGER.info("solve: level %d stopped: %s", level, exc.headline)
            if exc.last_beta is not None:
                carry = (problem.family, exc.last_beta)
            record.failed(exc, freedom, continued=continued, goal=label)
            continue
        how = " (continued from where less freedom stopped)" if continued else ""
        record.tried.append(f"{freedom}: solved{how}")
        return _result(problem, solution, used, turns, record.tried)
    return None


def _turns_label(turns: dict[str, int]) -> str:
    """The goal an offset asks for, for people: ``goal as stated`` or its joints' turns."""
    if not turns:
        return "goal as stated"
    return "goal " + ", ".join(f"{n} {k:+d} turn(s)" for n, k in turns.items())


def _result(
    problem: Problem,
    solution: Solution,
    used: list[int],
    turns: dict[str, int],
    tried: list[str],
) -> SearchResult:
    """The search's answer: the solved problem, its freedom per joint and its joints' turns."""
    robot = problem.robot
    names = robot.joint_names
    return SearchResult(
        problem=problem,
        solution=solution,
        freedom=dict(zip(names, used, strict=True)),
        full_turns={
            n: turns.get(n, 0)
            for n, j in zip(names, robot.joints, strict=True)
            if j.kind == "continuous"
        },
        tried=tried,
    )


def _distributions(
    scenario: Scenario, options: SolveOptions, planar: bool
) -> list[list[int] | None]:
    """Free coefficients per joint to try in turn (None: the scenario's ``[path] extra``)."""
    if scenario.extra is not None:
        return [None]
    n = scenario.robot.n
    spatial_continuation = not planar and options.strategy in (None, Strategy.CONTINUATION)
    return list(freedom_candidates(n, 1 if planar else 3, spatial_continuation))


def _refuse(
    scenario: Scenario,
    attempts: int,
    first_error: FreeFloatError | None,
    nearest: tuple[float, tuple[float, ...] | None, SolverError | None],
    tried: list[str],
    turns: GoalTurns,
    blocked: tuple[str, ...],
) -> NoReturn:
    """Raise the refusal of a search that found no root (``attempts`` goal offsets tried).

    ``nearest``: the best residual (rad), its axes and error; ``turns``: the first level's
    unreachable-attitude error (the turn asked from the quintic path's attitude) and the one
    that got closest; ``blocked``: the constraints that stood in the way of some level.

    Raises:
        InfeasibleError: the planar bounds refused the only goal tried.
        InputError: bad input, and no attempt got to solve.
        UnreachableAttitudeError: a level stopped on the way to its goal: the figures of the
            goal whose levels got closest (named first when several were tried).
        SolverError: otherwise, with the best residual (rad) and every attempt.
    """
    best, best_axes, best_error = nearest
    origin, closest = turns.origin, turns.closest
    continuous = any(j.kind == "continuous" for j in scenario.robot.joints)
    hint = ""
    off_axis = isinstance(first_error, InfeasibleError) and first_error.off_axis
    if continuous and not scenario.allow_full_turns and not off_axis:  # no way round helps
        hint = (
            "a continuous joint could reach its goal the other way round: try "
            "[path] allow_full_turns = true (or --allow-full-turns)"
        )
    if isinstance(first_error, InfeasibleError) and attempts == 1:
        message = f"{first_error}; {hint}" if hint else str(first_error)
        raise InfeasibleError(
            first_error.requested_deg, first_error.bounds_deg, message, first_error.off_axis
        )
    if isinstance(first_error, InfeasibleError) and best == math.inf:  # each refused up front
        raise InfeasibleError(
            first_error.requested_deg,
            first_error.bounds_deg,
            message=f"no goal tried can be reached; tried: {'; '.join(tried)}",
        )
    if isinstance(first_error, InputError) and best == math.inf:
        raise first_error
    fingers = finger_hint(scenario.robot, closest.stopped_by if closest is not None else "")
    extra = extra_hint(scenario, best_error or first_error)
    hint = "; ".join(part for part in (fingers, extra, hint) if part)
    if origin is not None and closest is not None:
        # One figure: how far along the turn asked from the quintic attitude any level got,
        # for the goal tried (as stated, or with joints' turns) whose levels got closest.
        reached = max(origin.asked - closest.best_residual, origin.reached)
        axis = ", ".join(f"{a:.3f}" for a in origin.axis)
        start = "attitude of the loop it began on" if turns.looped else "quintic path's attitude"
        goal = f"{turns.goal}: " if attempts > 1 else ""
        hint = "; ".join(part for part in (hint, reach_hint(hint)) if part)
        raise UnreachableAttitudeError(
            f"{goal}{UnreachableAttitudeError.turn_phrase(reached, origin.asked)} about this "
            f"direction (axis {axis} from the {start}); stopped by {closest.stopped_by}",
            closest.best_residual,
            reached=reached,
            asked=origin.asked,
            tried=tried,
            per_axis=closest.per_axis,
            hint=hint,
            stopped_by=closest.stopped_by,
            last_beta=closest.last_beta,
            axis=origin.axis,
            problem=closest.problem,
            blocked_by=blocked,
        )
    headline = "no path reaches the goal attitude"
    if best_error is not None and best_error.stopped_by:
        headline = best_error.headline
    raise SolverError(
        headline,
        best if math.isfinite(best) else math.nan,
        tried,
        per_axis=best_axes,
        hint=hint,
        stopped_by=best_error.stopped_by if best_error else "",
        reached_fraction=best_error.reached_fraction if best_error else 0.0,
        blocked_by=blocked,
    )
