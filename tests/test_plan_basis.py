"""Format 4: a plan's paths from its file alone, older formats, path quality, the default path."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import integrate

import freefloat as ff
from freefloat.cli import main
from freefloat.physics.dynamics import inverse_dynamics_batch
from freefloat.verify.path_eval import file_path

from conftest import ROOT
from legacy import _monomials_in_s, as_format_3


def _from_file(doc: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q, qd, qdd at the plan's sample times from its JSON alone (numpy polynomials in s)."""
    T = doc["duration"]
    t = np.asarray(doc["samples"]["t"])
    out = []
    for i, name in enumerate(doc["robot"]["joints"]):
        c = np.polynomial.Polynomial(
            _monomials_in_s(
                doc["request"]["start_joints"][i],
                doc["request"]["goal_joints"][i],
                doc["path"]["coefficients"][name],
            )
        )
        out.append([c(t / T), c.deriv(1)(t / T) / T, c.deriv(2)(t / T) / T**2])
    return tuple(np.array([row[k] for row in out]).T for k in range(3))  # type: ignore[return-value]


@pytest.fixture(scope="module")
def richer_plan(worked_scenario) -> ff.Plan:
    """The worked example with 3 and 4 free parameters on its joints (minimum norm)."""
    import dataclasses

    scenario = dataclasses.replace(worked_scenario, extra={"q1": 3, "q2": 4})
    return ff.plan(scenario)


def test_a_plan_is_evaluated_from_its_file_alone(worked_plan, richer_plan):
    for plan in (worked_plan, richer_plan):
        doc = json.loads(plan.to_json())
        assert doc["format"] == "freefloat.plan/5"
        assert doc["path"]["basis"] == "quintic+jacobi66"
        q, qd, qdd = _from_file(doc)
        samples = doc["samples"]
        np.testing.assert_allclose(q, samples["q"], atol=1e-10)
        np.testing.assert_allclose(qd, samples["qd"], atol=1e-10)
        np.testing.assert_allclose(qdd, samples["qdd"], atol=1e-10)
    assert [len(v) for v in richer_plan.free_parameters.values()] == [3, 4]


def test_the_verifiers_jacobi_polynomials_are_scipys():
    """The file's basis as verification evaluates it (rescaled Gegenbauer polynomials) against
    SciPy's Jacobi polynomials, up to degree 80 and the two derivatives' parameters, on a dense
    grid of [-1, 1]: to 1e-12 of each polynomial's largest value."""
    from scipy.special import eval_jacobi

    from freefloat.verify.path_eval import _jacobi

    x = np.linspace(-1.0, 1.0, 801)
    n = np.arange(81)
    for shift in (0, 1, 2):
        got = _jacobi(n, shift, x)
        m = n - shift
        want = eval_jacobi(np.maximum(m, 0)[None, :], 6 + shift, 6 + shift, x[:, None])
        want = np.where(m[None, :] >= 0, want, 0.0)
        scale = np.maximum(np.abs(want).max(axis=0), 1e-300)
        assert np.all(np.abs(got - want) <= 1e-12 * scale)
        assert np.all(got[:, m < 0] == 0.0)


