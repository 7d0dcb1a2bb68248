"""Solver settings, the strategy names and the typed results of a solve."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputLimitError

__all__ = [
    "DEFAULT_TOLERANCE",
    "POLISH",
    "TOLERANCE_RANGE_RAD",
    "Attempt",
    "Root",
    "Solution",
    "SolveOptions",
    "Strategy",
]


class Strategy(str, enum.Enum):
    """The built-in strategies' names (how ``h(beta) = 0`` is solved); recorded in the plan.

    The registry of strategy functions (:data:`~freefloat.solvers.dispatch.STRATEGIES`) is
    keyed by name, so a new strategy needs no member here: options, solutions and plans carry
    the plain name.

    - ``none``: the quintic path (``beta = 0``) already reaches the goal.
    - ``scan``: one unknown, one equation: scan a bracket, refine every sign change.
    - ``multistart``: Newton-type searches (Broyden, Levenberg-Marquardt, minimum-norm SQP)
      from several deterministic starts.
    - ``continuation``: track the solution from the quintic path's own attitude to the goal.
    """

    NONE = "none"
    SCAN = "scan"
    MULTISTART = "multistart"
    CONTINUATION = "continuation"


#: Default attitude tolerance (rad).
DEFAULT_TOLERANCE = 1e-9
#: Accepted attitude tolerances (rad). Below 1e-11 no plan can be certified: a solution is
#: accepted only when the attitude integration's own error estimate is below a tenth of the
#: tolerance, and the step control aims at 1e-12 rad (``INTEGRATION_TOLERANCE``), near the
#: round-off floor of the sixth-order Magnus steps in double precision (about 1e-13 rad over
#: thousands of steps). Above 1e-7 a plan could not pass verification, whose independent
#: attitude check holds every plan to 1e-7 rad.
TOLERANCE_RANGE_RAD = (1e-11, 1e-7)
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
        max_evaluations: no new start or step is begun after this many residual evaluations
            (a count, so the same input gives the same plan on any machine).
        strategy: force a strategy (a name in
            :data:`~freefloat.solvers.dispatch.STRATEGIES`, or a :class:`Strategy`); default:
            chosen from the problem's shape.
    """

    tolerance: float = DEFAULT_TOLERANCE
    max_deviation: float = 8.0
    scan_points: int = 161
    max_iterations: int = 100
    starts: int = 7
    keep_solutions: int = 1
    max_evaluations: int = 4000
    strategy: str | None = None

    def __post_init__(self) -> None:
        if isinstance(self.strategy, Strategy):  # carried by its plain name
            object.__setattr__(self, "strategy", self.strategy.value)
        low, high = TOLERANCE_RANGE_RAD
        if not low <= self.tolerance <= high:  # NaN fails too
            raise InputLimitError("tolerance", self.tolerance, low, high, "rad")


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
        steps: integration steps on which ``beta`` was certified.
        strategy: the name of the strategy that found ``beta``.
        tried: what was attempted, in order.
    """

    beta: np.ndarray
    residual: float
    method: str
    iterations: int
    evaluations: int
    wall_time: float
    roots: tuple[Root, ...] = field(default_factory=tuple)
    integration_error: float = 0.0
    steps: int = 0
    strategy: str = Strategy.NONE.value
    tried: tuple[str, ...] = ()


@dataclass
class Attempt:
    """What one strategy produced, before polishing, filtering and certification.

    Attributes:
        candidates: free-coefficient vectors that may be roots.
        method: the method that produced the first good candidate (a label for people).
        iterations: iterations of that method.
        residuals: per candidate index, its residual vector when already known exactly.
        tried: what was attempted, in order.
        stopped_by: why the strategy stopped short, when it did (for error messages).
        blocked_by: the names of the constraints that stopped it, when any did.
        reached_fraction: for continuation, how far along the way to the goal it got (0-1).
        message: a one-line account of a failure for the error message ("" for the default).
        last_beta: where a strategy that stopped short got to (continuation), so that a
            search with more freedom can continue from there.
    """

    candidates: list[np.ndarray] = field(default_factory=list)
    method: str = ""
    iterations: int = 0
    residuals: dict[int, np.ndarray] = field(default_factory=dict)
    tried: list[str] = field(default_factory=list)
    stopped_by: str = ""
    blocked_by: tuple[str, ...] = ()
    reached_fraction: float = 0.0
    message: str = ""
    last_beta: np.ndarray | None = None
