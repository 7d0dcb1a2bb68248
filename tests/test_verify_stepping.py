"""Step-doubling verdicts: a refusal needs two converging doublings in a row.

An open-loop forward-dynamics replay can be erratic (its error grows without bound over a long
motion): the difference between two step counts may then shrink 8-fold once by chance, and the
verifier refused a valid plan on it (a Kinova servicer goal inside the reach's inner set). The
truth here is RK4's own convergence on an ODE with a closed-form solution, against a sequence
that does not converge.
"""

from __future__ import annotations

import itertools
import math

import freefloat as ff
from freefloat.verify.stepping import _decided

TOLERANCE = 1e-4


def _rk4_exp(steps: int) -> float:
    """y' = y on [0, 1] from y(0) = 1 by RK4 (the exact value is e)."""
    h, y = 1.0 / steps, 1.0
    for _ in range(steps):
        k1 = y
        k2 = y + h / 2 * k1
        k3 = y + h / 2 * k2
        k4 = y + h * k3
        y += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return y


def _verdict(results: list[float], target: float) -> tuple[bool, float] | None:
    """Doubling loop of the verifier over ``results`` (one per step count, doubling).

    Returns (passed, value) once decided, None when never decided (no verdict).
    """
    previous = earlier = math.inf
    for coarse, fine in itertools.pairwise(results):
        value, estimate = abs(fine - target), abs(fine - coarse)
        if _decided(value, estimate, previous, TOLERANCE, 0.01, earlier):
            return value <= TOLERANCE + estimate, value  # as Check.passed judges it
        earlier, previous = previous, estimate
    return None


def test_a_converging_integration_is_decided_both_ways() -> None:
    results = [_rk4_exp(2**k) for k in range(1, 10)]
    passed = _verdict(results, math.e)
    assert passed is not None and passed[0]  # converges to e: passes
    refused = _verdict(results, math.e + 0.5)  # a wrong target: refused, the value near 0.5
    assert refused is not None and not refused[0]
    assert abs(refused[1] - 0.5) < 1e-6


def test_an_erratic_sequence_that_shrinks_once_gives_no_verdict() -> None:
    # Differences 4.0, 1.2, 0.15: the last shrinks 8-fold, the one before only 3.3-fold.
    results = [5.0, 1.0, 2.2, 2.05]
    assert _verdict(results, 0.0) is None
    # Without the earlier difference (the former rule) the same sequence was refused.
    assert _decided(2.05, 0.15, 1.2, TOLERANCE, 0.01)


def test_a_first_chance_agreement_decides_nothing() -> None:
    # The first doubling (nothing before it) agreeing to 1e-6 on a value far over the
    # tolerance: no convergence is shown yet, so no refusal; nor an acceptance, whose estimate
    # bounds the error only once the differences shrink (unless it is below rounding).
    assert not _decided(1.0, 1e-6, math.inf, TOLERANCE, 0.01, math.inf)
    assert not _decided(1e-6, 1e-7, math.inf, TOLERANCE, 0.01, math.inf)
    assert _decided(1e-6, 1e-7, 2e-6, TOLERANCE, 0.01, math.inf)  # shrunk 20-fold
    assert _decided(1e-6, 1e-9, math.inf, TOLERANCE, 0.01, math.inf)  # below 1e-5 of it
    # A value over the tolerance by less than a small estimate is not refused either.
    assert not _decided(1.05 * TOLERANCE, 0.1 * TOLERANCE, 1.0, TOLERANCE, 0.01, 8.0)


def test_a_check_within_its_own_error_of_the_tolerance_gives_no_verdict() -> None:
    """Within the tolerance whatever its own error: ok; within its own error of it, either
    side: no verdict (not refused); beyond both: FAILED."""
    from freefloat.plans.guarantees import Check

    assert Check("replay_attitude", 5e-5, 1e-4, "rad", 2e-5).verdict == "ok"
    assert Check("replay_attitude", 5e-5, 1e-4, "rad", 2e-3).verdict == "no verdict"
    undecided = Check("replay_attitude", 2.7, 1e-4, "rad", 2.7)
    assert undecided.verdict == "no verdict" and undecided.passed
    assert Check("replay_attitude", 3e-4, 1e-4, "rad", 1e-5).verdict == "FAILED"
    assert Check("replay_attitude", math.nan, 1e-4, "rad", 1.0).verdict == "FAILED"


def test_a_replay_allowed_other_steps_is_judged_not_compared(worked_plan, tmp_path, capsys):
    """The worked example's replay needs 32 steps; allowed 16 it cannot converge: its
    figures differ from the file's (made with the default cap), which is no mismatch. The
    table says 'no verdict' for it, and the plan is not refused."""
    from freefloat.cli import main

    path = worked_plan.save(tmp_path / "worked.plan.json")
    result = ff.verify_plan(ff.Plan.load(path), replay_steps=16)
    replay = result["replay_attitude"]
    assert "not converged" in replay.detail and replay.verdict == "no verdict" and result.passed
    assert replay.value != worked_plan.verification["replay_attitude"].value
    assert main(["verify", str(path), "--replay-steps", "16"]) == 0
    row = next(x for x in capsys.readouterr().out.splitlines() if "replay_attitude" in x)
    assert row.endswith("no verdict")


def test_the_attitude_integrator_is_fifth_order_against_a_closed_form() -> None:
    """A base turning about a fixed body axis at the rate ``1 + sin 3t`` (rad/s) for 2 s: the
    exact attitude is the start turned by ``2 + (1 - cos 6) / 3`` rad about that axis. The
    verification's integrator (Butcher's fifth order, stages on the quarters) comes within
    1e-5 rad on 8 steps and its error falls more than 20-fold per doubling (RK4: 16)."""
    import numpy as np

    from freefloat.physics.attitude import quat_multiply
    from freefloat.verify.stepping import _rk5_attitude

    axis = np.array([1.0, -2.0, 2.0]) / 3.0
    duration, start = 2.0, ff.quat_from_zyx(0.3, -0.2, 0.1)
    angle = duration + (1.0 - math.cos(3.0 * duration)) / 3.0
    turn = np.append(axis * math.sin(angle / 2.0), math.cos(angle / 2.0))
    exact = quat_multiply(start, turn)
    errors = []
    for steps in (8, 16, 32):
        t = np.linspace(0.0, duration, 4 * steps + 1)
        omega = (1.0 + np.sin(3.0 * t))[:, None] * axis
        errors.append(ff.geodesic_angle(_rk5_attitude(start, omega, duration), exact))
    assert 1e-12 < errors[0] < 1e-5
    assert errors[1] < errors[0] / 20.0 and errors[2] < errors[1] / 20.0
