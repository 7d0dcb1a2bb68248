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
fails, the run is repeated from there (at most :data:`ROUNDS` runs).

The result is polished back onto ``h = 0`` by minimum-norm Newton steps and kept only if it
honours every constraint and lowers the objective (or ``beta_0`` broke a constraint);
otherwise ``beta_0`` stands. Budgets are counts: SLSQP's iterations per run and
:data:`MAX_EVALUATIONS` objective evaluations per call.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np

from .._blas import one_blas_thread
from ..problem.constraints import Constraint, DurationScaledLimit
from ..problem.objectives import Objective, gauss_legendre
from ..problem.residual import Problem
from ..progress import heartbeat
from .least_norm import nearest_root_within
from .newton import polish
from .options import SolveOptions
from .restore import broken_constraint
from .rows import tightest_instants
from .sqp import constraint_functions

__all__ = ["ROUNDS", "Optimised", "optimise"]

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


@dataclass(frozen=True)
class Optimised:
    """Where the objective's minimisation ended.

    Attributes:
        beta: the root kept (``beta_0`` when nothing better was found).
        value: the objective there (its unit, at the problem's duration).
        start_value: the objective at ``beta_0`` (the same).
        iterations: SLSQP iterations.
        improved: whether ``beta`` differs from ``beta_0``.
        note: why ``beta_0`` was kept, when it was.
        evaluations: objective evaluations spent.
    """

    beta: np.ndarray
    value: float
    start_value: float
    iterations: int
    improved: bool
    note: str = ""
    evaluations: int = 0


class _BudgetSpentError(Exception):
    """The objective evaluation budget of one call is spent."""


def _tightest(
    problem: Problem, constraints: Sequence[Constraint], beta: np.ndarray, instants: np.ndarray
) -> np.ndarray:
    """``instants`` with the normalised instants where the path at ``beta`` is tightest."""
    extra = tightest_instants(problem, constraints, beta)
    return np.unique(np.clip(np.concatenate([instants, extra]), 0.0, 1.0))


def scaled_coordinates(
    problem: Problem, objective: Objective, beta: np.ndarray, value: float
) -> np.ndarray:
    """``S`` in which the objective divided by ``value`` has a Hessian near the identity.

    With the objective's metric ``M`` at ``beta`` (its Gauss-Newton factor: ``2 M^T M`` is
    close to the Hessian), ``S^T (M^T M + r^2 A^T A) S = value / 2 I``, where ``A`` is the
    weighted second-derivative map of the basis (exact Gauss-Legendre integration) and ``r`` a
    small multiple that keeps the matrix positive definite where ``M`` is rank deficient.
    Without a metric (``min_length``), ``S^T A^T A S`` is ``value / |A|^2 I``: the acceleration
    norm, scaled to the value. Built from the QR factors of the stacked matrices, not from a
    Cholesky factor of the product: that squares the condition number of a high-degree
    monomial basis.
    """
    s, w = gauss_legendre(max(problem.family.degrees))
    dqss = problem.family.affine_samples(s).dqss
    accel = (np.sqrt(w)[:, None, None] * dqss).reshape(-1, problem.n_free)
    metric = objective.metric(problem, beta)
    if metric is None:
        stacked = accel * np.sqrt(max(value, 1e-300) / max(_norm2(accel), 1e-300))
    else:
        weight = 1e-3 * np.sqrt(_norm2(metric) / max(_norm2(accel), 1e-300))
        stacked = np.vstack([metric, weight * accel]) / np.sqrt(max(0.5 * value, 1e-300))
    r = np.linalg.qr(stacked, mode="r")
    return np.linalg.solve(r, np.eye(problem.n_free))


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


def _reaches(problem: Problem, constraint: Constraint, beta: np.ndarray) -> bool:
    """Whether a constraint left out of a run must be imposed after it.

    A costly one: when the path at ``beta`` breaks it. An affine one: when the path comes
    within its rows' back-off of the limit, so that a result kept without its rows honours
    every row it would have had (they are all slack there).
    """
    if not constraint.affine:
        return bool(broken_constraint(problem, [constraint], beta))
    return constraint.violation(problem, beta).value > -BACKOFF * constraint.tolerance


def _norm2(matrix: np.ndarray) -> float:
    """Squared Frobenius norm."""
    return float(np.sum(matrix * matrix))


def _where(name: str, spent: int, budget: int) -> str:
    """A progress line of the minimisation (evaluations are counts)."""
    return f"minimise {name}: {spent} of at most {budget} objective evaluations at this level"


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

    ev = _Evaluations(problem, unit, objective, beta0, s_mat, scale, max_evaluations)

    active = [c for c in constraints if c.applies_to(problem.robot)]
    imposed = [c for c in active if _imposed_first(problem, c, beta0)]
    coarse = np.linspace(0.0, 1.0, COARSE_INSTANTS)
    instants = _tightest(problem, _placed(active, imposed), beta0, coarse)
    z = np.zeros(problem.n_free)
    iterations = 0

    def kept(note: str) -> Optimised:
        """The start stands (``note`` says why)."""
        return Optimised(beta0, start_value, start_value, iterations, False, note, ev.spent)

    for _ in range(ROUNDS):
        run = _run(problem, ev, imposed, instants, z, max_iterations, options.tolerance)
        iterations += run.iterations
        if run.candidate is None:
            return kept(run.note)
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
        inside = nearest_root_within(problem, candidate, imposed, instants, options)
        if inside.honoured and not broken_constraint(problem, constraints, inside.beta):
            candidate = inside.beta
            break
        if not run.success:  # no point within the imposed rows: more instants will not help
            return kept(f"breaks {broken}")
    else:
        return kept(f"breaks {broken}")
    value = objective.evaluate(unit, candidate).value
    if not value < start.value and not broken_constraint(problem, constraints, beta0):
        return kept("no lower value")
    return Optimised(candidate, value * at_t, start_value, iterations, True, "", ev.spent)


