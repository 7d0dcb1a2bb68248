"""A correction keeps a pointing cone where the mission fixed it in space.

``freefloat correct`` starts from the measured attitude. It read the plan's cone direction,
given in the plan's start frame, in that new start frame: the cone turned with the whole
plan's turn, and a "verified" correction took the antenna 15.8 deg from the mission's
direction, beyond its 12 deg. Truth here: SciPy's DOP853 integration of the attitude from
Pinocchio's centroidal map (test_base_swing.scipy_largest) and SciPy's rotations.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import freefloat as ff
from freefloat.physics.attitude import quat_from_zyx
from freefloat.problem.constraints import BasePointing, BaseSwing, JointPositionLimits
from freefloat.robust.plan_robustness import correct_plan
from test_base_swing import scipy_largest

#: The shipped Panda servicer with its z axis held within 12 deg of where it started; its goal
#: attitude tilts that axis 9.7 deg.
CONE = """
[constraints.base_pointing]
axis = [0.0, 0.0, 1.0]
half_angle_deg = 12.0
"""


SCENARIOS = Path(__file__).resolve().parents[1] / "robots" / "scenarios"


@pytest.fixture(scope="module")
def coned(tmp_path_factory):
    path = tmp_path_factory.mktemp("cone") / "panda.toml"
    path.write_text((SCENARIOS / "panda_servicer.toml").read_text() + CONE)
    scenario = ff.Scenario.from_toml(path)
    return ff.plan(scenario), scenario.robot


def test_the_restarted_cone_points_where_it_did_in_space():
    """Closed form: a start turned 90 deg about z sees a direction along x along -y."""
    cone = BasePointing([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], math.radians(30.0))
    turn = Rotation.from_euler("z", 90.0, degrees=True).as_quat()
    np.testing.assert_allclose(cone.restarted(turn).direction, [0.0, -1.0, 0.0], atol=1e-15)
    assert cone.restarted(turn).axis.tolist() == [0.0, 0.0, 1.0]
    swing, limits = BaseSwing(0.1), JointPositionLimits()  # measured from the own start
    assert swing.restarted(turn) is swing and limits.restarted(turn) is limits


def test_a_correction_keeps_the_boresight_in_the_missions_cone(coned):
    plan, robot = coned
    measured = [-5.0, -10.5, -5.5]  # the z axis 11.8 deg from the mission's direction
    corrected = correct_plan(plan, measured).plan
    assert corrected is not None
    start = Rotation.from_quat(plan.base.start_quaternion_xyzw)
    mission = start.apply([0.0, 0.0, 1.0])  # the cone's direction in space
    at = Rotation.from_euler("ZYX", measured, degrees=True)  # yaw, pitch, roll
    same = abs(float(at.as_quat() @ quat_from_zyx(*np.radians(measured))))
    assert same == pytest.approx(1.0, abs=1e-12)  # freefloat's convention, SciPy's rotation

    def from_mission(y: np.ndarray) -> np.ndarray:
        axes = (at * Rotation.from_quat(np.atleast_2d(np.asarray(y).T))).apply([0.0, 0.0, 1.0])
        return np.arccos(np.clip(axes @ mission, -1.0, 1.0))

    largest, _ = scipy_largest(corrected, robot, from_mission)
    assert math.degrees(largest) <= 12.0 + 1e-6
    record = next(c for c in corrected.constraints if c.name == "base_pointing")
    direction = np.asarray(record.parameters["direction"])
    np.testing.assert_allclose(direction, at.inv().apply(mission), atol=1e-12)
    assert record.parameters["half_angle_deg"] == 12.0


def test_a_measured_attitude_outside_the_cone_is_refused_with_its_angle(coned):
    plan, _ = coned
    measured = [-5.0, -12.0, -6.0]
    start = Rotation.from_quat(plan.base.start_quaternion_xyzw)
    axis = Rotation.from_euler("ZYX", measured, degrees=True).apply([0.0, 0.0, 1.0])
    angle = math.degrees(math.acos(axis @ start.apply([0.0, 0.0, 1.0])))
    with pytest.raises(ff.GoalAttitudeError) as info:
        correct_plan(plan, measured)
    assert (info.value.where, info.value.constraint) == ("measured", "base_pointing")
    assert str(info.value) == (
        f"measured attitude breaks base_pointing (the boresight {angle:.3g} deg from the "
        "direction, at most 12 deg allowed), where the correcting motion starts: no "
        "correction from it keeps the plan's [constraints.base_pointing]"
    )
