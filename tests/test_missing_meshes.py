"""An arm whose mesh files are missing composes, plans and plays (simple shapes), with a warning."""

from __future__ import annotations

import logging

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.robot.compose import ServicerSpec, compose_servicer
from freefloat.viz.playback import build_playback, write_html
from freefloat.viz.urdf_visuals import MISSING_MESH_RADIUS, visual_model

from conftest import ROOT

CYLINDER = '<geometry><cylinder radius="0.05" length="1.0"/></geometry>'


def _meshless_urdf(tmp_path):
    text = (ROOT / "robots" / "planar_2dof.urdf").read_text()
    assert text.count(CYLINDER) >= 1
    text = text.replace(CYLINDER, '<geometry><mesh filename="meshes/link.stl"/></geometry>', 1)
    path = tmp_path / "meshless.urdf"
    path.write_text(text)
    return path


def test_compose_warns_instead_of_refusing(tmp_path, caplog):
    arm = _meshless_urdf(tmp_path)
    spec = ServicerSpec(arm=str(arm), base_mass=500.0, base_size=(1.0, 1.0, 1.0))
    with caplog.at_level(logging.WARNING, logger="freefloat"):
        path = compose_servicer(spec, tmp_path / "servicer.urdf")
    assert path.is_file() and ff.load_robot(path).n == 2
    assert any("mesh file(s) of the arm cannot be found" in r.getMessage() for r in caplog.records)


def test_plan_and_playback_draw_a_sphere_for_the_missing_mesh(tmp_path, caplog, worked_plan):
    urdf = _meshless_urdf(tmp_path)
    scenario = (ROOT / "robots" / "scenarios" / "worked_example.toml").read_text()
    path = tmp_path / "meshless.toml"
    path.write_text(scenario.replace('robot = "planar_2dof"', f'robot = "{urdf}"'))
    plan = ff.plan(ff.Scenario.from_toml(path))
    np.testing.assert_allclose(plan.samples.q, worked_plan.samples.q, atol=1e-12)
    with caplog.at_level(logging.WARNING, logger="freefloat"):
        visual = visual_model(ff.load_robot(urdf))
        playback = build_playback(plan)
        nodes = set(playback.frames[0])
        page = write_html(plan, tmp_path / "page.html")
    link1 = next(v for v in visual if v.name.startswith("link1"))
    assert (link1.shape, link1.size) == ("sphere", (MISSING_MESH_RADIUS,))
    assert any(name.lower().endswith("link1_0") for name in nodes)  # the link is still drawn
    assert page.is_file() and page.stat().st_size > 0
    messages = [r.getMessage() for r in caplog.records]
    assert any(
        "meshes/link.stl" in m and f"spheres of {MISSING_MESH_RADIUS:g} m" in m for m in messages
    )


def test_links_without_visuals_are_drawn_from_their_collisions_or_said_undrawn(tmp_path, caplog):
    """Robonaut 2 and a composed Canadarm2 showed no robot: their links have no <visual>.
    link1's <visual> becomes a <collision> (a 0.07 m sphere here): drawn from it, as its
    URDF states it; link2's is removed: a body with mass and nothing to draw, said so."""
    text = (ROOT / "robots" / "planar_2dof.urdf").read_text()
    first = text.index("<visual>", text.index('<link name="link1">'))
    end = text.index("</visual>", first) + len("</visual>")
    text = (
        text[:first]
        + (
            '<collision><origin xyz="0.5 0 0"/><geometry><sphere radius="0.07"/></geometry>'
            "</collision>"
        )
        + text[end:]
    )
    second = text.index("<visual>", text.index('<link name="link2">'))
    text = text[:second] + text[text.index("</visual>", second) + len("</visual>") :]
    path = tmp_path / "bare.urdf"
    path.write_text(text)
    with caplog.at_level(logging.WARNING, logger="freefloat"):
        drawn = {v.name: v for v in visual_model(ff.load_robot(path))}
    assert (drawn["link1_0"].shape, drawn["link1_0"].size) == ("sphere", (0.07,))
    assert drawn["link1_0"].element == "collision" and drawn["base_0"].element == "visual"
    assert drawn["link1_0"].placement.translation == pytest.approx([0.5, 0.0, 0.0])
    # link2 (nothing to draw): a ball at its frame, a rod to its child joint at x = 1 m (its
    # URDF's ee_joint origin); Robonaut 2, Canadarm2 and VISPA showed only their trails
    assert sorted(n for n in drawn if n.startswith("link2")) == ["link2_rod0", "link2_skeleton"]
    ball, rod = drawn["link2_skeleton"], drawn["link2_rod0"]
    robot = ff.load_robot(path)
    frame = robot.model.frames[robot.model.getFrameId("link2", pin.FrameType.BODY)]
    assert (ball.shape, ball.element) == ("sphere", "skeleton")
    assert ball.placement.isApprox(frame.placement) and ball.joint == frame.parentJoint
    assert rod.shape == "capsule" and rod.size[1] == pytest.approx(1.0)
    local = frame.placement.actInv(rod.placement)  # in link2's frame
    assert local.translation == pytest.approx([0.5, 0.0, 0.0], abs=1e-12)
    assert local.rotation[:, 2] == pytest.approx([1.0, 0.0, 0.0], abs=1e-12)  # along the rod
    said = [r.getMessage() for r in caplog.records]
    assert any("have no <visual> (e.g. link1): drawn from their <collision>" in m for m in said)
    assert any(
        "neither a <visual> nor a <collision> shape (e.g. link2): drawn as a skeleton" in m
        for m in said
    )
