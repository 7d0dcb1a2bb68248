"""Playback of keep-out objects and the clearance figure, against independent truth."""

from __future__ import annotations

import base64
import dataclasses
import gzip
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import umsgpack
from PIL import Image

import freefloat as ff
from freefloat.plans.guarantees import SafetyReport
from freefloat.plans.records import sha256_hex
from freefloat.robot.collision import CollisionModel, Obstacle
from freefloat.viz.clearance_curve import clearance_curve
from freefloat.viz.playback import EXTRAS, build_playback, obstacle_node, write_html
from freefloat.viz.plots import figures, save_figures

from conftest import ROOT

PANEL = Obstacle("panel", "box", (0.2, 0.4, 0.6), (0.3, -1.2, 0.1), (0.0, 0.0, 0.5))
BALL = Obstacle("ball", "sphere", (0.25,), (-1.0, 0.8, 0.0), (0.0, 0.0, 0.0))
ROD = Obstacle("rod", "capsule", (0.05, 0.8), (0.0, 1.2, 0.0), (math.pi / 2, 0.0, 0.0))


@pytest.fixture(scope="module")
def guarded_plan(worked_plan):
    return dataclasses.replace(
        worked_plan, safety=SafetyReport(checked=False, obstacles=[PANEL, BALL, ROD])
    )


def _commands(page: str) -> list[dict]:
    packed = json.loads(re.search(r"const commands = (\[.*?\]);", page).group(1))
    return [umsgpack.unpackb(gzip.decompress(base64.b64decode(c))) for c in packed]


def _pose(xyz, rpy) -> np.ndarray:
    """Closed form: the homogeneous matrix of a position and roll-pitch-yaw (Rz Ry Rx)."""
    r, p, y = rpy
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    out = np.eye(4)
    out[:3, :3] = rz @ ry @ rx
    out[:3, 3] = xyz
    return out


def _quat_matrix(xyzw) -> np.ndarray:
    x, y, z, w = xyzw
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_obstacles_move_with_the_spacecraft(guarded_plan):
    s = guarded_plan.samples
    pb = build_playback(guarded_plan)
    for record in (PANEL, BALL, ROD):
        node = obstacle_node(record.name)
        local = _pose(record.xyz, record.rpy)
        for k in range(0, len(s.t), 25):
            base = np.eye(4)
            base[:3, :3] = _quat_matrix(s.base_quaternion_xyzw[k])
            base[:3, 3] = s.base_position[k]
            np.testing.assert_allclose(pb.frames[k][node], base @ local, atol=1e-12)
    # the base turns during the plan, so the obstacles do too
    first, last = pb.frames[0][obstacle_node("panel")], pb.frames[-1][obstacle_node("panel")]
    assert np.abs(first[:3, :3] - last[:3, :3]).max() > 1e-3


