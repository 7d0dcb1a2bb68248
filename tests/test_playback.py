"""Browser playback: recorded poses, standalone HTML in a real browser, no stray servers."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.viz.playback import EXTRAS, build_playback, write_html

from browser import screenshot


def _servers() -> int:
    out = subprocess.run(
        ["pgrep", "-f", "meshcat.servers.zmqserver"], capture_output=True, text=True, check=False
    )
    return len(out.stdout.split())


@pytest.fixture(scope="module")
def playback(worked_plan):
    return build_playback(worked_plan)


def _track(playback, node, prop):
    clip = next(c for path, c in playback.animation.clips.items() if path.lower().endswith(node))
    track = clip.tracks[prop]
    return track.frames, np.array(track.values)


def test_animation_base_pose_equals_samples(playback, worked_plan):
    s = worked_plan.samples
    frames, positions = _track(playback, f"{EXTRAS}/base_frame", "position")
    assert frames == list(range(len(s.t)))
    np.testing.assert_allclose(positions, np.array(s.base_position), atol=1e-12)
    _, quats = _track(playback, f"{EXTRAS}/base_frame", "quaternion")
    expected = np.array(s.base_quaternion_xyzw)
    signs = np.sign(np.sum(quats * expected, axis=1))[:, None]
    np.testing.assert_allclose(quats * signs, expected, atol=1e-12)
    assert playback.fps == pytest.approx((len(s.t) - 1) / worked_plan.duration)


def test_animation_link_poses_carry_the_joint_angles(playback, worked_plan):
    """Joint angles recovered from the recorded link poses equal the sampled joints."""
    s = worked_plan.samples
    r_off = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # URDF rpy 0 pi/2 0

    def rotations(name):
        _, quats = _track(playback, name, "quaternion")
        return [ff.physics.attitude.quat_to_matrix(q) for q in quats]

    base = [ff.physics.attitude.quat_to_matrix(np.array(q)) for q in s.base_quaternion_xyzw]
    link1, link2 = rotations("link1_0"), rotations("link2_0")
    for k in range(0, len(s.t), 20):
        rz1 = base[k].T @ link1[k] @ r_off.T
        rz2 = r_off @ link1[k].T @ link2[k] @ r_off.T
        assert np.arctan2(rz1[1, 0], rz1[0, 0]) == pytest.approx(
            np.arctan2(np.sin(s.q[k][0]), np.cos(s.q[k][0])), abs=1e-6
        )
        assert np.arctan2(rz2[1, 0], rz2[0, 0]) == pytest.approx(
            np.arctan2(np.sin(s.q[k][1]), np.cos(s.q[k][1])), abs=1e-6
        )
    _, tips = _track(playback, f"{EXTRAS}/end_effector", "position")
    np.testing.assert_allclose(tips, np.array(s.end_effector_position), atol=1e-12)


@pytest.fixture(scope="module")
def html_page(worked_plan, tmp_path_factory):
    before = _servers()
    path = write_html(worked_plan, tmp_path_factory.mktemp("html") / "plan.html")
    assert _servers() == before  # no server left after writing
    return path


def test_standalone_html_is_self_contained(html_page):
    text = html_page.read_text()
    assert "MeshCat.Viewer" in text and "set_animation" in text
    assert "http://" not in text.split("<script>")[0]  # nothing to fetch before the viewer


def test_browser_renders_and_animates(html_page):
    early, late = screenshot(html_page, 1500), screenshot(html_page, 6500)
    assert early.shape == (600, 800, 3)
    for shot in (early, late):  # not blank: the background gradient plus a lit robot
        assert shot.std() > 20.0
        assert len(np.unique(shot.reshape(-1, 3), axis=0)) > 200
    changed = np.abs(early - late).sum(axis=2) > 30
    assert changed.mean() > 0.002  # the robot moved between the two instants


def test_markers_are_drawn_on_top_in_the_legend_colours(html_page):
    """The CM lies inside the spacecraft and the end effector inside its own link: the page's
    scene commands (decoded here) draw both without depth test, in the legend's colours."""
    import base64
    import gzip
    import json
    import re

    import umsgpack

    from freefloat.viz.controls import LEGEND

    packed = json.loads(re.search(r"const commands = (\[.*?\]);", html_page.read_text()).group(1))
    objects = {}
    for item in packed:
        command = umsgpack.unpackb(gzip.decompress(base64.b64decode(item)))
        if command.get("type") == "set_object":
            objects[command["path"].rsplit("/", 1)[-1]] = command["object"]
    legend = {text.split(" (")[0]: css for css, text in LEGEND}
    for node, label in (("cm", "system centre of mass"), ("end_effector", "end effector")):
        material = objects[node]["materials"][0]
        assert material["depthTest"] is False and material["transparent"] is True
        assert f"#{material['color']:06x}" == legend[label]


