"""Collision models kept per source: shared by fresh loads, rebuilt on a change, history-free."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import time
from pathlib import Path

import numpy as np

import freefloat as ff
from freefloat.physics import attitude as att
from freefloat.problem.constraints import Clearance, registry
from freefloat.problem.constraints.registry import cached_collision_model, scenario_constraints
from freefloat.robot.collision import known_srdf
from freefloat.robot.geometry import BuiltPerSource
from freefloat.robust.inertial import perturbed_robot
from freefloat.verify import clearance_check
from freefloat.verify.clearance import MeshClearance

from conftest import ROOT

PANDA = ROOT / "robots" / "scenarios" / "panda_servicer.toml"


def _fresh() -> ff.Scenario:
    return ff.Scenario.from_toml(PANDA)


def _models(scenario: ff.Scenario, srdf: Path | None = None):
    robot = scenario.robot
    srdf = srdf or known_srdf(robot)
    model = cached_collision_model(robot, srdf, scenario.safety.obstacles)
    return model, clearance_check.mesh_clearance(robot, Clearance(model, scenario.safety.margin))


def test_fresh_loads_of_one_file_share_the_models_and_a_mass_change_keeps_them():
    first, second = _fresh(), _fresh()
    assert first.robot is not second.robot and first.robot.model is not second.robot.model
    assert _models(first)[0] is _models(second)[0]
    assert _models(first)[1] is _models(second)[1]
    link = first.robot.link_names[-1]
    heavier = perturbed_robot(first.robot, {link: {"mass": 1.1}})  # the same geometry
    assert heavier.model is not first.robot.model
    assert cached_collision_model(heavier, known_srdf(first.robot), ()) is (
        cached_collision_model(first.robot, known_srdf(first.robot), ())
    )


def test_an_edited_srdf_or_another_tree_gets_its_own_models(tmp_path):
    scenario = _fresh()
    srdf = tmp_path / "robot.srdf"
    original = Path(known_srdf(scenario.robot)).read_text()
    srdf.write_text(original)
    before = _models(scenario, srdf)
    assert _models(_fresh(), srdf)[0] is before[0]
    model = before[0]
    a, b = model.pairs[0]
    frames, objects = scenario.robot.model.frames, model.geometry.geometryObjects
    links = frames[objects[a].parentFrame].name, frames[objects[b].parentFrame].name
    extra = f'<disable_collisions link1="{links[0]}" link2="{links[1]}" reason="test"/>'
    srdf.write_text(original.replace("</robot>", extra + "\n</robot>"))
    os.utime(srdf, ns=(srdf.stat().st_atime_ns, srdf.stat().st_mtime_ns + 10**9))
    after = _models(_fresh(), srdf)
    assert after[0] is not before[0] and after[1] is not before[1]
    assert after[0].n_pairs == before[0].n_pairs - 1 and (a, b) not in after[0].pairs
    # another kinematic tree from the same text: a joint moved 1 cm
    moved = _fresh().robot
    moved.model.jointPlacements[3].translation = moved.model.jointPlacements[3].translation + 0.01
    assert cached_collision_model(moved, srdf, ()) is not cached_collision_model(
        _fresh().robot, srdf, ()
    )


def _same_size_rewrite(path: Path, text: str) -> None:
    """Write ``text`` (as long as the file's content) and set the modification time back."""
    info = path.stat()
    assert len(text.encode()) == info.st_size
    path.write_text(text)
    os.utime(path, ns=(info.st_atime_ns, info.st_mtime_ns))
    assert path.stat().st_mtime_ns == info.st_mtime_ns and path.stat().st_size == info.st_size


def test_an_srdf_rewritten_at_the_same_size_and_time_gets_its_own_models(tmp_path):
    """Path, modification time and size all stay: the pairs follow the file's new content."""
    scenario = _fresh()
    srdf = tmp_path / "robot.srdf"
    original = Path(known_srdf(scenario.robot)).read_text()
    srdf.write_text(original)
    model = _models(scenario, srdf)[0]
    a, b = model.pairs[0]
    frames, objects = scenario.robot.model.frames, model.geometry.geometryObjects
    links = frames[objects[a].parentFrame].name, frames[objects[b].parentFrame].name
    line = f'<disable_collisions link1="{links[0]}" link2="{links[1]}" reason="test"/>'
    comment = "<!--" + line[4:-3] + "-->"  # the same length, disabling nothing
    srdf.write_text(original.replace("</robot>", comment + "\n</robot>"))
    checked = _models(_fresh(), srdf)[0]
    assert (a, b) in checked.pairs
    _same_size_rewrite(srdf, original.replace("</robot>", line + "\n</robot>"))
    disabled = _models(_fresh(), srdf)[0]
    assert (a, b) not in disabled.pairs and disabled.n_pairs == checked.n_pairs - 1
    _same_size_rewrite(srdf, original.replace("</robot>", comment + "\n</robot>"))
    assert (a, b) in _models(_fresh(), srdf)[0].pairs


def test_a_file_stamp_changes_with_the_content_fresh_or_still(tmp_path, monkeypatch):
    """A fresh file is told by its digest alone (every time the file system reports kept the
    same); a still one by its change time (every write sets it; setting the modification time
    back does not); a stamp compared with one that holds a digest holds one too."""
    import types

    from freefloat.robot import file_stamp

    path = tmp_path / "mesh.stl"
    path.write_bytes(b"solid a\nendsolid a\n")
    info = path.stat()
    frozen = types.SimpleNamespace(  # what os.stat reports, whatever is written
        st_mtime_ns=time.time_ns(),
        st_ctime_ns=time.time_ns(),
        st_ino=7,
        st_size=info.st_size,
        st_mode=info.st_mode,
    )
    with monkeypatch.context() as patched:
        patched.setattr(file_stamp.os, "stat", lambda _: frozen)
        fresh = file_stamp.file_stamp(str(path))
        assert fresh[-1] and fresh == file_stamp.file_stamp(str(path))
        path.write_bytes(b"solid b\nendsolid b\n")  # the same size, the same reported times
        assert file_stamp.file_stamp(str(path)) != fresh  # the digest alone tells
    monkeypatch.setattr(file_stamp, "FRESH_S", -1.0)  # as if every file had been still
    still = file_stamp.file_stamp(str(path))
    assert still[-1] == "" and still == file_stamp.file_stamp(str(path))
    assert file_stamp.file_stamp(str(path), like=fresh)[-1]  # compared with a digest: one
    for _ in range(200):  # a write in a later tick of the file system's clock
        _same_size_rewrite(path, "solid c\nendsolid c\n")
        if path.stat().st_ctime_ns != still[2]:
            break
        time.sleep(0.01)
    again = file_stamp.file_stamp(str(path))
    assert again[1] == still[1] and again[4] == still[4]  # the same modification time, size
    assert again != still
    assert file_stamp.file_stamp(str(tmp_path / "gone"))[1:5] == (-1, -1, -1, -1)


def _untimed(plan: ff.Plan) -> str:
    data = json.loads(plan.to_json())
    for timing in ("wall_time_s", "solve_time_s", "sample_time_s", "verify_time_s"):
        data["solver"].pop(timing)
    return json.dumps(data, sort_keys=True)


def test_a_plan_with_the_kept_models_is_the_plan_with_models_built_afresh(monkeypatch):
    """The kept models carry bounds from earlier plans: which pairs a query measures may
    differ, never a figure of the plan (byte for byte, timings aside)."""
    turned = dataclasses.replace(
        _fresh(),
        goal_attitude=att.quat_multiply(_fresh().goal_attitude, att.quat_exp([0.0, 0.05, 0.0])),
    )
    ff.plan(turned)  # the kept models now carry that plan's bounds
    kept = _untimed(ff.plan(_fresh()))
    monkeypatch.setattr(registry, "_MODELS", BuiltPerSource(registry._MODELS._build))
    monkeypatch.setattr(clearance_check, "_MODELS", BuiltPerSource(clearance_check._MODELS._build))
    scenario = _fresh()
    assert any(c.name == "clearance" for c in scenario_constraints(scenario.resolved()))
    assert _untimed(ff.plan(scenario)) == kept
    assert math.isfinite(json.loads(kept)["verification"]["checks"][0]["value"])


def test_a_robot_changed_after_its_models_were_kept_changes_no_kept_model(monkeypatch):
    """The models are built on a copy of the first caller's Pinocchio model: a joint of that
    robot moved afterwards leaves a fresh load's distances those of models built afresh."""
    monkeypatch.setattr(registry, "_MODELS", BuiltPerSource(registry._MODELS._build))
    monkeypatch.setattr(clearance_check, "_MODELS", BuiltPerSource(MeshClearance))
    first = _fresh()
    kept, kept_mesh = _models(first)
    placement = first.robot.model.jointPlacements[3]
    placement.translation = placement.translation + 0.2
    first.robot.model.jointPlacements[3] = placement
    fresh = _fresh().robot
    assert _models(_fresh()) == (kept, kept_mesh)
    built = registry.collision_model(fresh, known_srdf(fresh), first.safety.obstacles)
    joints = np.asarray(_fresh().start, dtype=float)
    assert np.array_equal(kept.distances(joints).values, built.distances(joints).values)
    again = MeshClearance(fresh, known_srdf(fresh), first.safety.obstacles)
    assert np.array_equal(kept_mesh.placements(joints), again.placements(joints))


def test_collision_geometry_is_the_loaded_texts_when_the_file_changes_on_disk(tmp_path):
    """A robot loaded from a file that is rewritten afterwards keeps the collision geometry of
    the text it was loaded from (what its models are kept under and its plans carry): the box
    the original text states, not the one now on disk; a fresh load gets the new box."""
    from freefloat.robot.geometry import load_collision_geometry

    text = (ROOT / "robots" / "planar_2dof.urdf").read_text()
    link = ff.load_robot(ROOT / "robots" / "planar_2dof.urdf").link_names[-1]
    box = '<collision><geometry><box size="{} 0.1 0.1"/></geometry></collision>'
    marker = f'<link name="{link}">'
    assert marker in text
    path = tmp_path / "two_link.urdf"
    path.write_text(text.replace(marker, marker + box.format(0.3)))
    loaded = ff.load_robot(path)
    path.write_text(text.replace(marker, marker + box.format(0.7)))
    os.utime(path, ns=(path.stat().st_atime_ns, path.stat().st_mtime_ns + 10**9))

    def sizes(robot: ff.Robot) -> list[float]:
        objects = load_collision_geometry(robot).geometryObjects
        return [float(2.0 * obj.geometry.halfSide[0]) for obj in objects]

    assert sizes(loaded) == [0.3]
    assert sizes(ff.load_robot(path)) == [0.7]