def test_standalone_html_contains_the_obstacles(guarded_plan, tmp_path):
    page = write_html(guarded_plan, tmp_path / "guarded.html").read_text()
    commands = _commands(page)
    objects = {
        c["path"]: c["object"]
        for c in commands
        if c["type"] == "set_object" and "obstacles" in c["path"]
    }
    prefix = f"/meshcat/{EXTRAS}/obstacles"

    def geometry(path):
        obj = objects[path]
        return obj["geometries"][0], obj["materials"][0]

    box, material = geometry(f"{prefix}/panel")
    assert box["type"] == "BoxGeometry"
    assert [box["width"], box["height"], box["depth"]] == pytest.approx(PANEL.size)
    assert material["transparent"] is True and 0.0 < material["opacity"] < 1.0
    red, green, blue = (
        (material["color"] >> 16) & 255,
        (material["color"] >> 8) & 255,
        material["color"] & 255,
    )
    assert red > 200 and green < 80 and blue < 80
    sphere, _ = geometry(f"{prefix}/ball")
    assert sphere["type"] == "SphereGeometry" and sphere["radius"] == pytest.approx(0.25)
    cylinder, _ = geometry(f"{prefix}/rod/cylinder")
    assert cylinder["type"] == "CylinderGeometry"
    assert cylinder["height"] == pytest.approx(0.8) and cylinder["radiusTop"] == pytest.approx(0.05)
    for end in ("top", "bottom"):
        cap, _ = geometry(f"{prefix}/rod/{end}")
        assert cap["type"] == "SphereGeometry" and cap["radius"] == pytest.approx(0.05)
    # animated with the base: one position track per obstacle node, one key per sample
    animation = next(c for c in commands if c["type"] == "set_animation")
    tracked = {a["path"]: a["clip"]["tracks"] for a in animation["animations"]}
    n = len(guarded_plan.samples.t)
    for name in ("panel", "ball", "rod"):
        tracks = {t["name"]: t for t in tracked[f"{prefix}/{name}"]}
        keys = tracks[".position"]["keys"]
        assert [key["time"] for key in keys] == list(range(n))
        expected = guarded_plan.samples.base_position[-1]
        record = {"panel": PANEL, "ball": BALL, "rod": ROD}[name]
        rot = _quat_matrix(guarded_plan.samples.base_quaternion_xyzw[-1])
        np.testing.assert_allclose(
            keys[-1]["value"], rot @ record.xyz + np.asarray(expected), atol=1e-9
        )
    assert "keep-out objects" in page  # legend


def test_plan_without_obstacles_draws_none(worked_plan):
    pb = build_playback(worked_plan)
    assert not [name for name in pb.frames[0] if "/obstacles/" in name]


#: The worked example's planar arm with collision shapes: a base box and a ball at the tip.
def _collision_urdf(tmp_path) -> str:
    text = (ROOT / "robots" / "planar_2dof.urdf").read_text()
    hull = '<box size="1.0 1.0 1.0"/></geometry>'
    text = text.replace("</visual>", f"</visual>\n    <collision><geometry>{hull}</collision>", 1)
    marker = '<link name="link2">'
    head, tail = text.split(marker)
    tail = tail.replace(
        "</link>",
        '<collision><origin xyz="1.0 0 0"/><geometry><sphere radius="0.1"/></geometry>'
        "</collision></link>",
        1,
    )
    path = tmp_path / "planar_collide.urdf"
    path.write_text(head + marker + tail)
    return str(path)


@pytest.fixture(scope="module")
def checked_plan(worked_plan, tmp_path_factory):
    urdf = _collision_urdf(tmp_path_factory.mktemp("collide"))
    text = Path(urdf).read_text(encoding="utf-8")  # the same robot, with collision geometry
    return dataclasses.replace(
        worked_plan,
        robot=dataclasses.replace(
            worked_plan.robot, urdf=urdf, urdf_text=text, urdf_sha256=sha256_hex(text)
        ),
        safety=SafetyReport(checked=True, margin_m=0.05, obstacles=[BALL]),
    )


def _tip(plan, q) -> np.ndarray:
    """Closed form: the tip ball's centre in the spacecraft frame (m)."""
    q1, q2 = q
    return np.array([0.5 + math.cos(q1) + math.cos(q1 + q2), math.sin(q1) + math.sin(q1 + q2), 0])


def test_clearance_curve_equals_collision_distances(checked_plan):
    curve = clearance_curve(checked_plan, samples=41)
    assert curve is not None and len(curve.t) == 41
    assert curve.t[0] == 0.0 and curve.t[-1] == pytest.approx(checked_plan.duration)
    assert curve.margin == 0.05
    robot = ff.load_robot(checked_plan.robot.urdf)
    model = CollisionModel(robot, None, [Obstacle("ball", "sphere", (0.25,), (-1.0, 0.8, 0.0))])
    assert sorted(curve.names) == sorted(model.names)
    for k in (0, 10, 23, 40):
        q = checked_plan.joint_positions(curve.t[k])
        values = model.distances(q).values
        assert curve.smallest[k] == pytest.approx(values.min(), abs=1e-9)
        assert curve.names[curve.pair[k]] == model.names[int(np.argmin(values))]
        # independent: the tip ball against the obstacle ball, in closed form
        ball = values[model.names.index(next(n for n in model.names if "obstacle:ball" in n))]
        gap = np.linalg.norm(_tip(checked_plan, q) - np.array(BALL.xyz)) - 0.1 - 0.25
        assert ball == pytest.approx(gap, abs=1e-6)
        assert curve.smallest[k] <= gap + 1e-9


