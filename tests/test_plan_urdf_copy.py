"""Self-contained plans (issue 26): a freefloat.plan/4 file carries its URDF and its SHA-256;
relative paths are read from the plan's folder; older files load with a warning."""

from __future__ import annotations

import hashlib
import json
import shutil

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main

from conftest import ROOT, as_older_format

PLANAR = ROOT / "robots" / "planar_2dof.urdf"


@pytest.fixture
def moved(tmp_path, worked_plan):
    """The worked plan pointing at a copy of its URDF in ``tmp_path/robot``; (plan, urdf)."""
    folder = tmp_path / "robot"
    folder.mkdir()
    urdf = folder / "robot.urdf"
    shutil.copy(PLANAR, urdf)
    doc = json.loads(worked_plan.to_json())
    doc["robot"]["urdf"] = str(urdf)
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(doc))
    return path, urdf


def test_a_plan_carries_its_urdf(worked_plan):
    assert worked_plan.format == "freefloat.plan/5"
    assert worked_plan.robot.urdf_text == PLANAR.read_text(encoding="utf-8")
    digest = hashlib.sha256(PLANAR.read_bytes()).hexdigest()  # the file's bytes: no BOM here
    assert worked_plan.robot.urdf_sha256 == digest


def test_a_plan_verifies_from_its_copy_when_the_urdf_is_gone(moved, capsys):
    path, urdf = moved
    urdf.unlink()  # a cleared cache
    assert main(["verify", str(path)]) == 0, capsys.readouterr().err
    assert "passed" in capsys.readouterr().out


