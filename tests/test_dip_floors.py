"""The solvers' dense check skips the dips a bound shows cannot hold the lowest point.

Its lowest point along a path that breaks the margin comes from a scalar search at every
sampled local minimum below it (``Clearance._below``); a minimum whose floor (the bound of the
clearance over the two intervals the search spans, ``minima_floors``) is not below the lowest
found so far is skipped. Checked here: the floors lie below every pair's distance measured by
coal pair by pair at dense instants of those intervals (brute force: no bound spares a query),
the answer is the same with the floors as without them, and fewer searches are run. Two kinds
of path: through a 5 cm keep-out ball (dips well below the margin), and clear of a smaller
ball by 0.1 mm less than the margin (the check halves intervals, so the floors are taken over
samples it added, in time order, next to samples it spared).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import freefloat as ff
import freefloat.problem.constraints.clearance as clearance_module
import freefloat.problem.constraints.clearance_samples as samples_module
from freefloat.problem.constraints.registry import scenario_constraints

from conftest import ROOT

SHIPPED = (ROOT / "robots" / "scenarios" / "ur5_servicer.toml").read_text()


def _ball(folder: Path, radius: float = 0.05, margin: float = 0.01) -> ff.Scenario:
    """The UR5 servicer with a keep-out ball in its way (test_clearance_truth's case)."""
    path = folder / f"ball_{radius!r}_{margin!r}.toml"
    path.write_text(
        SHIPPED + f'\n[safety]\nmargin_m = {margin!r}\n[[obstacles]]\nname = "ball"\n'
        f"sphere = {radius!r}\nxyz = [0.85, 0.14, -0.20]\n"
    )
    return ff.Scenario.from_toml(path)


def _clearance(scenario: ff.Scenario):
    (found,) = [c for c in scenario_constraints(scenario) if c.name == "clearance"]
    return found


def _cases(folder: Path) -> list[tuple[ff.Scenario, object]]:
    """(scenario, path): random paths through the ball, and each again with a thin margin."""
    through = _ball(folder)
    problem = ff.problem_from_scenario(through)
    rng = np.random.default_rng(3)
    betas = [np.zeros(problem.n_free)] + [rng.normal(0, 0.6, problem.n_free) for _ in range(5)]
    cases = []
    for beta in betas:
        path = problem.polynomials(beta)
        cases.append((through, path))
        lowest = _clearance(through).smallest(path, 201)[0]
        radius = max(0.001, 0.05 + lowest - 0.02)  # the path clears it by about 2 cm
        clear = _clearance(_ball(folder, radius)).smallest(path, 201)[0]
        if clear > 0.0:
            cases.append((_ball(folder, radius, clear + 1e-4), path))
    return cases


def test_dip_floors_hold_and_spare_searches_without_changing_the_lowest_point(
    tmp_path, monkeypatch
):
    cases = _cases(tmp_path)
    seen: list[tuple[object, object, np.ndarray, np.ndarray, np.ndarray]] = []
    real_floors = clearance_module.minima_floors

    def recording(model, path, t, minima, tables):
        found = real_floors(model, path, t, minima, tables)
        seen.append((model, path, t.copy(), minima.copy(), found.copy()))
        return found

    searches = [0]
    real_search = samples_module.scalar_minimum

    def counted(*args, **kwargs):
        searches[0] += 1
        return real_search(*args, **kwargs)

    monkeypatch.setattr(samples_module, "scalar_minimum", counted)
    monkeypatch.setattr(clearance_module, "minima_floors", recording)
    with_floors = [_clearance(s)._solvers_check(p) for s, p in cases]
    run_with = searches[0]
    monkeypatch.setattr(clearance_module, "minima_floors", lambda *a: np.full(len(a[3]), -np.inf))
    without = [_clearance(s)._solvers_check(p) for s, p in cases]
    run_without = searches[0] - run_with

    assert sum(w[1] is not None for w in with_floors) >= 8  # most break the margin
    assert with_floors == without  # the same bound, lowest value, time and pair, to the bit
    assert run_with < run_without  # and fewer scalar searches
    halved = [t for _, _, t, _, _ in seen if len(t) > 201]
    assert halved  # the thin margins made the check measure samples between the first ones

    checked = 0
    for model, path, t, minima, floors in seen:
        for k, floor in zip(minima.tolist(), floors.tolist(), strict=True):
            lo, hi = t[max(k - 1, 0)], t[min(k + 1, len(t) - 1)]
            dense = path.positions(np.linspace(lo, hi, 41))
            truth = min(float(np.min(model.distances(q).values)) for q in dense)
            assert floor <= truth + 1e-12
            checked += 1
    assert checked >= 10


@pytest.mark.parametrize("offset", [-1, 1])
def test_a_dip_next_to_a_spared_sample_has_no_floor(tmp_path, offset):
    """A sample the check spared (NaN bounds: it lay above the limit) bounds nothing: the
    floor of a minimum beside it is -inf, so its search always runs."""
    scenario = _ball(tmp_path)
    model = _clearance(scenario).model
    path = ff.problem_from_scenario(scenario).polynomials(np.zeros(3))
    t = np.linspace(0.0, path.duration, 7)
    q = path.positions(t)
    found = model.closest_many(q, t / path.duration)
    table = found.lower.copy()
    arms = samples_module.lever_arms(model, q)
    table[3 + offset], arms[3 + offset] = np.nan, np.nan
    floors = samples_module.minima_floors(model, path, t, np.array([3, 5]), (table, arms))
    assert floors[0] == -np.inf
    # the other minimum has the spared sample beside it only when it lies after the first
    assert (floors[1] == -np.inf) == (offset == 1)