def test_the_figures_closest_point_is_refined_between_samples(checked_plan):
    """The figure's label took the lowest of its 400 samples, not refined (Canadarm2 with a
    payload: 0.01184 m at 153 s against the plan's 0.011226 m at 152.2 s). Truth: every
    pair's distance (brute force) on an instant grid 50 times as dense, its lowest point the
    vertex of the parabola through the three lowest neighbours."""
    curve = clearance_curve(checked_plan, samples=41)
    robot = ff.load_robot(checked_plan.robot.urdf)
    model = CollisionModel(robot, None, [Obstacle("ball", "sphere", (0.25,), (-1.0, 0.8, 0.0))])
    dense = np.linspace(0.0, checked_plan.duration, 2001)
    truth = [model.distances(q).values.min() for q in checked_plan.joint_positions(dense)]
    k = int(np.argmin(truth))
    value, when, pair = curve.closest
    assert curve.smallest.min() - truth[k] > 1e-6  # the samples alone miss the lowest point
    a, b, c = np.polyfit(dense[k - 1 : k + 2] - dense[k], truth[k - 1 : k + 2], 2)
    vertex, at = c - b * b / (4.0 * a), dense[k] - b / (2.0 * a)
    assert value <= truth[k] and value == pytest.approx(vertex, abs=1e-9)
    assert when == pytest.approx(at, abs=1e-4)
    q = checked_plan.joint_positions(np.array([when]))[0]
    assert pair == model.names[int(np.argmin(model.distances(q).values))]


def test_clearance_figure_is_drawn_and_written(checked_plan, worked_plan, tmp_path):
    import matplotlib.pyplot as plt

    plt.close("all")
    figs = figures(checked_plan)
    ax = figs["clearance"].axes[0]
    curve = clearance_curve(checked_plan)
    line = next(line for line in ax.lines if line.get_label() == "smallest clearance")
    np.testing.assert_allclose(line.get_ydata(), curve.smallest)
    margin = next(line for line in ax.lines if line.get_label() == "margin")
    assert margin.get_linestyle() == "--" and margin.get_ydata()[0] == 0.05
    _, _, pair = curve.closest
    assert any(pair in text.get_text() for text in ax.get_legend().get_texts())
    assert "[m]" in ax.get_ylabel() and "[s]" in ax.get_xlabel()
    plt.close("all")
    assert "clearance" not in figures(worked_plan)  # not checked: no figure
    plt.close("all")
    written = save_figures(checked_plan, tmp_path / "figs")
    png = tmp_path / "figs" / "clearance.png"
    assert png in written
    with Image.open(png) as img:
        assert np.asarray(img.convert("L")).std() > 5


def test_a_clearance_that_stays_put_is_refined_once_not_per_sample():
    """A closest pair at a constant distance made every sample a local minimum, each refined
    by its own search: 11 348 distance queries for a 400-sample figure. A run of equal
    samples is refined once (and at most a few minima in all)."""
    from types import SimpleNamespace

    from freefloat.viz import clearance_curve as module

    calls = []

    class Flat:
        def closest_value(self, q):
            calls.append(q)
            return 0.1, 0

    t = np.linspace(0.0, 10.0, 400)
    plan = SimpleNamespace(duration=10.0, joint_positions=lambda s: np.zeros((len(s), 2)))
    low = module._lowest(Flat(), plan, t, np.full(400, 0.1), np.zeros(400, dtype=int))
    assert (low.distance, low.pair) == (0.1, 0)
    assert 0 < len(calls) <= 2 * 60  # one bounded search, not 400