@dataclass(frozen=True)
class _Run:
    """One SLSQP run (:func:`_run`).

    Attributes:
        candidate: its end point polished onto the goal (rad or m), None when it has none.
        z: its end point in scaled coordinates (unitless: ``beta = beta0 + S z``).
        iterations: SLSQP iterations spent.
        success: whether SLSQP says it converged.
        note: why there is no candidate ("" when there is one).
    """

    candidate: np.ndarray | None
    z: np.ndarray
    iterations: int
    success: bool = False
    note: str = ""


def _run(
    problem: Problem,
    ev: _Evaluations,
    imposed: Sequence[Constraint],
    instants: np.ndarray,
    z: np.ndarray,
    max_iterations: int,
    tolerance: float,
) -> _Run:
    """SLSQP from ``z`` within the ``imposed`` rows at ``instants``, polished (rad)."""
    from scipy.optimize import minimize  # imported when first used

    cons = [{"type": "eq", "fun": ev.h, "jac": ev.dh}]
    cons += _inequalities(problem, imposed, instants, ev)
    try:
        with np.errstate(all="ignore"), one_blas_thread():
            result = minimize(
                ev.fun,
                z,
                jac=ev.grad,
                method="SLSQP",
                constraints=cons,
                options={"ftol": 1e-12, "maxiter": int(max_iterations)},
            )
    except _BudgetSpentError:
        return _Run(None, z, 0, note=f"evaluation budget ({ev.budget}) spent")
    nit, z = int(result.nit), np.asarray(result.x, dtype=float)
    candidate = ev.to_beta(z)
    if not np.all(np.isfinite(candidate)):
        return _Run(None, z, nit, note="diverged")
    try:
        candidate, vector = polish(problem, candidate, tolerance)
    except (np.linalg.LinAlgError, FloatingPointError, ValueError):
        return _Run(None, z, nit, note="polish failed")
    if float(np.linalg.norm(vector)) >= tolerance:
        return _Run(None, z, nit, note="left the goal")
    return _Run(candidate, z, nit, bool(result.success))


class _Evaluations:
    """The objective and the attitude residual in scaled coordinates ``z``.

    ``beta = beta0 + S z``; the objective at T = 1 s divided by ``scale``. Values are kept for
    the last few points; objective evaluations are counted against a budget (a count).
    """

    def __init__(
        self,
        problem: Problem,
        unit: Problem,
        objective: Objective,
        beta0: np.ndarray,
        s_mat: np.ndarray,
        scale: float,
        budget: int,
    ) -> None:
        self.problem, self.unit, self.objective = problem, unit, objective
        self.beta0, self.s_mat, self.scale, self.budget = beta0, s_mat, scale, budget
        self.memo: dict[bytes, Any] = {}
        self.spent = 0  # objective evaluations so far

    def to_beta(self, z: np.ndarray) -> np.ndarray:
        return self.beta0 + self.s_mat @ z

    def _cached(self, kind: str, z: np.ndarray, make: Callable[[np.ndarray], Any]) -> Any:
        key = kind.encode() + np.asarray(z, dtype=float).tobytes()
        if key not in self.memo:
            if kind == "j":
                self.spent += 1
                if self.spent > self.budget:
                    raise _BudgetSpentError
                heartbeat(partial(_where, self.objective.name, self.spent, self.budget))
            if len(self.memo) > 64:
                self.memo.clear()
            self.memo[key] = make(self.to_beta(z))
        return self.memo[key]

    def _objective(self, z: np.ndarray) -> Any:
        return self._cached("j", z, lambda b: self.objective.evaluate(self.unit, b))

    def fun(self, z: np.ndarray) -> float:
        return float(self._objective(z).value) / self.scale

    def grad(self, z: np.ndarray) -> np.ndarray:
        return np.asarray(self.s_mat.T @ self._objective(z).gradient) / self.scale

    def h(self, z: np.ndarray) -> np.ndarray:
        return np.asarray(self._cached("h", z, self.problem.residual_and_jacobian)[0])

    def dh(self, z: np.ndarray) -> np.ndarray:
        return np.asarray(self._cached("h", z, self.problem.residual_and_jacobian)[1] @ self.s_mat)


def _inequalities(
    problem: Problem, imposed: Sequence[Constraint], instants: np.ndarray, ev: _Evaluations
) -> list[dict[str, object]]:
    """SLSQP inequality rows of the imposed constraints at the instants, backed off a little."""
    cons: list[dict[str, object]] = []
    for constraint in imposed:
        backoff = BACKOFF * constraint.tolerance
        for g, dg in constraint_functions(problem, [constraint], instants):
            cons.append(
                {
                    "type": "ineq",
                    "fun": lambda z, g=g, b=backoff: g(ev.to_beta(z)) - b,
                    "jac": lambda z, dg=dg: dg(ev.to_beta(z)) @ ev.s_mat,
                }
            )
    return cons
