"""An objective's SLSQP run that stops short keeps the best point it met within its rows.

On a real satellite (ETS-VII under ``min_effort``) SLSQP stopped with "Inequality constraints
incompatible" after passing points at a quarter of the start's effort within every clearance
row, its last point deep in collision; the minimum-norm path was kept. Here SLSQP is made to
stop the same way on the shipped Panda servicer: after a few iterations, reporting failure,
its last point thrown far off. Truth: the plan's independent verification (coal on the
meshes, the forward-dynamics replay) and its effort integrated afresh from the plan file's
polynomials (inverse dynamics at 96 Gauss nodes, not the objective's quadrature).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize

import freefloat as ff
from freefloat.solvers.optimise import FALLBACK_NOTE
from freefloat.verify.checks import joint_torque_function
from freefloat.viz.summary import objective_line

from conftest import ROOT

PANDA = ROOT / "robots" / "scenarios" / "panda_servicer.toml"


def _effort(plan: ff.Plan, robot: ff.Robot) -> float:
    """Integral of |tau|^2 dt (N^2 m^2 s) by a 96-node Gauss rule on [0, T]."""
    tau = joint_torque_function(plan, ff.MomentumMap(robot))
    x, w = np.polynomial.legendre.leggauss(96)
    t = 0.5 * plan.duration * (x + 1.0)
    return (
        0.5
        * plan.duration
        * sum(wi * float(tau(ti) @ tau(ti)) for ti, wi in zip(t, w, strict=True))
    )


#: How the cut run's last point is left: far off (its path, polished, breaks the joint
#: limits), not a number (no candidate at all), or back at the start (no lower value).
ENDS = {
    "far": lambda x, x0: np.asarray(x) + 50.0,
    "nan": lambda x, x0: np.full_like(np.asarray(x, dtype=float), np.nan),
    "start": lambda x, x0: np.array(x0, dtype=float),
}


def _stopping_short(iterations: int, end: str = "far"):
    """SciPy's ``minimize`` cut to ``iterations`` SLSQP iterations, failing, its last point
    left as ``end`` says (:data:`ENDS`)."""
    real = scipy.optimize.minimize

    def minimize(fun, x0, **kwargs):  # type: ignore[no-untyped-def]
        options = {**kwargs.pop("options", {}), "maxiter": iterations}
        result = real(fun, x0, options=options, **kwargs)
        result.success = False
        result.status, result.message = 4, "Inequality constraints incompatible"
        result.x = ENDS[end](result.x, x0)
        return result

    return minimize


@pytest.fixture(scope="module")
def scenario() -> ff.Scenario:
    return ff.Scenario.from_toml(PANDA)


@pytest.mark.parametrize("end", sorted(ENDS))
def test_a_run_that_stops_short_keeps_the_best_point_within_its_rows(scenario, monkeypatch, end):
    """However the run's last point is left, the plan keeps a lower-effort path than the
    minimum-norm one, within every constraint (verification passes on the meshes), and its
    effort as the plan file gives it is the reported value and below the minimum-norm
    path's."""
    minimum_norm = ff.plan(scenario)
    start = _effort(minimum_norm, scenario.robot)
    monkeypatch.setattr(scipy.optimize, "minimize", _stopping_short(4, end))
    plan = ff.plan(scenario, objective="min_effort")
    assert plan.verification.passed
    report = plan.objective
    assert report is not None and report.start_value == pytest.approx(start, rel=1e-6)
    effort = _effort(plan, scenario.robot)
    assert effort == pytest.approx(report.value, rel=1e-6)
    assert effort < 0.99 * start
    note = f"{FALLBACK_NOTE} (Inequality constraints incompatible)"  # as the cut run ends
    assert [level.note for level in report.levels][-1] == note
    assert objective_line(plan).endswith(f"; found as {note}")


def test_without_a_point_within_the_rows_the_minimum_norm_path_stands(scenario, monkeypatch):
    """Cut to no iteration, SLSQP meets only its start (which lowers nothing): the
    minimum-norm path is kept, and said to be."""
    monkeypatch.setattr(scipy.optimize, "minimize", _stopping_short(0))
    plan = ff.plan(scenario, objective="min_effort")
    report = plan.objective
    assert report is not None and report.value == report.start_value
    assert plan.verification.passed


def test_the_journal_lists_points_within_every_row_lowest_objective_first():
    """Closed form: rows ``z0 >= 0`` and ``1 - z1 >= 0``, objective ``z0 + z1``; the points
    within both rows below 5 come lowest first, the others (a row negative, a row never asked,
    not a number) never."""
    from freefloat.solvers.iterates import Journal

    journal = Journal(2)
    objective = journal.objective_of(lambda z: float(z[0] + z[1]))
    first = journal.inequality(0, lambda z: np.array([z[0], 1.0]))
    second = journal.inequality(1, lambda z: np.array([1.0 - z[1]]))
    points = [[1.0, 0.5], [0.2, 0.1], [-0.1, 0.0], [3.0, 3.0], [9.0, 0.0], [np.nan, 0.0]]
    for point in points:
        z = np.array(point)
        objective(z), first(z), second(z)
    lonely = np.array([0.0, 0.0])
    objective(lonely), first(lonely)  # the second row never asked there
    best = journal.best(5.0, 3)
    assert [list(z) for z in best] == [[0.2, 0.1], [1.0, 0.5]]
    assert [list(z) for z in journal.best(1.0, 3)] == [[0.2, 0.1]]


def test_corrections_that_fail_numerically_leave_a_verified_plan(scenario, monkeypatch):
    """The least-norm corrections raising (as a point far off may make them) neither stop the
    plan nor let a path within no constraint through: the plan verifies, and its effort is at
    most the minimum-norm path's."""
    import numpy.linalg

    import freefloat.solvers.optimise as optimise

    def failing(*args, **kwargs):  # type: ignore[no-untyped-def]
        raise numpy.linalg.LinAlgError("SVD did not converge")

    monkeypatch.setattr(scipy.optimize, "minimize", _stopping_short(4, "far"))
    monkeypatch.setattr(optimise, "nearest_root_within", failing)
    plan = ff.plan(scenario, objective="min_effort")
    assert plan.verification.passed
    assert plan.objective.value <= plan.objective.start_value