def test_verifying_a_plan_without_clearance_loads_no_special_functions(worked_plan, tmp_path):
    """SciPy's special functions cost a fresh process 0.15-0.25 s to import on the 2-core
    machine: ``freefloat verify`` of the worked example does without them."""
    import subprocess
    import sys

    path = worked_plan.save(tmp_path / "plan.json")
    code = (
        "import sys\nfrom freefloat.cli import main\n"
        f"code = main(['verify', {str(path)!r}, '-q'])\n"
        "print('scipy.special' in sys.modules)\nsys.exit(code)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "False"


def test_a_format_3_plan_still_loads_and_verifies(worked_plan, tmp_path, capsys):
    old = tmp_path / "old.json"
    old.write_text(json.dumps(as_format_3(json.loads(worked_plan.to_json()))))
    assert main(["verify", str(old)]) == 0, capsys.readouterr().err
    loaded = ff.Plan.load(old)
    assert loaded.format == "freefloat.plan/3" and loaded.basis == "monomial"
    # the figure for this plan in the old basis: "min_norm = 3044.85 rad^2"
    assert loaded.objective.value == pytest.approx(3044.85, abs=0.01)
    np.testing.assert_allclose(
        loaded.path().evaluate(np.linspace(0, 10, 5)).q,
        worked_plan.path().evaluate(np.linspace(0, 10, 5)).q,
        atol=1e-12,
    )
    assert json.loads(loaded.to_json())["format"] == "freefloat.plan/3"  # kept when re-written


def test_a_basis_that_does_not_belong_to_the_format_is_refused(worked_plan, tmp_path, capsys):
    doc = json.loads(worked_plan.to_json())
    del doc["path"]["basis"]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    assert main(["verify", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "path" in err and "basis" in err


def test_path_quality_is_the_dense_excursion(richer_plan):
    doc = json.loads(richer_plan.to_json())
    t = np.linspace(0.0, doc["duration"], 200001)
    dense = dict(doc, samples={"t": t.tolist()})
    q = _from_file(dense)[0]
    start = np.asarray(doc["request"]["start_joints"])
    goal = np.asarray(doc["request"]["goal_joints"])
    beyond = np.maximum.reduce(
        [np.zeros(2), q.max(0) - np.maximum(start, goal), np.minimum(start, goal) - q.min(0)]
    )
    quality = richer_plan.quality
    assert quality is not None
    got = [quality.excursion_beyond_span[n] for n in doc["robot"]["joints"]]
    np.testing.assert_allclose(got, np.degrees(beyond), atol=1e-6)
    assert quality.largest_excursion == pytest.approx(max(got))
    assert quality.largest_excursion > 1.0  # the property is not vacuous


def _deviation(doc: dict, free: dict) -> float:
    """int_0^1 |q - q_quintic|^2 ds of the path with ``free`` parameters (adaptive quadrature)."""
    polys = []
    for i, name in enumerate(doc["robot"]["joints"]):
        q0, q1 = doc["request"]["start_joints"][i], doc["request"]["goal_joints"][i]
        with_free = np.polynomial.Polynomial(_monomials_in_s(q0, q1, free[name]))
        quintic = np.polynomial.Polynomial(_monomials_in_s(q0, q1, []))
        polys.append(with_free - quintic)
    value, _ = integrate.quad(lambda s: sum(float(p(s)) ** 2 for p in polys), 0.0, 1.0)
    return value


def test_the_default_root_is_the_one_closest_to_the_quintic(worked_plan):
    doc = json.loads(worked_plan.to_json())
    roots = doc["solver"]["solutions"]
    deviations = [_deviation(doc, r["free_parameters"]) for r in roots]
    assert len(deviations) == 5
    assert deviations[0] == min(deviations)
    assert doc["objective"]["value"] == pytest.approx(deviations[0], rel=1e-9)
    assert doc["path_quality"]["deviation_rms_deg"] == pytest.approx(
        math.degrees(math.sqrt(deviations[0])), rel=1e-9
    )


def test_min_effort_reaches_within_two_percent_of_optimal_control(worked_scenario):
    plan = ff.plan(worked_scenario, objective="min_effort")
    mmap = ff.MomentumMap(ff.load_robot(ROOT / "robots" / "planar_2dof.urdf"))
    # Not the objective's quadrature nor its path evaluation: 200 Gauss nodes on the path as
    # verification evaluates the file (scipy's Jacobi polynomials; degree 21 is beyond what
    # monomials evaluate to this precision).
    x, w = np.polynomial.legendre.leggauss(200)
    t = 0.5 * plan.duration * (x + 1.0)
    torques = inverse_dynamics_batch(mmap, *file_path(plan)(t)).tau
    effort = 0.5 * plan.duration * float(w @ (torques**2).sum(axis=1))
    assert effort == pytest.approx(plan.objective.value, rel=1e-9)
    assert effort <= 26.6 * 1.02
    assert plan.verification.passed
