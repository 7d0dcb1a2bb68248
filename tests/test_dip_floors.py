"""The solvers' dense check skips the dips a bound shows cannot hold the lowest point.

Its lowest point along a path that breaks the margin comes from a scalar search at every
sampled local minimum below it (``Clearance._below``); a minimum whose floor (the bound of the
clearance over the two intervals the search spans, ``minima_floors``) is not below the lowest
found so far is skipped. Checked here: the floors lie below every pair's distance measured by
coal pair by pair at dense instants of those intervals (brute force: no bound spares a query),
the answer is the same with the floors as without them, and some searches are skipped.
"""

from __future__ import annotations

import numpy as np
import pytest

import freefloat as ff
import freefloat.problem.constraints.clearance as clearance_module
from freefloat.problem.constraints.registry import scenario_constraints

from conftest import ROOT

#: A 5 cm keep-out ball in the UR5 servicer's way (test_clearance_truth's case).
BALL = '\n[safety]\nmargin_m = 0.01\n[[obstacles]]\nname = "ball"\nsphere = 0.05\n'
BALL += "xyz = [0.85, 0.14, -0.20]\n"


@pytest.fixture(scope="module")
def ball_scenario(tmp_path_factory):
    path = tmp_path_factory.mktemp("dips") / "ur5_ball.toml"
    path.write_text((ROOT / "robots" / "scenarios" / "ur5_servicer.toml").read_text() + BALL)
    return ff.Scenario.from_toml(path)


def _paths(scenario):
    """The plain quintic path and random paths of the family, most of them through the ball."""
    problem = ff.problem_from_scenario(scenario)
    rng = np.random.default_rng(3)
    betas = [np.zeros(problem.n_free)] + [rng.normal(0, 0.6, problem.n_free) for _ in range(7)]
    return [problem.polynomials(beta) for beta in betas]


def _fresh_clearance(scenario):
    (found,) = [c for c in scenario_constraints(scenario) if c.name == "clearance"]
    return found


def test_dip_floors_hold_and_spare_searches_without_changing_the_lowest_point(
    ball_scenario, monkeypatch
):
    paths = _paths(ball_scenario)
    floors_seen: list[tuple[object, np.ndarray, np.ndarray, np.ndarray]] = []
    real_floors = clearance_module.minima_floors

    def recording(model, path, t, minima, tables):
        found = real_floors(model, path, t, minima, tables)
        floors_seen.append((path, t.copy(), minima.copy(), found.copy()))
        return found

    searches = {"with": 0, "without": 0}
    real_refined = clearance_module.refined_minima

    def counting(label):
        def refined(model, path, t, sampled, minima, floors=None):
            best = float(np.min(sampled))
            for i in range(len(minima)):  # an upper count: those not skipped at the start
                searches[label] += int(floors is None or floors[i] < best)
            return real_refined(model, path, t, sampled, minima, floors)

        return refined

    monkeypatch.setattr(clearance_module, "minima_floors", recording)
    monkeypatch.setattr(clearance_module, "refined_minima", counting("with"))
    with_floors = [_fresh_clearance(ball_scenario)._solvers_check(p) for p in paths]
    monkeypatch.setattr(clearance_module, "minima_floors", lambda *a: np.full(len(a[3]), -np.inf))
    monkeypatch.setattr(clearance_module, "refined_minima", counting("without"))
    without = [_fresh_clearance(ball_scenario)._solvers_check(p) for p in paths]

    broken = [w for w in with_floors if w[1] is not None]
    assert len(broken) >= 5  # the ball is in the way of most of them
    assert with_floors == without  # the same bound, lowest value, time and pair, to the bit
    assert searches["with"] < searches["without"]

    model = _fresh_clearance(ball_scenario).model
    checked = 0
    for path, t, minima, floors in floors_seen:
        for k, floor in zip(minima.tolist(), floors.tolist(), strict=True):
            lo, hi = t[max(k - 1, 0)], t[min(k + 1, len(t) - 1)]
            dense = path.positions(np.linspace(lo, hi, 41))
            truth = min(float(np.min(model.distances(q).values)) for q in dense)
            assert floor <= truth + 1e-12
            checked += 1
    assert checked >= 5
