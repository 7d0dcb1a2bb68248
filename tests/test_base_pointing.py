"""The pointing cone of a spacecraft axis (``[constraints.base_pointing]``).

Truth the code under test does not compute: SciPy's DOP853 integration of the attitude from
Pinocchio's centroidal map, written out in the tests (test_base_swing.scipy_largest), and
SciPy's rotations for the start and goal. The Jacobian against finite differences and the
record's round trip are in the plug-in contract (test_plugins).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import freefloat as ff
from freefloat.cli import main
from freefloat.errors import InputError
from freefloat.problem.constraints import BasePointing, constraint_from_record
from test_base_swing import REORIENTATION, scipy_largest

#: The Panda servicer's reorientation turns it 3 deg about its z axis: the z axis ends where
#: it started, but tilts on the way.
BORESIGHT = np.array([0.0, 0.0, 1.0])


def _tilt(y: np.ndarray) -> np.ndarray:
    """Angle (rad) of the spacecraft's z axis from its start direction, per column of y."""
    rotations = Rotation.from_quat(np.atleast_2d(np.asarray(y).T))
    return np.arccos(np.clip(rotations.apply(BORESIGHT) @ BORESIGHT, -1.0, 1.0))


def test_a_boresight_is_kept_in_its_cone(tmp_path, capsys):
    scenario_path = tmp_path / "free.toml"
    scenario_path.write_text(REORIENTATION)
    scenario = ff.Scenario.from_toml(scenario_path)
    free, _ = scipy_largest(ff.plan(scenario), scenario.robot, _tilt)
    assert math.degrees(free) > 4.0  # unbounded, the z axis tilts 4.8 deg on the way
    bounded = tmp_path / "bounded.toml"
    bounded.write_text(
        REORIENTATION + "\n[constraints.base_pointing]\naxis = [0, 0, 1]\nhalf_angle_deg = 3\n"
    )
    out = tmp_path / "plan.json"
    assert main(["plan", str(bounded), "-o", str(out), "-q"]) == 0
    plan = ff.Plan.load(out)
    tilt, _ = scipy_largest(plan, scenario.robot, _tilt)
    assert math.degrees(tilt) <= 3.0 + 1e-6
    data = json.loads(out.read_text())
    record = next(c for c in data["constraints"] if c["name"] == "base_pointing")
    assert record["parameters"] == {
        "axis": [0.0, 0.0, 1.0],
        "direction": [0.0, 0.0, 1.0],
        "half_angle_deg": 3.0,
    }
    check = next(c for c in data["verification"]["checks"] if c["name"] == "base_pointing")
    assert check["value"] == pytest.approx(tilt - math.radians(3.0), abs=1e-8)
    assert main(["verify", str(out)]) == 0
    capsys.readouterr()


def test_a_start_or_goal_outside_the_cone_is_refused_before_any_search(tmp_path, capsys):
    # The goal turns the spacecraft 3 deg about z: its x axis ends 3 deg from where it
    # started (SciPy's rotation), beyond a 2 deg cone.
    turned = Rotation.from_euler("z", 3.0, degrees=True).apply([1.0, 0.0, 0.0])
    angle = math.degrees(math.acos(turned @ [1.0, 0.0, 0.0]))
    path = tmp_path / "s.toml"
    path.write_text(
        REORIENTATION + "\n[constraints.base_pointing]\naxis = [1, 0, 0]\nhalf_angle_deg = 2\n"
    )
    with pytest.raises(ff.GoalAttitudeError) as info:
        ff.plan(ff.Scenario.from_toml(path))
    assert (info.value.where, info.value.constraint) == ("goal", "base_pointing")
    assert str(info.value) == (
        f"goal attitude breaks base_pointing (the boresight {angle:.4g} deg from the "
        "direction, at most 2 deg allowed), where every path ends; choose a goal attitude "
        "it allows or loosen [constraints.base_pointing]"
    )
    assert info.value.excess == pytest.approx(math.radians(angle - 2.0), abs=1e-12)
    # a direction 10 deg from the boresight: already outside at the start
    tilted = [math.cos(math.radians(10.0)), math.sin(math.radians(10.0)), 0.0]
    path.write_text(
        REORIENTATION + "\n[constraints.base_pointing]\naxis = [1, 0, 0]\n"
        f"direction = {tilted}\nhalf_angle_deg = 5\n"
    )
    assert main(["plan", str(path), "-o", str(tmp_path / "p.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "start attitude breaks base_pointing (the boresight 10 deg from the direction" in err
    assert "change the start attitude or loosen [constraints.base_pointing]" in err


@pytest.mark.parametrize(
    ("record", "said"),
    [
        ({"half_angle_deg": 5}, "base_pointing: missing 'axis'; its keys are axis, direction,"),
        ({"axis": [1, 0, 0]}, "base_pointing: missing 'half_angle_deg'"),
        ({"axis": [1, 0, 0], "half_angle_deg": 5, "up": 1}, "unknown key 'up'"),
        ({"axis": [0, 0, 0], "half_angle_deg": 5}, "base_pointing axis must be a non-zero"),
        ({"axis": [1, 0], "half_angle_deg": 5}, "base_pointing axis must be 3 numbers"),
        ({"axis": [1, 0, 0], "direction": "x", "half_angle_deg": 5}, "direction must be 3"),
        ({"axis": [1, 0, 0], "half_angle_deg": 180}, "between 0 and 180 (exclusive;"),
        ({"axis": [1, 0, 0], "half_angle_deg": 5e-324}, "between 0 and 180 (exclusive;"),
        ({"axis": [1, 0, 0], "half_angle_deg": 179.99999999}, "at least 1e-6 rad from either"),
    ],
)
def test_bad_cones_are_named(record, said):
    with pytest.raises(InputError) as info:
        constraint_from_record("base_pointing", record)
    assert said in str(info.value)


def test_the_direction_defaults_to_the_boresight():
    cone = BasePointing([0.0, 0.0, 2.0], None, 0.1)
    assert cone.direction.tolist() == [0.0, 0.0, 1.0]
    assert cone.at_attitude(np.array([0.0, 0.0, 0.0, 1.0])).value == pytest.approx(-0.1)


def test_a_cone_near_a_half_turn_is_judged_in_radians():
    # A cosine gap of 1e-9 is 2.6 deg of angle at a half-angle of 180 deg: judged by the
    # cosine, a boresight turned right round passed a 179.9999 deg cone. SciPy's rotation of
    # the axis is the truth here.
    cone = BasePointing([1.0, 0.0, 0.0], None, math.radians(179.9999))
    turned = Rotation.from_euler("z", 180.0, degrees=True).as_quat()
    angle = math.acos(np.clip(Rotation.from_quat(turned).apply([1.0, 0.0, 0.0])[0], -1.0, 1.0))
    excess = cone.at_attitude(turned)
    assert excess.value == pytest.approx(angle - math.radians(179.9999), abs=1e-12)
    assert excess.value > 10 * cone.tolerance  # beyond: refused, not passed
    assert math.cos(cone.half_angle) - math.cos(angle) < 1e-9  # the cosine gap: "within"
