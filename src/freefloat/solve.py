"""Solve ``h(beta) = 0`` for the free path coefficients (method.md section 5).

- One unknown and one equation (planar, one free coefficient): scan a bracket, refine every
  sign change with Brent's safeguarded secant method, and return the minimum-norm root with
  the others listed.
- Otherwise the search runs from several deterministic starts and keeps the minimum-norm root.
- As many unknowns as equations: Broyden's quasi-Newton method with a backtracking line search
  (the Jacobian is refreshed by central differences when the line search stalls); where it
  fails (dh/dbeta nearly singular), Levenberg-Marquardt from the same start.
- More unknowns than equations: minimum-norm ``beta`` subject to ``h(beta) = 0`` by SQP
  (SciPy's SLSQP), then minimum-norm Gauss-Newton corrections.

A solution is returned only when the residual is below the tolerance; otherwise
:class:`~freefloat.errors.SolverError` reports the best residual reached and what was tried.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq, least_squares, minimize

from .errors import SolverError
from .paths import basis_coefficients
from .problem import Problem

__all__ = ["DEFAULT_TOLERANCE", "Root", "Solution", "SolveOptions", "solve"]

#: Default attitude tolerance (rad).
DEFAULT_TOLERANCE = 1e-9
#: Iterations continue until the residual is this fraction of the tolerance (1e-13 rad by
#: default): with exact Jacobians the last step costs one evaluation and buys three digits.
POLISH = 1e-4


@dataclass(frozen=True)
class SolveOptions:
    """Solver settings.

    Attributes:
        tolerance: largest accepted attitude error at T (rad).
        max_deviation: half-width of the one-unknown bracket, as the largest deviation of the
            joint from its quintic path (rad; or m for a prismatic joint).
        scan_points: number of residual samples across the bracket.
        max_iterations: iteration cap of the quasi-Newton and SQP solvers.
        starts: number of starting points tried (the quintic path first, then deterministic
            pseudo-random ones); several are needed because ``dh/dbeta`` is singular at the
            quintic path whenever free coefficients of one power move several joints (moving
            along the straight joint-space line only re-times it).
        keep_solutions: stop after this many solutions; the minimum-norm one is returned.
        time_budget: no new start is tried after this many seconds (s).
    """

    tolerance: float = DEFAULT_TOLERANCE
    max_deviation: float = 8.0
    scan_points: int = 161
    max_iterations: int = 100
    starts: int = 7
    keep_solutions: int = 1
    time_budget: float = 20.0


@dataclass(frozen=True)
class Root:
    """One solution of ``h(beta) = 0``.

    Attributes:
        beta: free coefficients (normalised-time coefficients, rad or m).
        residual: norm of ``h`` there (rad).
        path_length: summed joint travel along the path (rad, plus m for prismatic joints).
    """

    beta: np.ndarray
    residual: float
    path_length: float


@dataclass(frozen=True)
class Solution:
    """The chosen solution and how it was found.

    Attributes:
        beta: chosen free coefficients (rad or m).
        residual: norm of ``h(beta)`` (rad).
        method: solver used.
        iterations: iterations of the solver that produced ``beta``.
        evaluations: residual evaluations (each integrates the attitude along a path).
        wall_time: seconds spent solving.
        roots: every root found, the chosen one first.
        integration_error: estimated error of the attitude integration at ``beta`` (rad).
    """

    beta: np.ndarray
    residual: float
    method: str
    iterations: int
    evaluations: int
    wall_time: float
    roots: tuple[Root, ...] = field(default_factory=tuple)
    integration_error: float = 0.0


def _polish(
    problem: Problem, beta: np.ndarray, tol: float, iterations: int = 8
) -> tuple[np.ndarray, np.ndarray]:
    """Minimum-norm Gauss-Newton corrections until the residual is well below ``tol``.

    Returns the corrected ``beta`` and its residual vector.
    """
    r = problem.residual(beta)
    if np.linalg.norm(r) < POLISH * tol:
        return beta, r
    jac = problem.jacobian(beta)
    for _ in range(iterations):
        if np.linalg.norm(r) < POLISH * tol:
            break
        trial = beta - np.linalg.lstsq(jac, r, rcond=None)[0]
        r_trial = problem.residual(trial)
        if np.linalg.norm(r_trial) >= np.linalg.norm(r):
            break
        beta = trial
        r, jac = problem.residual_and_jacobian(beta)
    return beta, r


def _scan(
    problem: Problem, options: SolveOptions
) -> tuple[list[np.ndarray], int, list[np.ndarray]]:
    """All roots of the scalar residual in the bracket.

    Returns the roots, the iterations, and the residuals of the roots when known.

    Sign changes on a coarse grid are refined with Brent's method, or, with a planar map,
    all at once by safeguarded Newton steps with the exact slope.
    """
    power = problem.family.free_index[0][1]
    shape = np.polynomial.polynomial.polyval(np.linspace(0.0, 1.0, 201), basis_coefficients(power))
    half_width = options.max_deviation / np.abs(shape).max()
    grid = np.linspace(-half_width, half_width, options.scan_points)
    fine_steps = problem.steps
    problem.set_steps(max(16, fine_steps // 4))  # locating sign changes needs less accuracy
    assert problem.yaw_change is not None
    values = problem.yaw_changes(grid[:, None]) - problem.yaw_change
    problem.set_steps(fine_steps)

    changes = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))
    if problem.planar_map is not None:
        lo, hi = grid[changes], grid[changes + 1]
        seed = lo - values[changes] * (hi - lo) / (values[changes + 1] - values[changes])
        return _newton_brackets(problem, lo, hi, seed)

    def scalar(b: float) -> float:
        return float(problem.residual(np.array([b]))[0])

    roots, iterations = [], 0
    for i in changes:
        lo, hi = grid[i], grid[i + 1]
        f_lo, f_hi = scalar(lo), scalar(hi)
        if np.sign(f_lo) == np.sign(f_hi):  # the coarse scan saw a change the fine one does not
            continue
        root, info = brentq(
            scalar, lo, hi, xtol=1e-13, rtol=4 * np.finfo(float).eps, full_output=True
        )
        iterations += info.iterations
        roots.append(np.array([root]))
    return roots, iterations, []


def _newton_brackets(
    problem: Problem, lo: np.ndarray, hi: np.ndarray, seed: np.ndarray, iterations: int = 60
) -> tuple[list[np.ndarray], int, list[np.ndarray]]:
    """Refine every bracketed root at once (vectorised over the brackets).

    Newton steps with the exact slope, kept inside each bracket by bisection.
    """
    assert problem.yaw_change is not None
    target = problem.yaw_change
    if len(lo) == 0:
        return [], 0, []
    values = problem.yaw_changes(np.concatenate([lo, hi])[:, None])
    f_lo, f_hi = values[: len(lo)] - target, values[len(lo) :] - target
    keep = np.sign(f_lo) != np.sign(f_hi)  # the coarse scan saw a change the fine one does not
    lo, hi, f_lo = lo[keep], hi[keep], f_lo[keep]
    x = np.clip(seed[keep], lo, hi)  # the secant point of the coarse scan
    done = iterations
    f = np.full(len(x), np.inf)
    for iteration in range(1, iterations + 1):
        f, slope = problem.yaw_changes_and_slopes(x)
        f = f - target
        if np.all(np.abs(f) < 1e-14):
            done = iteration
            return [np.array([r]) for r in x], done, [np.array([v]) for v in f]
        left = np.sign(f) == np.sign(f_lo)
        lo, f_lo = np.where(left, x, lo), np.where(left, f, f_lo)
        hi = np.where(left, hi, x)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = x - f / slope
        inside = np.isfinite(newton) & (newton > lo) & (newton < hi)
        x = np.where(np.abs(f) < 1e-14, x, np.where(inside, newton, 0.5 * (lo + hi)))
    return [np.array([root]) for root in x], done, []


def _broyden(problem: Problem, beta: np.ndarray, options: SolveOptions) -> tuple[np.ndarray, int]:
    r, jac = problem.residual_and_jacobian(beta)
    refreshed = True
    for iteration in range(1, options.max_iterations + 1):
        if np.linalg.norm(r) < POLISH * options.tolerance:
            return beta, iteration
        step = -np.linalg.lstsq(jac, r, rcond=None)[0]
        t = 1.0
        while t > 1e-4:
            trial = beta + t * step
            r_trial = problem.residual(trial)
            if np.linalg.norm(r_trial) < (1.0 - 1e-4 * t) * np.linalg.norm(r):
                break
            t *= 0.5
        else:
            if refreshed:
                return beta, iteration
            jac, refreshed = problem.jacobian(beta), True
            continue
        s = trial - beta
        jac = jac + np.outer(r_trial - r - jac @ s, s) / (s @ s)
        beta, r, refreshed = trial, r_trial, False
    return beta, options.max_iterations


def _starts(n: int, count: int) -> list[tuple[str, np.ndarray]]:
    """The quintic path, then ``count - 1`` deterministic pseudo-random starts (rad)."""
    rng = np.random.default_rng(20070101)
    out = [("the quintic path", np.zeros(n))]
    for k in range(1, count):
        scale = (1.0, 3.0, 10.0)[(k - 1) // 4 % 3]
        direction = rng.normal(size=n)
        beta = scale * direction / np.linalg.norm(direction)
        out.append((f"start {k} (|beta| = {scale:g})", beta))
    return out


def _levenberg_marquardt(
    problem: Problem, beta: np.ndarray, options: SolveOptions
) -> tuple[np.ndarray, int]:
    """Damped Gauss-Newton (MINPACK's LM): robust where dh/dbeta is nearly singular."""
    result = least_squares(
        problem.residual,
        beta,
        jac=problem.jacobian,
        method="lm",
        xtol=1e-15,
        ftol=1e-15,
        gtol=1e-15,
        max_nfev=options.max_iterations,
    )
    return np.asarray(result.x, dtype=float), int(result.nfev)


def _sqp(problem: Problem, beta: np.ndarray, options: SolveOptions) -> tuple[np.ndarray, int]:
    """Minimum-norm ``beta`` with ``h(beta) = 0`` and the joint limits along the path."""
    cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def evaluate(b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = np.asarray(b, dtype=float).tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = problem.residual_and_jacobian(b)
        return cache[key]

    constraints: list[dict[str, object]] = [
        {"type": "eq", "fun": lambda b: evaluate(b)[0], "jac": lambda b: evaluate(b)[1]}
    ]
    g_mat, g_vec = problem.limit_constraints()
    if len(g_vec):
        constraints.append(
            {"type": "ineq", "fun": lambda b: g_vec - g_mat @ b, "jac": lambda b: -g_mat}
        )
    result = minimize(
        lambda b: 0.5 * float(b @ b),
        beta,
        jac=lambda b: b,
        method="SLSQP",
        constraints=constraints,
        options={"ftol": 1e-16, "maxiter": options.max_iterations},
    )
    return np.asarray(result.x, dtype=float), int(result.nit)


def solve(problem: Problem, options: SolveOptions | None = None) -> Solution:
    """Find the free coefficients that bring the base to its goal attitude.

    Raises:
        SolverError: no ``beta`` with a residual below the tolerance was found.
    """
    options = options or SolveOptions()
    tol = options.tolerance
    start_time = time.perf_counter()
    start_evaluations = problem.evaluations
    zero = np.zeros(problem.n_free)
    tried: list[str] = []
    candidates: list[np.ndarray] = []
    known: dict[int, np.ndarray] = {}  # residuals already computed at converged candidates
    iterations = 0

    def within_limits(beta: np.ndarray) -> bool:
        over, name = problem.limit_violation(beta)
        if over > 1e-9:
            tried.append(f"a root breaks the limit of joint {name!r}")
            return False
        return True

    if np.linalg.norm(problem.residual(zero)) < 0.01 * tol and within_limits(zero):
        method, candidates = "none (the quintic path already reaches the goal)", [zero]
    elif problem.n_free == 1 and problem.n_equations == 1:
        method = "bracket scan + " + (
            "safeguarded Newton" if problem.planar_map is not None else "Brent secant"
        )
        candidates, iterations, residuals = _scan(problem, options)
        known = dict(enumerate(residuals))
        tried.append(
            f"{options.scan_points}-point scan of a bracket of +-{options.max_deviation:g} rad "
            "path deviation"
        )
        if not candidates:
            tried.append("no sign change of h in the bracket")
    else:
        square = problem.n_free == problem.n_equations
        method = "Broyden quasi-Newton" if square else "SQP minimum norm (SLSQP)"
        found = 0
        for label, start in _starts(problem.n_free, options.starts):
            if time.perf_counter() - start_time > options.time_budget:
                tried.append(f"stopped: time budget of {options.time_budget:g} s spent")
                break
            name = "minimum-norm SQP with joint limits"
            try:
                beta = None
                if square:
                    beta, its = _broyden(problem, start, options)
                    name = "Broyden"
                    if np.linalg.norm(problem.residual(beta)) > tol:
                        beta, its = _levenberg_marquardt(problem, start, options)
                        name = "Broyden, then Levenberg-Marquardt"
                    if np.linalg.norm(problem.residual(beta)) > tol or not within_limits(beta):
                        tried.append(f"{name} from {label}")
                        beta = None
                        name = "SQP with joint limits"
                if beta is None:
                    beta, its = _sqp(problem, start, options)
            except (np.linalg.LinAlgError, FloatingPointError, ValueError) as exc:
                # An optimiser that diverges is a failed attempt, not a crash.
                tried.append(f"{name} from {label}: diverged ({type(exc).__name__})")
                continue
            tried.append(f"{name} from {label}")
            candidates.append(beta)
            if np.linalg.norm(problem.residual(beta)) < tol:
                if found == 0:
                    iterations = its
                    method = {
                        "Broyden": "Broyden quasi-Newton",
                        "Broyden, then Levenberg-Marquardt": "Levenberg-Marquardt",
                    }.get(name, "SQP minimum norm (SLSQP) with joint limits")
                found += 1
                if found >= options.keep_solutions:
                    break

    roots = []
    best_vector = problem.residual(zero)  # the quintic path always respects the limits
    for index, beta in enumerate(candidates):
        if index in known:  # refined to 1e-14 rad by the vectorised Newton: no polishing
            vector = known[index]
        else:
            beta, vector = _polish(problem, beta, tol)
        residual = float(np.linalg.norm(vector))
        if not within_limits(beta):
            continue
        if residual < np.linalg.norm(best_vector):
            best_vector = vector
        if residual < tol:
            roots.append(Root(beta, residual, problem.path_length(beta)))
    roots.sort(key=lambda r: float(r.beta @ r.beta))
    if not roots:
        raise SolverError(
            "no path within the joint limits reaches the goal attitude",
            float(np.linalg.norm(best_vector)),
            _dedupe(tried),
            per_axis=best_vector.tolist(),
        )

    # Certify the integration at the chosen root; refine the grid and polish when needed.
    chosen = roots[0]
    error = problem.integration_error(chosen.beta)
    for _ in range(3):
        if error <= 0.1 * tol:
            break
        problem.choose_steps(chosen.beta)
        beta, vector = _polish(problem, chosen.beta, tol)
        chosen = Root(beta, float(np.linalg.norm(vector)), chosen.path_length)
        error = problem.integration_error(chosen.beta)
    if error > 0.1 * tol or chosen.residual >= tol:
        raise SolverError(
            f"attitude integration error {error:.3g} rad is too large to certify the plan",
            chosen.residual,
            _dedupe(tried),
        )
    return Solution(
        beta=chosen.beta,
        residual=chosen.residual,
        method=method,
        iterations=iterations,
        evaluations=problem.evaluations - start_evaluations,
        wall_time=time.perf_counter() - start_time,
        roots=(chosen, *roots[1:]),
        integration_error=error,
    )


def _dedupe(items: list[str]) -> list[str]:
    """Items in order, repeated ones counted (keeps error messages short)."""
    counts: dict[str, int] = {}
    for item in items:
        counts[item] = counts.get(item, 0) + 1
    return [item if n == 1 else f"{item} (x{n})" for item, n in counts.items()]
