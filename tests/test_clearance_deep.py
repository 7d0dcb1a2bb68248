"""The solvers' dense clearance check on paths deep in collision.

Truth: every pair measured (no bound between samples, no pair spared) on a grid fifty times
as dense as the check's own, and the check's own answer when it halves every undecided
interval as it did before it stopped at the smallest sample.
"""

from __future__ import annotations

import numpy as np
import pytest

import freefloat as ff
import freefloat.problem.constraints.clearance as clearance_module
from freefloat.problem.constraints.clearance import Clearance
from freefloat.robot.collision import CollisionModel, known_srdf
from test_collision_bound import _Dip, _OnePath

from conftest import ROOT

PANDA = ROOT / "robots" / "scenarios" / "panda_servicer.toml"
UR5 = ROOT / "robots" / "scenarios" / "ur5_servicer.toml"
MARGIN = 0.01


def _deep_path(path, seed: int):
    """A problem and a beta whose path lies at least 5 cm deep in collision somewhere."""
    scenario = ff.Scenario.from_toml(path)
    robot = scenario.robot
    problem = ff.problem_from_scenario(scenario, extra=[2] * robot.n)
    rng = np.random.default_rng(seed)
    everything = CollisionModel(robot, known_srdf(robot))
    everything._weights = None  # the truth: no bound between samples, every pair measured
    for _ in range(20):
        beta = rng.normal(0.0, 1.5, problem.n_free)
        poly = problem.polynomials(beta)
        t = np.linspace(0.0, poly.duration, 201 * 50)
        dense = min(
            float(everything.closest_many(poly.evaluate(chunk).q).values.min())
            for chunk in np.array_split(t, 25)
        )
        if dense < MARGIN - 0.05:
            return robot, problem, beta, dense
    raise AssertionError("no deep path drawn")


@pytest.mark.parametrize(("path", "seed"), [(PANDA, 3), (UR5, 4)], ids=["panda", "ur5"])
def test_the_smallest_clearance_of_a_path_deep_in_collision_is_the_dense_grids(
    path, seed, monkeypatch
):
    """The check's smallest clearance is at most the dense grid's (it misses no deeper
    point) and within 1 mm below it (the grid's spacing times the bodies' speeds), and the
    same bits as when every interval the bound cannot clear of the margin is halved."""
    robot, problem, beta, dense = _deep_path(path, seed)
    check = Clearance(CollisionModel(robot, known_srdf(robot)), MARGIN)
    excess = check.violation(problem, beta)
    reported = MARGIN - excess.value
    assert reported <= dense + 1e-9
    assert reported >= dense - 1e-3
    assert excess.detail.startswith(f"min clearance {reported:.6g} m")

    # the earlier rule: every interval whose bound falls below the margin is halved
    original = clearance_module.undecided

    def below_the_margin(model, poly, ends, tables, limit, below=None):
        return original(model, poly, ends, tables, limit)

    monkeypatch.setattr(clearance_module, "undecided", below_the_margin)
    halved = Clearance(CollisionModel(robot, known_srdf(robot)), MARGIN)
    assert halved.violation(problem, beta) == excess  # value, and time and pair in the detail


class _TwoDips(_Dip):
    """A fake collision model along one joint, ``q = t`` over 1 s, 201 samples (closed form).

    Clearance (m): ``margin - 2 cm + |q - 0.25|`` (a dip seen: its minimum on sample 50) and
    ``margin - 5 cm + 40 |q - q_b|`` with ``q_b`` halfway between samples 150 and 151, which
    both lie 5 cm above the margin: the deeper dip hides between samples. The clearance
    changes at most 40 m per rad (the weight).
    """

    hidden = 150.5 / 200

    def __init__(self, margin: float) -> None:
        super().__init__(margin, 0.0, np.array([[40.0]]))

    def values(self, q: np.ndarray) -> np.ndarray:
        seen = self.margin - 0.02 + np.abs(q - 0.25)
        hidden = self.margin - 0.05 + 40.0 * np.abs(q - self.hidden)
        return np.minimum(seen, hidden)


def test_a_deeper_dip_between_samples_than_the_deepest_sample_is_found(monkeypatch):
    """Closed form (:class:`_TwoDips`): a sample lies 2 cm below the margin, and between two
    samples 5 cm above it the clearance dips 5 cm below: the check reports the hidden dip (its
    depth and time), having measured fewer instants than when it halved every interval the
    bound could not clear of the margin."""
    from freefloat.problem.paths import JointPolynomials

    path = JointPolynomials.from_monomials([[0.0, 1.0]], 1.0)
    model = _TwoDips(MARGIN)
    check = Clearance(model, MARGIN)
    excess = check.violation(_OnePath(path), np.zeros(1))
    assert excess.value == pytest.approx(0.05, abs=1e-8)
    assert check.critical_times(None, path)[0] == pytest.approx(_TwoDips.hidden, abs=1e-6)
    assert "at t = 0.7525 s" in excess.detail

    original = clearance_module.undecided  # the earlier rule: halved below the margin
    monkeypatch.setattr(
        clearance_module,
        "undecided",
        lambda m, p, e, t, limit, below=None: original(m, p, e, t, limit),
    )
    every = _TwoDips(MARGIN)
    assert Clearance(every, MARGIN).violation(_OnePath(path), np.zeros(1)) == excess
    assert model.rows < every.rows
