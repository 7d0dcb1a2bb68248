"""The evenly spread sample points: in the cube, reproducible, evenly spread by SciPy's measure."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy.stats import qmc

from freefloat.problem.quasi_random import unit_points


@pytest.mark.parametrize(("count", "dimensions"), [(256, 3), (256, 7), (512, 12)])
def test_points_are_spread_evenly_by_scipys_discrepancy(count: int, dimensions: int) -> None:
    points = unit_points(count, dimensions)
    assert points.shape == (count, dimensions)
    assert points.min() >= 0.0 and points.max() < 1.0
    # SciPy's centred L2 discrepancy (its own code): far below independent uniform draws
    # (averaged over seeds) and within a small factor of SciPy's scrambled Sobol points.
    ours = qmc.discrepancy(points)
    drawn = np.mean(
        [qmc.discrepancy(np.random.default_rng(s).random((count, dimensions))) for s in range(8)]
    )
    sobol = qmc.discrepancy(qmc.Sobol(dimensions, scramble=True, seed=0).random(count))
    assert ours < 0.6 * drawn
    assert ours < 10.0 * sobol


def test_every_joint_is_covered_in_each_tenth_of_its_range() -> None:
    points = unit_points(256, 7)
    counts = np.stack([np.histogram(points[:, j], bins=10, range=(0, 1))[0] for j in range(7)])
    # 25.6 per bin if exactly even; independent uniform draws stray by about 5 (one sigma)
    assert counts.min() >= 21 and counts.max() <= 30


def test_seeds_give_other_points_and_the_same_points_again() -> None:
    assert np.array_equal(unit_points(64, 5, seed=3), unit_points(64, 5, seed=3))
    for seed in (1, 5, -1, -7):  # every column moves, the points stay in the cube
        other = unit_points(64, 20, seed=seed)
        assert other.min() >= 0.0 and other.max() < 1.0
        assert not np.any(np.all(np.isclose(other, unit_points(64, 20)), axis=0))
    assert np.array_equal(unit_points(32, 5), unit_points(64, 5)[:32])  # every prefix


def test_the_same_points_in_a_new_process() -> None:
    code = (
        "from freefloat.problem.quasi_random import unit_points;"
        "print(unit_points(50, 6, 2).tobytes().hex())"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert bytes.fromhex(out.stdout.strip()) == unit_points(50, 6, 2).tobytes()


def test_bad_sizes_are_refused() -> None:
    with pytest.raises(ValueError, match="dimensions >= 1"):
        unit_points(4, 0)
    assert unit_points(0, 3).shape == (0, 3)
