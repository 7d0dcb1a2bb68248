"""The root that minimises an objective, within every constraint (docs/method.md section 13).

Starting from a root ``beta_0`` (``h(beta_0) = 0``), SciPy's SLSQP minimises the objective
subject to ``h(beta) = 0`` (exact Jacobian) and the path constraints.

Scaling: SLSQP works in coordinates ``z`` with ``beta = beta_0 + S z``, in which the objective
divided by its value at ``beta_0`` has a Hessian close to the identity. ``S`` comes from the
objective's Gauss-Newton factor (weighted torque derivatives for ``min_effort``), regularised
by the basis polynomials' second derivatives (alone for objectives without one). Without it a
Panda's wrist joints, whose torques are tiny, leave directions almost flat and SLSQP crawls.

Constraints: the first run imposes the affine constraints (cheap rows) and those ``beta_0``
breaks; a costly constraint that is slack there (clearance far from its margin, say) is imposed
only if a result breaks it, and so is an affine duration-scaled limit whose peaks at ``beta_0``
stay below :data:`FAR_FRACTION` of its limits (joint rates, typically: their hundreds of rows
would only slow SLSQP's subproblems down). Rows sit at fixed instants during one run:
:data:`COARSE_INSTANTS` evenly spaced ones and those where the path is tightest (each joint's
extremes, say), and are held :data:`BACKOFF` tolerances inside the limit, so that a limit
reached at a row is not broken between rows by more than its tolerance. When a result still
breaks an imposed constraint, its tightest instants are added and the nearest root within
them is tried (least-norm corrections, :func:`.least_norm.nearest_root_within`); if that
fails, the run is repeated from there (at most :data:`ROUNDS` runs). A run SLSQP ends without
converging falls back on the best points it met within every row (:mod:`.iterates`).

The result is polished back onto ``h = 0`` by minimum-norm Newton steps and kept only if it
honours every constraint and lowers the objective (or ``beta_0`` broke a constraint);
otherwise ``beta_0`` stands. Budgets are counts: SLSQP's iterations per run and
:data:`MAX_EVALUATIONS` objective evaluations per call.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from .._blas import one_blas_thread
from ..problem.constraints import Constraint, DurationScaledLimit
from ..problem.objectives import Objective
from ..problem.residual import Problem
from .iterates import Journal
from .least_norm import nearest_root_within
from .newton import polish
from .options import SolveOptions
from .restore import broken_constraint
from .rows import tightest_instants
from .scaled import BudgetSpentError, Evaluations, scaled_coordinates
from .sqp import Function, constraint_functions

__all__ = ["FALLBACK_NOTE", "ROUNDS", "Optimised", "optimise"]

#: Objective evaluations one call may spend by default (SLSQP's line searches included);
#: beyond its budget the start stands.
MAX_EVALUATIONS = 400
#: Rows are held this many of their constraint's tolerances inside the limit.
BACKOFF = 1000.0
#: Evenly spaced normalised instants of the rows, to which the path's tightest are added.
COARSE_INSTANTS = 25
#: An affine duration-scaled limit whose peaks at the start stay below this fraction of their
#: limits is left out of the first run, like a costly constraint slack at the start.
FAR_FRACTION = 0.5
#: SLSQP runs at most, each adding what the last one broke: a left-out constraint, or the
#: instants where it broke an imposed one.
ROUNDS = 8
#: Points within the rows a run that did not converge is polished from, at most
#: (:mod:`.iterates`).
FALLBACKS = 3
#: How a result taken from a run's fallbacks is recorded (the plan's objective levels).
FALLBACK_NOTE = "the best point within its rows of an SLSQP run that did not converge"


@dataclass(frozen=True)
class Optimised:
    """Where the objective's minimisation ended.

    Attributes:
        beta: the root kept (``beta_0`` when nothing better was found).
        value: the objective there (its unit, at the problem's duration).
        start_value: the objective at ``beta_0`` (the same).
        iterations: SLSQP iterations.
        improved: whether ``beta`` differs from ``beta_0``.
        note: why ``beta_0`` was kept, when it was; how ``beta`` was found, when it is the
            best point of a run that did not converge (:func:`_fallback_kept`).
        evaluations: objective evaluations spent.
    """

    beta: np.ndarray
    value: float
    start_value: float
    iterations: int
    improved: bool
    note: str = ""
    evaluations: int = 0


def _tightest(
    problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray, instants: np.ndarray
) -> np.ndarray:
    """``instants`` with the normalised instants where the path at ``beta`` is tightest."""
    extra = tightest_instants(problem, constraints, beta)
    return np.unique(np.clip(np.concatenate([instants, extra]), 0.0, 1.0))


def _imposed_first(problem: Problem, constraint: Constraint, beta: np.ndarray) -> bool:
    """Whether the first run imposes a constraint: affine and not far, or broken at ``beta``."""
    if constraint.affine and not _far(problem, constraint, beta):
        return True
    return bool(broken_constraint(problem, [constraint], beta))


def _placed(active: Sequence[Constraint], imposed: Sequence[Constraint]) -> list[Constraint]:
    """The constraints whose tightest instants carry rows.

    Every affine one, imposed or not (so that the rows of the imposed ones do not depend on
    which are left out), and the imposed others.
    """
    return [c for c in active if c.affine or c in imposed]


def _far(problem: Problem, constraint: Constraint, beta: np.ndarray) -> bool:
    """Whether a duration-scaled limit is far from binding on the path at ``beta``.

    Far: every peak (joint rates, say) is below :data:`FAR_FRACTION` of its limit. Its rows
    are then left out of the first run.
    """
    if not isinstance(constraint, DurationScaledLimit):
        return False
    peak = constraint.worst(problem.robot, problem.polynomials(beta))
    return peak is not None and peak.fraction < FAR_FRACTION


def _fallback_kept(
    problem: Problem,
    constraints: Sequence[Constraint],
    imposed: Sequence[Constraint],
    instants: np.ndarray,
    run: _Run,
    options: SolveOptions,
    lower: Callable[[np.ndarray], bool],
) -> np.ndarray | None:
    """The first of a run's fallbacks, polished, within every constraint and ``lower``.

    One that breaks a constraint between the rows' instants is first brought inside at its
    tightest instants, as a run's own result is (:func:`_inside`; rad or m).
    """
    active = [c for c in constraints if c.applies_to(problem.robot)]
    for point in run.fallbacks:
        beta = _polished(problem, point, options.tolerance)
        if isinstance(beta, str):
            continue
        if broken_constraint(problem, constraints, beta):
            at = _tightest(problem, _placed(active, imposed), beta, instants)
            inside = _inside(problem, beta, imposed, at, options)
            if inside is None or broken_constraint(problem, constraints, inside):
                continue
            beta = inside
        if lower(beta):
            return beta
    return None


def _inside(
    problem: Problem,
    beta: np.ndarray,
    imposed: Sequence[Constraint],
    instants: np.ndarray,
    options: SolveOptions,
) -> np.ndarray | None:
    """:func:`.least_norm.nearest_root_within`'s root if honoured, else None (rad or m)."""
    try:
        inside = nearest_root_within(problem, beta, imposed, instants, options)
    except (np.linalg.LinAlgError, FloatingPointError, ValueError):
        return None
    return inside.beta if inside.honoured else None


def _reaches(problem: Problem, constraint: Constraint, beta: np.ndarray) -> bool:
    """Whether a constraint left out of a run must be imposed after it.

    A costly one: when the path at ``beta`` breaks it. An affine one: when the path comes
    within its rows' back-off of the limit, so that a result kept without its rows honours
    every row it would have had (they are all slack there).
    """
    if not constraint.affine:
        return bool(broken_constraint(problem, [constraint], beta))
    return constraint.violation(problem, beta).value > -BACKOFF * constraint.tolerance


def optimise(
    problem: Problem,
    beta: np.ndarray,
    objective: Objective,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    max_iterations: int = 200,
    max_evaluations: int = MAX_EVALUATIONS,
) -> Optimised:
    """Minimise ``objective`` over the roots, from the root ``beta`` (see the module docstring).

    Args:
        problem: the problem (not changed).
        beta: a root (within the constraints, or a start that breaks one: the result then
            honours them or ``beta`` stands).
        objective: what to minimise.
        constraints: path constraints to keep.
        options: solver settings (attitude tolerance, rad).
        max_iterations: SLSQP iteration budget per run.
        max_evaluations: objective evaluation budget of the call.
    """
    beta0 = np.asarray(beta, dtype=float)
    # The objective scales as T^-p: minimise it at T = 1 s, so that the path found does not
    # depend on the duration to the last bit (the constraints keep the real duration).
    unit = problem.with_duration(1.0)
    start = objective.evaluate(unit, beta0)
    at_t = problem.duration**-objective.duration_power  # value at T from value at 1 s
    start_value = start.value * at_t
    if problem.n_free == 0:
        return Optimised(beta0, start_value, start_value, 0, False, "no free coefficients")
    scale = start.value if start.value > 0 else 1.0
    s_mat = scaled_coordinates(unit, objective, beta0, scale)

    ev = Evaluations(problem, unit, objective, beta0, s_mat, scale, max_evaluations)
    ev.start = start.value / scale  # the start's value, as the runs see it

    active = [c for c in constraints if c.applies_to(problem.robot)]
    imposed = [c for c in active if _imposed_first(problem, c, beta0)]
    coarse = np.linspace(0.0, 1.0, COARSE_INSTANTS)
    instants = _tightest(problem, _placed(active, imposed), beta0, coarse)
    z = np.zeros(problem.n_free)
    iterations = 0

    def kept(note: str) -> Optimised:
        """The start stands (``note`` says why)."""
        return Optimised(beta0, start_value, start_value, iterations, False, note, ev.spent)

    def fallback(run: _Run) -> np.ndarray | None:
        """The best point a run that did not converge met, kept (:func:`_fallback_kept`)."""
        lower = lambda beta: bool(objective.evaluate(unit, beta).value < start.value)  # noqa: E731
        return _fallback_kept(problem, constraints, imposed, instants, run, options, lower)

    how = ""  # how the result was found, when not as a run's own end
    for _ in range(ROUNDS):
        run = _run(problem, ev, imposed, instants, z, max_iterations, options.tolerance)
        iterations += run.iterations
        if run.candidate is None:
            found = fallback(run)
            if found is None:
                return kept(run.note)
            candidate, how = found, _fallback_note(run)
            break
        candidate, z = run.candidate, run.z
        broken = broken_constraint(problem, constraints, candidate)
        if not broken:
            break
        missing = [c for c in active if c not in imposed and _reaches(problem, c, candidate)]
        if missing:  # a constraint left out because it was slack at the start now binds:
            imposed += missing  # impose it, from the start (whose path honours every one)
            z = np.zeros(problem.n_free)
            continue
        # Rows hold at the instants but not between them (or the run stopped short of them):
        # add the path's tightest instants and first try the nearest root within them.
        instants = _tightest(problem, _placed(active, imposed), candidate, instants)
        inside = _inside(problem, candidate, imposed, instants, options)
        if inside is not None and not broken_constraint(problem, constraints, inside):
            candidate = inside
            break
        if not run.success:  # no point within the imposed rows: more instants will not help
            found = fallback(run)
            if found is None:
                return kept(f"the minimised path breaks {broken}")
            candidate, how = found, _fallback_note(run)  # the best it met within its rows
            break
    else:
        return kept(f"the minimised path breaks {broken}")
    value = objective.evaluate(unit, candidate).value
    if not value < start.value and not broken_constraint(problem, constraints, beta0):
        found = fallback(run)  # a run that did not converge may have met a lower point
        if found is None:
            return kept("no lower value")
        candidate, how = found, _fallback_note(run)
        value = objective.evaluate(unit, found).value
    return Optimised(candidate, value * at_t, start_value, iterations, True, how, ev.spent)


@dataclass(frozen=True)
class _Run:
    """One SLSQP run (:func:`_run`).

    Attributes:
        candidate: its end point polished onto the goal (rad or m), None when it has none.
        z: its end point in scaled coordinates (unitless: ``beta = beta0 + S z``).
        iterations: SLSQP iterations spent.
        success: whether SLSQP says it converged.
        note: why there is no candidate ("" when there is one).
        stopped: why SLSQP stopped without converging ("" when it converged).
        fallbacks: when SLSQP did not converge (or spent the evaluation budget), the points
            of lowest objective it met within every row, below the start's (rad or m, not
            polished), best first.
    """

    candidate: np.ndarray | None
    z: np.ndarray
    iterations: int
    success: bool = False
    note: str = ""
    fallbacks: tuple[np.ndarray, ...] = ()
    stopped: str = ""


def _run(
    problem: Problem,
    ev: Evaluations,
    imposed: Sequence[Constraint],
    instants: np.ndarray,
    z: np.ndarray,
    max_iterations: int,
    tolerance: float,
) -> _Run:
    """SLSQP from ``z`` within the ``imposed`` rows at ``instants``, polished (rad)."""
    from scipy.optimize import minimize  # imported when first used

    journal = Journal(0)
    cons = [{"type": "eq", "fun": ev.h, "jac": ev.dh}]
    cons += _inequalities(problem, imposed, instants, ev, journal)
    try:
        with np.errstate(all="ignore"), one_blas_thread():
            result = minimize(
                journal.objective_of(ev.fun),
                z,
                jac=ev.grad,
                method="SLSQP",
                constraints=cons,
                options={"ftol": 1e-12, "maxiter": int(max_iterations)},
            )
    except BudgetSpentError:
        note = f"evaluation budget ({ev.budget}) spent"
        return _Run(None, z, 0, note=note, fallbacks=_fallbacks(ev, journal), stopped=note)
    nit, z = int(result.nit), np.asarray(result.x, dtype=float)
    fallbacks = () if result.success else _fallbacks(ev, journal)
    stopped = "" if result.success else str(result.message)
    candidate = _polished(problem, ev.to_beta(z), tolerance)
    if isinstance(candidate, str):
        return _Run(None, z, nit, note=candidate, fallbacks=fallbacks, stopped=stopped)
    return _Run(candidate, z, nit, bool(result.success), fallbacks=fallbacks, stopped=stopped)


def _fallback_note(run: _Run) -> str:
    """The record of a result taken from a run's fallbacks (:class:`Optimised` ``note``)."""
    return f"{FALLBACK_NOTE} ({run.stopped})"


def _polished(problem: Problem, beta: np.ndarray, tolerance: float) -> np.ndarray | str:
    """``beta`` polished onto the goal (rad or m), or why it cannot be."""
    if not np.all(np.isfinite(beta)):
        return "diverged"
    try:
        beta, vector = polish(problem, beta, tolerance)
    except (np.linalg.LinAlgError, FloatingPointError, ValueError):
        return "polish failed"
    if float(np.linalg.norm(vector)) >= tolerance:
        return "left the goal"
    return beta


def _fallbacks(ev: Evaluations, journal: Journal) -> tuple[np.ndarray, ...]:
    """The :data:`FALLBACKS` best points (below the start's) a run met within every row."""
    return tuple(ev.to_beta(z) for z in journal.best(ev.start, FALLBACKS))


def _inequalities(
    problem: Problem,
    imposed: Sequence[Constraint],
    instants: np.ndarray,
    ev: Evaluations,
    journal: Journal,
) -> list[dict[str, object]]:
    """SLSQP inequality rows of the imposed constraints at the instants, backed off a little.

    Each function's values are noted in ``journal`` (its ``rows`` set to their number).
    """
    cons: list[dict[str, object]] = []
    for constraint in imposed:
        backoff = BACKOFF * constraint.tolerance
        for g, dg in constraint_functions(problem, [constraint], instants):

            def values(z: np.ndarray, g: Function = g, b: float = backoff) -> np.ndarray:
                return g(ev.to_beta(z)) - b

            cons.append(
                {
                    "type": "ineq",
                    "fun": journal.inequality(len(cons), values),
                    "jac": lambda z, dg=dg: dg(ev.to_beta(z)) @ ev.s_mat,
                }
            )
    journal.rows = len(cons)
    return cons
