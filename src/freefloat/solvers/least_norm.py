"""The root of least norm: ``min |beta|^2`` subject to ``h(beta) = 0``, within the constraints.

``|beta|^2`` is the path's mean squared deviation from the quintic (orthonormal basis,
docs/paths.md), so the least-norm root is the natural path among the roots of a family.

Both solvers are sequential quadratic programming with the exact Hessian of the objective
(``2 I``; the constraint's curvature left out):

- :func:`least_norm_root`, without path constraints: each step goes to the least-norm point of
  the linearised root set, ``beta+ = J^+ (J beta - h(beta))``, damped by a backtracking search on
  the merit ``|beta|^2 + mu |h(beta)|_1``;
- :func:`least_norm_root_within`, with every path constraint linearised at fixed instants
  (``g + G d <= 0``, :func:`.rows.linear_rows`): each step is the small quadratic program
  ``min |beta + d|^2`` s.t. ``J d = -h`` and the rows, solved by quadprog inside a box trust
  region, then corrected back onto the root set within the rows (:func:`nearest_root_within`'s
  least-norm steps); it is kept when that root deviates less, else the trust region halves.
  It starts from the free least-norm root brought inside the constraints when that deviates
  less than the given root, and stops once a step gains less than :data:`SETTLED`. When the
  result honours the rows but not the dense check between them, it is brought back inside by
  least-norm corrections at its tightest instants (kept when the dense check passes it), else
  those instants are added and the steps go on (at most :data:`ROUNDS` times).
- :func:`nearest_root_within`: a root just outside a constraint (between the instants of the
  rows that held it) brought inside by least-norm corrections.

Each result is polished onto ``h = 0`` by minimum-norm Newton steps. Budgets are counts.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import quadprog

from ..problem.constraints import DEFAULT_INSTANTS, Constraint
from ..problem.residual import Problem
from .newton import Polished, polish_at
from .options import SolveOptions
from .predictor import FAR_INSIDE, MARGIN
from .restore import broken_constraint
from .rows import NO_DIPS, RowCache, linear_rows, with_critical, with_dips

__all__ = [
    "CORRECTIONS",
    "FREE_ITERATIONS",
    "FREE_SETTLED",
    "ITERATIONS",
    "ROUNDS",
    "LeastNorm",
    "least_norm_root",
    "least_norm_root_within",
    "nearest_root_within",
]

#: SQP steps per round within the constraints.
ITERATIONS = 30
#: SQP steps of the least-norm root without path constraints, at most. Its steps leave out
#: the constraint's curvature and can creep along a curved root set: on the Panda servicer's
#: goal turned 10 deg about y they lower ``|beta|^2`` from 0.73 (30 steps) to 0.63 (60 steps),
#: which takes its largest excursion from 63 to 35 deg, so the next freedom level is not needed.
FREE_ITERATIONS = 60
#: The steps stop once the last :data:`SETTLE_STEPS` of them together changed ``|beta|^2`` by
#: less than this fraction of it: the steps no longer creep (the shipped dual UR5 servicer
#: after 15 steps, its root 0.15 % above the one 60 steps would reach).
FREE_SETTLED = 1e-3
SETTLE_STEPS = 5
#: Rounds of steps within the constraints, each adding the instants the last result broke.
ROUNDS = 4
#: Points one correction onto the root set within the rows checks: the one it starts from
#: and those of its least-norm steps.
CORRECTOR_STEPS = 4
#: Least-norm corrections :func:`nearest_root_within` tries.
CORRECTIONS = 3
#: First half-width of the box trust region of a step within the constraints (rad or m per
#: free coefficient) and its largest.
TRUST = 0.25
TRUST_MAX = 4.0
#: Steps within the constraints stop once one lowers ``|beta|^2`` by less than this fraction
#: (a natural path is the aim: the last per cent of deviation costs many steps where clearance
#: binds).
SETTLED = 0.01
#: A kept step may break a row by this much (its unit): the dense check of each constraint,
#: with its own tolerance, judges the result.
ROW_SLACK = 1e-6


@dataclass(frozen=True)
class LeastNorm:
    """A root of least norm found from a start, within the constraints.

    Attributes:
        beta: the root (free coefficients, rad or m), polished onto ``h = 0``.
        steps: SQP steps spent.
        honoured: whether its path honours every constraint everywhere (the dense check).
        residual: ``|h(beta)|`` (rad) as the last evaluation at ``beta`` found it, so a caller
            need not integrate the path again.
    """

    beta: np.ndarray
    steps: int
    honoured: bool
    residual: float


def least_norm_root(problem: Problem, beta: np.ndarray, options: SolveOptions) -> Polished:
    """SQP on ``min |beta|^2 s.t. h(beta) = 0`` from ``beta``, no path constraint (rad or m).

    Returns the root polished onto ``h = 0`` with its residual (rad) and Jacobian there.
    """
    r, jac = problem.residual_and_jacobian(beta)
    norms = [float(beta @ beta)]
    for _ in range(FREE_ITERATIONS):
        pinv = np.linalg.pinv(jac)
        step = pinv @ (jac @ beta - r) - beta
        multiplier = -2.0 * pinv.T @ beta  # from 2 beta + J^T lambda = 0
        mu = 2.0 * float(np.abs(multiplier).max()) + 1e-12
        merit = float(beta @ beta) + mu * float(np.abs(r).sum())
        slope = 2.0 * float(beta @ step) - mu * float(np.abs(r).sum())
        t = 1.0
        while t > 1e-3:
            trial = beta + t * step
            r_trial, jac_trial = problem.residual_and_jacobian(trial)
            value = float(trial @ trial) + mu * float(np.abs(r_trial).sum())
            if np.all(np.isfinite(r_trial)) and value <= merit + 1e-4 * t * min(slope, 0.0):
                break
            t *= 0.5
        else:
            break
        beta, r, jac = trial, r_trial, jac_trial
        norms.append(float(beta @ beta))
        if t * float(np.linalg.norm(step)) <= 1e-9 * max(1.0, float(np.linalg.norm(beta))):
            break
        if len(norms) > SETTLE_STEPS and (
            abs(norms[-1 - SETTLE_STEPS] - norms[-1]) <= FREE_SETTLED * norms[-1]
        ):
            break
    return polish_at(problem, beta, options.tolerance, evaluated=(r, jac))


def least_norm_root_within(
    problem: Problem,
    beta: np.ndarray,
    constraints: Sequence[Constraint],
    options: SolveOptions,
    free: np.ndarray | None = None,
    settled: float = SETTLED,
) -> LeastNorm:
    """The least-norm root from the root ``beta`` whose path keeps every constraint.

    Args:
        problem: the problem (not changed).
        beta: a root whose path honours the constraints (rad or m).
        constraints: the path constraints.
        options: solver settings (attitude tolerance, rad).
        free: the least-norm root without constraints, when known: brought inside them
            (:func:`nearest_root_within`), it is the start when it deviates less than ``beta``.
        settled: steps stop once one lowers ``|beta|^2`` by less than this fraction.

    A round's result that breaks a constraint between its instants (the steps press against
    a limit and its peak moves) is brought back inside by least-norm corrections
    (:func:`nearest_root_within`) and returned once the dense check passes it; when none can
    be, the free root brought inside is returned if the dense check passed it: a root that
    deviates less than ``beta`` and honours every constraint, rather than none.
    """
    active = [c for c in constraints if c.applies_to(problem.robot)]
    beta = np.asarray(beta, dtype=float)
    given = _norm(beta)
    honoured: LeastNorm | None = None  # a root below beta's norm that the dense check passed
    if free is not None:
        inside = nearest_root_within(problem, free, active, DEFAULT_INSTANTS, options)
        if inside.honoured and float(inside.beta @ inside.beta) < float(beta @ beta):
            honoured, beta = inside, inside.beta
    cache: RowCache = {}
    instants = with_critical(problem, active, beta, DEFAULT_INSTANTS)
    dips = with_dips(problem, active, beta, NO_DIPS)
    spent, residual = 0, math.nan
    for _ in range(ROUNDS):
        tolerance = options.tolerance
        point, steps = _steps(problem, active, beta, instants, cache, tolerance, settled, dips)
        spent += steps
        polished = polish_at(problem, point.beta, options.tolerance, evaluated=point.evaluated)
        beta, residual = polished.beta, float(np.linalg.norm(polished.residual))
        if not broken_constraint(problem, active, beta):
            return LeastNorm(beta, spent, True, residual)
        instants = with_critical(problem, active, beta, instants)
        dips = with_dips(problem, active, beta, dips)
        # pressed past a limit between the instants: brought back inside, least-norm
        inside = nearest_root_within(problem, beta, active, instants, options, dips)
        bar = given if honoured is None else _norm(honoured.beta)  # deviate less than these
        if inside.honoured and _norm(inside.beta) < bar:
            return replace(inside, steps=spent)
    if honoured is not None:  # the rounds pressed past a limit between their instants
        return replace(honoured, steps=spent)
    return LeastNorm(beta, spent, False, residual)


def _norm(beta: np.ndarray) -> float:
    """``|beta|^2``, the deviation from the quintic (rad^2 or m^2)."""
    return float(beta @ beta)


def nearest_root_within(
    problem: Problem,
    beta: np.ndarray,
    constraints: Sequence[Constraint],
    instants: np.ndarray,
    options: SolveOptions,
    dips: np.ndarray = NO_DIPS,
) -> LeastNorm:
    """A root near ``beta`` within the constraints, for a root just outside one between rows.

    Least-norm corrections onto the root set and inside the rows linearised at the last path
    (each polished onto ``h = 0``), the rows at ``instants`` and at the last path's tightest
    instants (and, for a constraint with its own instants, at ``dips`` and the last path's:
    :func:`.rows.with_dips`), at most :data:`CORRECTIONS` times (rad or m). ``honoured`` says
    whether the dense check of every constraint passes.
    """
    active = [c for c in constraints if c.applies_to(problem.robot)]
    beta = np.asarray(beta, dtype=float)
    residual = math.nan
    for count in range(1, CORRECTIONS + 1):
        instants = with_critical(problem, active, beta, instants)
        dips = with_dips(problem, active, beta, dips)
        cache: RowCache = {}
        point = _Point.at(problem, active, beta, instants, cache, dips=dips)
        # from the second correction on, the point is one the dense check rejected after a
        # correction: it gets a step even where its rows hold within ROW_SLACK (returned as
        # it is, it would be rejected again)
        slack = ROW_SLACK if count == 1 else 0.0
        found = _corrected(problem, active, point, instants, cache, options.tolerance, dips, slack)
        if found is None:
            return LeastNorm(beta, count, False, float(np.linalg.norm(point.r)))
        beta, residual = found.beta, float(np.linalg.norm(found.r))
        if not broken_constraint(problem, active, beta):
            return LeastNorm(beta, count, True, residual)
    return LeastNorm(beta, CORRECTIONS, False, residual)


def _steps(
    problem: Problem,
    constraints: Sequence[Constraint],
    beta: np.ndarray,
    instants: np.ndarray,
    cache: RowCache,
    tolerance: float,
    settled: float,
    dips: np.ndarray = NO_DIPS,
) -> tuple[_Point, int]:
    """Feasible trust-region SQP steps at fixed instants: (the last point, steps).

    Each step (the quadratic program of :func:`_step`) is corrected at its end by the
    least-norm step back onto the root set and inside the rows linearised there, then polished
    onto ``h = 0`` (:func:`.newton.polish`); it is kept when that path is a root within
    :data:`ROW_SLACK` of every row and deviates less. Otherwise the trust region halves. A
    start outside rows added since the last round is first corrected the same way. ``dips``:
    see :func:`.rows.linear_rows`.
    """
    here = _Point.at(problem, constraints, beta, instants, cache, dips=dips)
    if here.finite and float(here.g.max(initial=-1.0)) > ROW_SLACK:  # rows added since
        inside = _corrected(problem, constraints, here, instants, cache, tolerance, dips)
        here = here if inside is None else inside
    trust = TRUST
    steps = 0
    while steps < ITERATIONS and trust > 1e-9:
        steps += 1
        found = _step(here.beta, here, trust)
        if found is None:
            break
        d = found
        trial = _Point.at(problem, constraints, here.beta + d, instants, cache, dips=dips)
        new = _corrected(problem, constraints, trial, instants, cache, tolerance, dips)
        before = float(here.beta @ here.beta)
        if new is not None and float(new.beta @ new.beta) < before:
            here, trust = new, min(2.0 * trust, TRUST_MAX)
            if before - float(here.beta @ here.beta) <= settled * before:
                break
            continue
        trust = 0.5 * float(np.abs(d).max())
    return here, steps


def _corrected(
    problem: Problem,
    constraints: Sequence[Constraint],
    point: _Point,
    instants: np.ndarray,
    cache: RowCache,
    tolerance: float,
    dips: np.ndarray = NO_DIPS,
    slack: float = ROW_SLACK,
) -> _Point | None:
    """The root near ``point`` (evaluated at ``instants``) within the rows, or None.

    Least-norm steps onto the root set and inside the rows linearised at the last point, each
    polished onto ``h = 0``, until a point is a root within ``slack`` of every row (their
    units); at most :data:`CORRECTOR_STEPS` points are checked (the given one and its steps').
    """
    for count in range(1, CORRECTOR_STEPS + 1):
        if not point.finite:
            return None
        if np.linalg.norm(point.r) < tolerance and point.g.max(initial=-1.0) <= slack:
            return point
        if count == CORRECTOR_STEPS:
            return None  # a further step would not be checked
        correction = _step(np.zeros_like(point.beta), point, TRUST_MAX)
        if correction is None:
            return None
        found = polish_at(problem, point.beta + correction, tolerance)
        if not np.all(np.isfinite(found.beta)):
            return None
        evaluated = (found.residual, found.jacobian)
        point = _Point.at(problem, constraints, found.beta, instants, cache, evaluated, dips)
    return None


@dataclass(frozen=True)
class _Point:
    """An SQP iterate: ``beta``, the residual (rad) and rows (their units) with Jacobians."""

    beta: np.ndarray
    r: np.ndarray
    jac: np.ndarray
    g: np.ndarray
    g_mat: np.ndarray

    @classmethod
    def at(
        cls,
        problem: Problem,
        constraints: Sequence[Constraint],
        beta: np.ndarray,
        instants: np.ndarray,
        cache: RowCache,
        evaluated: tuple[np.ndarray, np.ndarray] | None = None,
        dips: np.ndarray = NO_DIPS,
    ) -> _Point:
        """The point at ``beta``; ``evaluated``: ``(h, dh/dbeta)`` there when known."""
        r, jac = evaluated if evaluated is not None else problem.residual_and_jacobian(beta)
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(jac))):
            return cls(beta, r, jac, np.full(1, np.inf), np.zeros((1, len(beta))))
        g, g_mat = linear_rows(problem, constraints, beta, instants, cache, dips)
        return cls(beta, r, jac, g, g_mat)

    @property
    def evaluated(self) -> tuple[np.ndarray, np.ndarray]:
        """``(h, dh/dbeta)`` at ``beta`` (rad, rad per unit of beta)."""
        return self.r, self.jac

    @property
    def finite(self) -> bool:
        return bool(np.all(np.isfinite(self.r)) and np.all(np.isfinite(self.g)))


def _step(centre: np.ndarray, point: _Point, trust: float) -> np.ndarray | None:
    """The step ``d`` from ``point``, or None if no step meets the rows.

    ``d`` minimises ``|centre + d|^2`` with ``J d = -r``, ``g + G d <= -MARGIN`` and
    ``|d|_inf <= trust`` (rad or m): ``centre`` is the point itself for a step towards the
    least norm, zero for the least-norm correction.
    """
    n = len(centre)
    near = point.g > FAR_INSIDE
    eye = np.eye(n)
    c_mat = np.vstack([point.jac, -point.g_mat[near], eye, -eye]).T
    b = np.concatenate([-point.r, point.g[near] + MARGIN, np.full(2 * n, -trust)])
    try:
        solution = quadprog.solve_qp(eye, -centre, c_mat, b, len(point.r))
    except ValueError:
        return None
    return np.asarray(solution[0])
