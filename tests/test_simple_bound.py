"""The simple-motion bound's joint gains: their gradients and their search, checked apart.

The gains are the largest norms of the columns of ``F1`` over the box a simple motion can
visit, found by sampling and a projected gradient ascent on the planner's batched formula.
Here the gradient is checked against finite differences of Pinocchio's centroidal map, and
the gains against SciPy's L-BFGS-B maximising the same norms on Pinocchio's map from the
same starting samples.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize

import freefloat as ff
from freefloat.problem.quasi_random import unit_points
from freefloat.problem.simple_bound import SAMPLES, _column_norms, simple_motion_bound

SCENARIOS = Path(__file__).resolve().parents[1] / "robots" / "scenarios"


def _setup(name: str) -> tuple[ff.MomentumMap, np.ndarray, np.ndarray]:
    scenario = ff.Scenario.from_toml(SCENARIOS / f"{name}.toml").resolved()
    return ff.MomentumMap(scenario.robot), np.asarray(scenario.start), np.asarray(scenario.goal)


def _pinocchio_norm(mmap: ff.MomentumMap, q: np.ndarray, column: int) -> float:
    return float(np.linalg.norm(mmap.f1(q)[:, column]))  # Pinocchio's computeCentroidalMap


def test_column_norm_gradients_match_finite_differences_of_pinocchios_map() -> None:
    mmap, start, goal = _setup("panda_servicer")
    rng = np.random.default_rng(11)
    n = len(start)
    joints = start + rng.uniform(0.0, 1.0, (n, n)) * (goal - start)
    columns = np.arange(n)
    norms, slopes = _column_norms(mmap, joints, columns)
    h = 1e-6
    for k in range(n):
        assert norms[k] == pytest.approx(_pinocchio_norm(mmap, joints[k], k), rel=1e-12)
        numeric = np.array(
            [
                (
                    _pinocchio_norm(mmap, joints[k] + h * e, k)
                    - _pinocchio_norm(mmap, joints[k] - h * e, k)
                )
                / (2 * h)
                for e in np.eye(n)
            ]
        )
        np.testing.assert_allclose(slopes[k], numeric, atol=1e-8 * max(1.0, norms[k]))


@pytest.mark.parametrize("name", ["panda_servicer", "ur5_servicer"])
@pytest.mark.parametrize("factor", [1.0, 3.0, 10.0])
@pytest.mark.parametrize("seed", [0, 2])
def test_gains_reach_what_lbfgsb_finds_from_the_same_samples(
    name: str, factor: float, seed: int
) -> None:
    """Within 3e-3 of L-BFGS-B's (measured: at most 4e-5 below it at k = 1, 2.5e-3 on the
    Panda at k = 10, where a curved ridge ends the ascent's step budget; often above it)."""
    mmap, start, goal = _setup(name)
    found = simple_motion_bound(mmap, start, goal, factor, seed=seed)
    box = found.box
    unit = unit_points(SAMPLES, len(start), seed)
    points = np.vstack([start, goal, box[:, 0] + unit * (box[:, 1] - box[:, 0])])
    for i in np.flatnonzero(found.travel > 0.0):
        sampled = [_pinocchio_norm(mmap, p, i) for p in points]
        theirs = minimize(
            lambda q, i=i: -_pinocchio_norm(mmap, q, i),
            points[int(np.argmax(sampled))],
            method="L-BFGS-B",
            bounds=[(float(a), float(b)) for a, b in box],
        )
        best = max(max(sampled), -float(theirs.fun))
        tolerance = 5e-5 if factor == 1.0 else 3e-3
        assert found.gains[i] >= best * (1.0 - tolerance), (i, found.gains[i], best)
