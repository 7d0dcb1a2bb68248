"""The servicer cache: a composed robot's file is reused only while its digest vouches for it.

An inline ``[robot]`` servicer's URDF edited in the cache (the spacecraft made 1000 kg
instead of 100) was read back and planned with, without a word. Truth: the spacecraft
body's mass in the model the planner loaded (Pinocchio's; the box's 100 kg with the arm's
fixed mounting link) against that of the servicer as first composed, and the file's own
text after the next load.
"""

from __future__ import annotations

import hashlib

import freefloat as ff

SCENARIO = """
duration = 20.0
[robot]
arm = "ur5"
base_mass = 100.0
base_size = [0.6, 0.6, 0.6]
mount = [0.3, 0.0, 0.0]
mount_rpy_deg = [0.0, 90.0, 0.0]
[start.joints]
shoulder_pan_joint = 0.0
shoulder_lift_joint = -90.0
elbow_joint = 90.0
wrist_1_joint = -90.0
wrist_2_joint = -90.0
wrist_3_joint = 0.0
[goal.joints]
shoulder_pan_joint = 10.0
shoulder_lift_joint = -80.0
elbow_joint = 80.0
wrist_1_joint = -90.0
wrist_2_joint = -90.0
wrist_3_joint = 0.0
"""


def _spacecraft_mass(scenario: ff.Scenario) -> float:
    return float(scenario.robot.model.inertias[1].mass)


def test_an_edited_cache_file_is_composed_again_and_rewritten(tmp_path, monkeypatch):
    monkeypatch.setenv("FREEFLOAT_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "inline.toml"
    path.write_text(SCENARIO)
    first = ff.Scenario.from_toml(path)
    composed = _spacecraft_mass(first)
    assert 100.0 <= composed < 110.0
    urdf = first.write_robot()
    digest = urdf.with_name(urdf.name + ".sha256")
    text = urdf.read_text()
    assert digest.read_text().strip() == hashlib.sha256(text.encode()).hexdigest()
    assert _spacecraft_mass(ff.Scenario.from_toml(path)) == composed  # reused: vouched for
    assert '<mass value="100.0"/>' in text
    urdf.write_text(text.replace('<mass value="100.0"/>', '<mass value="1000.0"/>', 1))
    again = ff.Scenario.from_toml(path)
    assert _spacecraft_mass(again) == composed
    again.write_robot()
    assert urdf.read_text() == text  # rewritten as composed
    digest.unlink()  # a file of a freefloat that wrote no digest: composed again
    urdf.write_text(text.replace('<mass value="100.0"/>', '<mass value="1000.0"/>', 1))
    assert _spacecraft_mass(ff.Scenario.from_toml(path)) == composed
