"""ZYX Euler angles at and near gimbal lock (issue 26): the conversion gives back the attitude
to rounding at every pitch, so a plan whose goal pitch is 90 deg verifies and plots."""

from __future__ import annotations

import math

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.physics.attitude import quat_from_zyx, quat_multiply, zyx_from_quat

from conftest import ROOT


def _rotation(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll) as a matrix (the truth, not via quaternions)."""
    cy, sy, cp, sp, cr, sr = (f(a) for a in (yaw, pitch, roll) for f in (math.cos, math.sin))
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def _matrix(q: np.ndarray) -> np.ndarray:
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_euler_angles_give_back_the_attitude_near_the_lock():
    rng = np.random.default_rng(26)
    worst = 0.0
    for _ in range(5_000):
        side = rng.choice([-1.0, 1.0])
        pitch = side * math.pi / 2 * (1.0 - 10.0 ** rng.uniform(-17, -1))
        q = quat_from_zyx(rng.uniform(-4, 4), pitch, rng.uniform(-4, 4))
        q *= rng.choice([-1.0, 1.0])  # either sign of the same attitude
        yaw, pitch_back, roll = zyx_from_quat(q)
        assert -math.pi < yaw <= math.pi and -math.pi < roll <= math.pi
        assert abs(pitch_back) <= math.pi / 2
        worst = max(worst, np.abs(_rotation(yaw, pitch_back, roll) - _matrix(q)).max())
    assert worst < 1e-12


def test_at_the_lock_roll_is_zero():
    for pitch in (math.pi / 2, -math.pi / 2):
        q = quat_from_zyx(0.3, pitch, 0.2)
        yaw, back, roll = zyx_from_quat(q)
        assert roll == 0.0 and back == pytest.approx(pitch, abs=1e-15)
        np.testing.assert_allclose(_rotation(yaw, back, roll), _matrix(q), atol=1e-14)


def test_a_panda_plan_whose_goal_pitch_is_90_deg_verifies_and_plots(tmp_path, capsys):
    """Start where the shipped Panda motion ends at pitch 90 deg exactly (the base's turn is
    the same from any start attitude): the samples near the end are at the lock."""
    shipped = ROOT / "robots" / "scenarios" / "panda_servicer.toml"
    turn = quat_from_zyx(*np.radians([-6.4, -8.8, -4.1]))  # the shipped goal from identity
    goal = quat_from_zyx(0.0, math.pi / 2, 0.0)
    start = quat_multiply(goal, turn * np.array([-1, -1, -1, 1]))
    start_deg = ", ".join(repr(float(a)) for a in np.degrees(zyx_from_quat(start)))
    text = shipped.read_text().replace(
        "base_zyx_deg = [0.0, 0.0, 0.0]", f"base_zyx_deg = [{start_deg}]"
    )
    text = text.replace("[-6.4, -8.8, -4.1]", "[0.0, 90.0, 0.0]")
    scenario = tmp_path / "pitch90.toml"
    scenario.write_text(
        text.replace('"panda_servicer"', f'"{ROOT / "robots" / "panda_servicer.urdf"}"')
    )
    plan = ff.plan(ff.Scenario.from_toml(scenario))
    assert plan.samples.base_zyx_deg[-1][1] == pytest.approx(90.0, abs=1e-6)
    path = plan.save(tmp_path / "p.json")
    assert main(["verify", "-q", str(path)]) == 0, capsys.readouterr()
    # plot verifies first (as above: it refused this plan before), then draws
    from freefloat.viz.plots import figures

    drawn = figures(ff.Plan.load(path), topics=("base_attitude",))
    assert "base_attitude" in drawn