def test_show_html_cli_leaves_no_server(tmp_path, worked_plan, capsys):
    plan_path = worked_plan.save(tmp_path / "p.json")
    before = _servers()
    assert main(["show", str(plan_path), "--html", str(tmp_path / "x.html"), "--speed", "2"]) == 0
    assert (tmp_path / "x.html").stat().st_size > 100_000
    assert _servers() == before
    assert "wrote" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("speed", "said"),
    [
        ("0", "--speed must be a positive number"),
        # slower, the page's animation times overflowed to infinity: nothing played
        ("1e-300", "--speed = 1e-300 is outside the supported range [0.001, 1000]"),
    ],
)
def test_bad_speed_is_refused(tmp_path, worked_plan, capsys, speed, said):
    plan_path = worked_plan.save(tmp_path / "p.json")
    page = tmp_path / "x.html"
    assert main(["show", str(plan_path), "--html", str(page), "--speed", speed]) == 2
    assert said in capsys.readouterr().err
    assert not page.exists()


def test_broken_meshcat_gives_a_clear_error(tmp_path, worked_plan):
    plan_path = worked_plan.save(tmp_path / "p.json")
    code = (
        "import sys; sys.modules['meshcat'] = None\n"
        "from freefloat.cli import main\n"
        f"sys.exit(main(['show', {str(plan_path)!r}, '--html', {str(tmp_path / 'y.html')!r}]))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=False
    )
    assert result.returncode == 2
    assert "the 3D viewer needs meshcat, which failed to import" in result.stderr
    assert "Traceback" not in result.stderr
    assert not (tmp_path / "y.html").exists()


def test_browser_plays_a_composed_servicer_with_meshes(tmp_path):
    from conftest import ROOT

    plan = ff.plan(
        ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "ur5_servicer.toml"), samples=61
    )
    pb = build_playback(plan)
    meshes = [name for name in pb.frames[0] if "shoulder" in name or "forearm" in name]
    assert meshes  # the UR5's mesh visuals are animated
    _, positions = _track(pb, f"{EXTRAS}/base_frame", "position")
    np.testing.assert_allclose(positions, np.array(plan.samples.base_position), atol=1e-12)
    page = write_html(plan, tmp_path / "ur5.html")
    text = page.read_text()
    assert "set_object" in text and len(text) > 1_000_000  # meshes are embedded
    early, late = screenshot(page, 2000), screenshot(page, 12000)
    for shot in (early, late):
        assert shot.std() > 20.0
        assert len(np.unique(shot.reshape(-1, 3), axis=0)) > 200
    assert (np.abs(early - late).sum(axis=2) > 30).mean() > 0.002


def test_show_serves_until_interrupted(tmp_path, worked_plan):
    import re
    import signal
    import socket
    import struct
    import time
    import urllib.request

    plan_path = worked_plan.save(tmp_path / "p.json")
    before = _servers()
    proc = subprocess.Popen(
        [sys.executable, "-m", "freefloat.cli", "show", str(plan_path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = proc.stdout.readline()
        match = re.search(r"open (http://127\.0\.0\.1:\d+/)", line)
        assert match, line
        page = urllib.request.urlopen(match.group(1), timeout=30).read().decode()
        assert "meshcat" in page.lower()
        # The served page is the standalone page, with its visible controls.
        assert 'id="ff-play"' in page and 'id="ff-title"' in page
        assert _servers() == before  # no MeshCat server is needed to serve it
        for _ in range(3):  # a client that leaves mid-page: no traceback from the server
            with socket.create_connection(
                ("127.0.0.1", int(match.group(1).split(":")[2][:-1]))
            ) as s:
                s.sendall(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
                s.recv(100)
                s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    finally:
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        code = proc.wait(timeout=30)
    assert code == 130  # Ctrl-C: the exit code of every command (README, docs/reference.md)
    assert proc.stderr.read() == "freefloat: interrupted\n"  # one line, no traceback
    time.sleep(0.5)
    assert _servers() == before