def test_a_changed_urdf_is_refused_naming_both_sums(moved, capsys):
    path, urdf = moved
    urdf.write_text(PLANAR.read_text().replace('effort="', 'effort="0', 1) + " ")
    assert main(["verify", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"the URDF {urdf} has changed since the plan was made (SHA-256" in err


def test_an_edited_copy_is_refused_by_its_sum(moved, capsys):
    path, _ = moved
    doc = json.loads(path.read_text())
    doc["robot"]["urdf_text"] = doc["robot"]["urdf_text"].replace("40.0", "41.0", 1)
    path.write_text(json.dumps(doc))
    assert main(["verify", str(path)]) == 2
    err = capsys.readouterr().err
    assert "'robot.urdf_sha256'" in err and "is not the SHA-256 of 'robot.urdf_text'" in err


def test_a_relative_path_is_read_from_the_plans_folder(moved, tmp_path, monkeypatch, capsys):
    """From another folder holding another robot.urdf, the plan's own is used."""
    path, urdf = moved
    doc = json.loads(path.read_text())
    doc["robot"]["urdf"] = "robot/robot.urdf"
    doc = as_older_format(doc)  # as a format-3 file: only the path counts
    path.write_text(json.dumps(doc))
    elsewhere = tmp_path / "elsewhere"
    (elsewhere / "robot").mkdir(parents=True)
    heavier = PLANAR.read_text().replace('<mass value="40.0"/>', '<mass value="41.0"/>')
    (elsewhere / "robot" / "robot.urdf").write_text(heavier)
    monkeypatch.chdir(elsewhere)
    assert ff.Plan.load(path).robot.urdf == str(urdf)
    assert main(["verify", str(path)]) == 0, capsys.readouterr().err
    err = capsys.readouterr().err
    assert "a plan written before freefloat.plan/4 carries no copy of its URDF: read from" in err


def test_a_format_1_plan_is_not_called_format_3(moved, capsys):
    """A /1 file is kept as /3 in memory; the warning names no format it is not."""
    path, _ = moved
    doc = as_older_format(json.loads(path.read_text()))
    doc["format"] = "freefloat.plan/1"
    path.write_text(json.dumps(doc))
    assert main(["verify", str(path)]) == 0, capsys.readouterr().err
    err = capsys.readouterr().err
    assert "written before freefloat.plan/4 carries no copy" in err
    assert "plan/3" not in err


def test_a_format_4_plan_without_its_copy_is_refused(moved, capsys):
    path, _ = moved
    doc = json.loads(path.read_text())
    del doc["robot"]["urdf_text"]
    path.write_text(json.dumps(doc))
    assert main(["verify", str(path)]) == 2
    assert "robot.urdf_text: missing" in capsys.readouterr().err


def test_older_plans_keep_their_format(moved):
    path, _ = moved
    doc = json.loads(path.read_text())
    doc = as_older_format(doc)
    path.write_text(json.dumps(doc))
    again = json.loads(ff.Plan.load(path).to_json())
    assert again["format"] == "freefloat.plan/3" and "urdf_text" not in again["robot"]


def test_a_clearance_checked_plan_verifies_and_exports_when_its_urdf_is_gone(tmp_path, capsys):
    """Collision geometry and the export's root frame come from the plan's copy."""
    scenario = ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml")
    plan = ff.plan(scenario, samples=21)
    assert plan.safety.checked
    urdf = tmp_path / "cache" / "servicer.urdf"
    urdf.parent.mkdir()
    shutil.copy(scenario.robot.urdf, urdf)
    doc = json.loads(plan.to_json())
    doc["robot"]["urdf"] = str(urdf)
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(doc))
    urdf.unlink()
    shutil.rmtree(urdf.parent)  # a cleared cache
    assert main(["verify", str(path)]) == 0, capsys.readouterr().err
    assert "clearance" in capsys.readouterr().out
    from freefloat.export.messages import export_frames

    frames = export_frames(str(urdf), doc["robot"]["urdf_text"])
    # the UR5's URDF has a link named world: the inertial frame takes another name
    assert (frames.root, frames.inertial) == (scenario.robot.base_link, "freefloat_world")


def _elbow_limited(plan, tmp_path, upper, drop_rows):
    """The plan's file with the elbow's URDF upper limit set (rad), its ``constraints`` list
    emptied and, with ``drop_rows``, its joint-limit checks removed."""
    doc = json.loads(plan.to_json())
    text = doc["robot"]["urdf_text"]
    limit = text.index("<limit", text.index('<joint name="elbow_joint"'))
    field = text.index('upper="', limit) + len('upper="')
    text = text[:field] + repr(upper) + text[text.index('"', field) :]
    doc["robot"]["urdf_text"] = text
    doc["robot"]["urdf_sha256"] = hashlib.sha256(text.encode()).hexdigest()
    doc["robot"]["urdf"] = str(tmp_path / "gone.urdf")
    doc["constraints"] = []
    if drop_rows:
        checks = doc["verification"]["checks"]
        doc["verification"]["checks"] = [c for c in checks if not c["name"].startswith("joint_")]
    path = tmp_path / "emptied.json"
    path.write_text(json.dumps(doc))
    return path


def test_a_plan_is_held_to_its_urdf_limits_whatever_its_records(tmp_path, capsys):
    """The file's ``constraints`` list emptied: verify still recomputes the URDF's limit checks
    (a file that keeps its rows and its limits verifies; the old code refused it for the
    rows it no longer recomputed), so a file must list them (one with its rows removed is
    refused, which the old code passed), and an elbow limit lowered below the path's peak
    (sampled densely here) but above its start and goal is a value the recomputation
    disagrees with."""
    plan = ff.plan(ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml"))
    elbow = plan.robot.joints.index("elbow_joint")
    t = np.linspace(0.0, plan.duration, 20001)
    q = plan.joint_positions(t)[:, elbow]
    lowered = float(0.5 * (q.max() + max(q[0], q[-1])))
    assert q.max() > lowered + 1e-3 and lowered > max(q[0], q[-1]) + 1e-3
    intact = float(ff.load_robot(ROOT / "robots" / "ur5_servicer.urdf").joints[elbow].upper)
    assert main(["verify", str(_elbow_limited(plan, tmp_path, intact, False))]) == 0
    capsys.readouterr()
    assert main(["verify", str(_elbow_limited(plan, tmp_path, lowered, True))]) == 2
    assert "the recomputation momentum" in capsys.readouterr().err  # the lists differ
    assert main(["verify", str(_elbow_limited(plan, tmp_path, lowered, False))]) == 2
    err = capsys.readouterr().err
    assert "joint_position_limits" in err and "disagrees with the recomputation" in err
