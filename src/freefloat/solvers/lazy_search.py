"""The search as ``plan`` runs it: the costly and the lazy constraints imposed only where needed.

The search first runs within the affine constraints alone (joint limits: cheap rows), and
imposes the costly ones (clearance) only when the path it finds breaks one
(:func:`search_lazily`); the lazy ones (velocity and effort limits, checked on the result)
only when the path breaks them. A path that breaks clearance is first brought inside by
least-norm corrections (the root nearest it within every constraint); only when that fails
does the search run again with clearance imposed. A goal the cheap search stops short of, on
a path the costly constraints do not bind, is refused without a second search. When only the
velocity or effort limits stood in the way, the refusal names the shortest duration at which
the path found without them respects them (another path may at a shorter one).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..errors import FreeFloatError, SolverError, UnreachableAttitudeError
from ..problem.build import problem_from_scenario
from ..problem.constraints import DEFAULT_INSTANTS, Constraint, DurationScaledLimit, LimitPeak
from ..problem.residual import Problem
from ..problem.scenario import Scenario
from .certify import certify
from .least_norm import nearest_root_within
from .options import Root, SolveOptions
from .restore import broken_constraint, broken_rows_first, first_broken
from .search import SearchResult, search

__all__ = ["broken_by", "explain_lazy_breaks", "search_lazily"]


def broken_by(found: SearchResult, constraints: Sequence[Constraint]) -> str:
    """``"name (where)"`` of the first constraint the path found breaks, or ``""``."""
    return broken_constraint(found.problem, constraints, found.solution.beta)


def explain_lazy_breaks(found: SearchResult, constraints: Sequence[Constraint]) -> None:
    """Refuse a path that still breaks a lazy constraint, naming the shortest duration if it can.

    The others were imposed by the search and kept by the minimisation: not checked again.
    """
    broken = first_broken(found.problem, constraints, found.solution.beta)
    if broken is None:
        return
    path = found.problem.polynomials(found.solution.beta)
    for limit in constraints:
        if isinstance(limit, DurationScaledLimit) and limit.name == broken.name:
            peak = limit.worst(found.problem.robot, path)
            if peak is not None and peak.fraction > 1.0:
                raise limit.error(peak)
    raise SolverError(f"the path found breaks {broken}", 0.0, blocked_by=(broken.name,))


def search_lazily(
    scenario: Scenario,
    options: SolveOptions,
    constraints: list[Constraint],
    keep_broken: bool = False,
) -> tuple[SearchResult, list[Constraint]]:
    """Search without the lazy constraints, then with them if the path found breaks one.

    Returns the result and the constraints the solvers imposed. With ``keep_broken``, when no
    path within the lazy constraints is found, the first path (which breaks them) is returned
    with the constraints it honours, for an objective to improve on.
    """
    eager = [c for c in constraints if not c.lazy]
    lazy = [c for c in constraints if c.lazy]
    try:
        proxied = _search_proxy_first(scenario, options, eager)
        found = proxied.found
        broken = bool(lazy) and bool(broken_by(found, lazy))
        if broken and proxied.brought_inside:  # as without that path: clearance imposed
            found = search(scenario, options, eager)
            broken = bool(broken_by(found, lazy))
    except SolverError as exc:
        _explain_duration_limits(scenario, options, constraints, exc)
        raise
    if not broken:  # the search honoured the eager ones
        return found, eager
    try:
        return search(scenario, options, constraints), constraints
    except SolverError as exc:
        if keep_broken:
            return found, eager
        _explain_duration_limits(scenario, options, constraints, exc)
        raise


@dataclass(frozen=True)
class _Proxied:
    """What :func:`_search_proxy_first` found.

    Attributes:
        found: the search's result, within every eager constraint.
        brought_inside: whether it is the cheap search's path brought inside the costly
            constraints (:func:`_brought_inside`) rather than a search's own.
    """

    found: SearchResult
    brought_inside: bool = False


def _search_proxy_first(
    scenario: Scenario, options: SolveOptions, eager: list[Constraint]
) -> _Proxied:
    """The search within the affine constraints alone, kept when its path honours the others.

    The costly constraints (clearance) are imposed only where they bind: when the path found
    within the cheap ones (joint limits) breaks one, it is brought inside them by least-norm
    corrections (:func:`_brought_inside`), and when that fails, or the cheap search fails, the
    search runs again with every constraint. Except when the cheap search stopped short of
    the goal on a path that honours the costly ones too: they do not bind where it stopped,
    and the goal is refused at once (:func:`_out_of_reach`). Both searches are local, so this
    is not a proof that the search with every constraint would stop there too; it stopped
    there on every goal compared (docs/clearance.md).
    """
    cheap = [c for c in eager if c.affine]
    if len(cheap) == len(eager):
        return _Proxied(search(scenario, options, eager))
    costly = [c for c in eager if not c.affine]
    try:
        found = search(scenario, options, cheap)
    except UnreachableAttitudeError as exc:
        if _stopped_within(exc, costly):
            raise _out_of_reach(exc, costly) from None
        return _Proxied(search(scenario, options, eager))
    except SolverError:
        return _Proxied(search(scenario, options, eager))
    # the dense check, not the rows first: the path is clear on most requests, and then the
    # rows would be measured for nothing (a correction measures them anyway)
    broken = broken_constraint(found.problem, eager, found.solution.beta)
    if not broken:
        return _Proxied(found)
    inside = _brought_inside(found, eager, broken, options)
    if inside is not None:
        return _Proxied(inside, brought_inside=True)
    return _Proxied(search(scenario, options, eager))


def _brought_inside(
    found: SearchResult, eager: Sequence[Constraint], broken: str, options: SolveOptions
) -> SearchResult | None:
    """The cheap search's root brought inside the eager constraints it breaks, or None.

    Least-norm corrections onto the root set within every eager constraint's rows
    (:func:`.least_norm.nearest_root_within`): a path that dips into the clearance margin
    becomes the root nearest it that keeps the margin, for a few corrections instead of a
    second search. Kept only when its integration is certified on its own grid and the dense
    check of every eager constraint passes (the corrections' own check, made again only when
    certifying polished the root on a finer grid); None otherwise, a numerical failure
    included (the search with every eager constraint then runs).
    """
    problem = found.problem.with_steps(found.solution.steps)
    before = problem.evaluations
    try:
        inside = nearest_root_within(problem, found.solution.beta, eager, DEFAULT_INSTANTS, options)
        if not inside.honoured:
            return None
        checked = certify(problem, inside.beta, inside.residual, options.tolerance)
    except (np.linalg.LinAlgError, FloatingPointError, ValueError):  # the search decides
        return None
    if not checked.passed:
        return None
    moved = not np.array_equal(checked.beta, inside.beta)  # polished on a finer grid
    if moved and broken_constraint(checked.problem, eager, checked.beta):
        return None
    root = Root(checked.beta, checked.residual, checked.problem.path_length(checked.beta))
    solution = replace(
        found.solution,
        beta=checked.beta,
        residual=checked.residual,
        evaluations=found.solution.evaluations + problem.evaluations - before,
        roots=(root,),
        integration_error=checked.integration_error,
        steps=checked.problem.steps,
    )
    note = (
        f"the path found within the joint limits broke {broken}: brought inside by "
        f"{inside.steps} least-norm correction{'s' if inside.steps > 1 else ''}"
    )
    return replace(found, problem=checked.problem, solution=solution, tried=[*found.tried, note])


def _stopped_within(error: UnreachableAttitudeError, costly: Sequence[Constraint]) -> bool:
    """Whether the path a search stopped on (``error``'s) honours the ``costly`` constraints."""
    if not isinstance(error.problem, Problem) or error.last_beta is None:
        return False
    return not broken_rows_first(error.problem, costly, np.asarray(error.last_beta, dtype=float))


def _out_of_reach(
    error: UnreachableAttitudeError, left_out: Sequence[Constraint]
) -> UnreachableAttitudeError:
    """The refusal of the search within the cheap constraints, naming those left out.

    Every figure and the constraints that stood in the way (``blocked_by``) are kept.
    """
    names = ", ".join(c.name for c in left_out)
    return error.with_headline(
        f"{error.headline}; the search without {names} stopped on a path that honours {names} too"
    )


def _explain_duration_limits(
    scenario: Scenario,
    options: SolveOptions,
    constraints: list[Constraint],
    error: SolverError,
) -> None:
    """Name the shortest duration when only the velocity or effort limits stood in the way.

    Raises :class:`VelocityLimitError` or :class:`EffortLimitError` (the one that needs the
    longer duration), with the shortest duration at which the path found without these
    limits respects both. Rates scale as 1/T and torques as 1/T^2, and the path shape does
    not depend on T, so that duration is exact for that path (a sufficient one: another path
    may respect the limits at a shorter one).
    """
    timed = [c for c in constraints if isinstance(c, DurationScaledLimit)]
    relaxed = [c for c in constraints if c not in timed]
    if not any(c.name in error.blocked_by for c in timed):
        return  # the velocity and effort limits did not stand in the way
    try:
        found = search(scenario, options, relaxed)
    except SolverError:  # no path without them either: is the duration itself too short?
        _refuse_below_floor(scenario, timed, error)
        return
    path = found.problem.polynomials(found.solution.beta)
    worst: tuple[DurationScaledLimit, LimitPeak] | None = None
    for limit in timed:
        peak = limit.worst(scenario.robot, path)
        if peak is None or peak.fraction <= 1.0:
            continue
        if worst is None or peak.shortest_duration > worst[1].shortest_duration:
            worst = (limit, peak)
    if worst is not None:
        found_error = worst[0].error(worst[1])
        if isinstance(error, UnreachableAttitudeError):  # how far the search within them got
            found_error = found_error.within_reach(error.reached, error.asked)
        raise found_error from error


def _refuse_below_floor(
    scenario: Scenario, timed: Sequence[DurationScaledLimit], error: SolverError
) -> None:
    """Raise ``error`` saying so when no path at all keeps the velocity limits in its duration.

    The floor is path-free: each joint's travel at its velocity limit (s; read off the plain
    quintic path, the same for every path between the same joints). A refusal of the attitude
    at a duration below it would point the user at the goal attitude instead of the duration.
    """
    rates = [limit for limit in timed if limit.power == 1]  # torques have no such floor
    if not rates or not (type(error) is SolverError or isinstance(error, UnreachableAttitudeError)):
        return
    try:
        quintic = problem_from_scenario(scenario, check_bounds=False)
    except FreeFloatError:  # the refusal stands as it is
        return
    path = quintic.polynomials(np.zeros(quintic.n_free))
    floor = 0.0
    for limit in rates:
        peak = limit.worst(scenario.robot, path)
        if peak is not None:
            floor = max(floor, peak.least_duration)
    if scenario.duration < floor:
        raise error.with_hint(
            f"no path keeps every velocity limit in under {floor:.4g} s (each joint's travel "
            f"at its limit), longer than the {scenario.duration:.4g} s asked: lengthen the "
            "duration first"
        ) from error
