"""The playback page's own controls in headless Chromium: present, visible, and they drive time."""

from __future__ import annotations

import json
import re
import subprocess
import tempfile
from pathlib import Path

import pytest

from freefloat.viz.controls import plan_title
from freefloat.viz.playback import write_html

from browser import FLAGS, chromium

# Headless Chromium under a virtual time budget starves requestAnimationFrame, which drives
# MeshCat's animator in a real browser; the probe stands in for the frame loop (every 16 ms of
# page time) and then clicks the page's own buttons.
PROBE = """
<script>
window.addEventListener("load", () => {
  setInterval(() => viewer.animator.update(), 16);
  const $ = (id) => document.getElementById(id);
  const seconds = () => +$("ff-readout").dataset.seconds;
  const out = {};
  const ids = ["ff-title", "ff-play", "ff-pause", "ff-restart", "ff-time", "ff-readout",
               "ff-speed", "ff-legend"];
  out.visible = ids.filter((id) => $(id) && $(id).offsetWidth > 0 && $(id).offsetHeight > 0);
  setTimeout(() => {
    $("ff-pause").click();
    setTimeout(() => {
      out.paused_a = seconds();
      setTimeout(() => {
        out.paused_b = seconds();
        $("ff-play").click();
        setTimeout(() => {
          out.playing = seconds();
          $("ff-restart").click();
          $("ff-pause").click();
          setTimeout(() => {
            out.restarted = seconds();
            out.readout = $("ff-readout").textContent;
            const pre = document.createElement("pre");
            pre.id = "ff-probe";
            pre.textContent = JSON.stringify(out);
            document.body.appendChild(pre);
          }, 300);
        }, 1500);
      }, 1000);
    }, 300);
  }, 1500);
});
</script>
"""


@pytest.fixture(scope="module")
def page(worked_plan, tmp_path_factory):
    return write_html(worked_plan, tmp_path_factory.mktemp("controls") / "plan.html")


def test_page_carries_title_controls_and_legend(page, worked_plan):
    text = page.read_text()
    assert f"<title>{plan_title(worked_plan)} - freefloat</title>" in text
    assert plan_title(worked_plan) == "planar_2dof: T = 10 s, base yaw -50.0 to 0.0 deg"
    for needle in ("ff-play", "ff-pause", "ff-restart", 'id="ff-time"', "ff-speed", "ff-legend"):
        assert needle in text
    assert "end-effector path" in text and "system centre of mass" in text


def test_clicking_play_advances_the_time_readout(page):
    probed = page.with_name("probe.html")
    text = page.read_text()
    index = text.rfind("</body>")
    probed.write_text(text[:index] + PROBE + text[index:])
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as tmp:  # as in browser.py
        result = subprocess.run(
            [
                chromium(),
                *FLAGS,
                f"--user-data-dir={Path(tmp) / 'profile'}",
                "--virtual-time-budget=15000",
                "--dump-dom",
                probed.as_uri(),
            ],
            capture_output=True,
            text=True,
            check=True,
            timeout=180,
        )
    match = re.search(r'<pre id="ff-probe">(.*?)</pre>', result.stdout)
    assert match, result.stdout[-2000:]
    out = json.loads(match.group(1).replace("&quot;", '"'))
    assert sorted(out["visible"]) == sorted(
        [
            "ff-title",
            "ff-play",
            "ff-pause",
            "ff-restart",
            "ff-time",
            "ff-readout",
            "ff-speed",
            "ff-legend",
        ]
    )
    assert out["paused_a"] > 0.5  # it played on its own first
    assert out["paused_b"] == pytest.approx(out["paused_a"], abs=1e-3)  # pause holds the time
    assert out["playing"] > out["paused_b"] + 0.5  # play advances it (1.5 s of page time)
    assert out["restarted"] < 0.2  # restart goes back to 0
    assert re.fullmatch(r"t = \d+\.\d\d s / 10\.00 s", out["readout"])


def test_compact_page_keeps_every_scene_command(worked_plan):
    import base64
    import gzip

    from freefloat.viz.compact import compact_page
    from freefloat.viz.playback import build_playback

    playback = build_playback(worked_plan)
    original = playback.html()
    found = re.findall(r"base64,([A-Za-z0-9+/=]+)\"\)", original)
    compact = compact_page(original)
    packed = json.loads(re.search(r"const commands = (\[.*?\]);", compact).group(1))
    unpacked = [gzip.decompress(base64.b64decode(c)) for c in packed]
    assert sorted(unpacked) == sorted(base64.b64decode(c) for c in found)
    assert b"set_animation" in unpacked[-1][:32]  # the animation binds to the final objects
    assert compact_page("<html>not meshcat</html>") == "<html>not meshcat</html>"


def test_panda_page_is_a_few_megabytes(tmp_path):
    import base64
    import gzip

    import freefloat as ff

    from conftest import ROOT

    plan = ff.plan(ff.Scenario.from_toml(ROOT / "robots" / "scenarios" / "panda_servicer.toml"))
    page = write_html(plan, tmp_path / "panda.html")
    size = page.stat().st_size
    assert size < 8e6, f"{size / 1e6:.1f} MB"
    packed = json.loads(re.search(r"const commands = (\[.*?\]);", page.read_text()).group(1))
    commands = [gzip.decompress(base64.b64decode(c)) for c in packed]
    assert any(b"/visuals/" in c for c in commands)
    assert not any(b"/collisions/" in c for c in commands)  # no second copy of the meshes


def test_titles_name_the_robot_not_its_cache_file(worked_plan):
    """A composed or inline servicer's URDF is a cache file named by a hash: titles (page and
    figures) take the URDF copy's ``<robot name>``; a plan without a copy, the file's stem."""
    from dataclasses import replace

    from freefloat.viz.plots import figures

    cached = replace(
        worked_plan,
        robot=replace(worked_plan.robot, urdf="/home/u/.cache/freefloat/3f9a1c0d7e.urdf"),
    )
    assert plan_title(cached).startswith("planar_2dof: T = 10 s")
    figure = figures(cached, ("base_rate",))["base_rate"]
    title = figure.axes[0].get_title()
    import matplotlib.pyplot as plt

    plt.close("all")  # the figures() call's sheets
    assert title == "base rate (planar_2dof, T = 10 s)"
    bare = replace(cached, robot=replace(cached.robot, urdf_text=""))
    assert plan_title(bare).startswith("3f9a1c0d7e: T = 10 s")
