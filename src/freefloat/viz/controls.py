"""Visible playback controls injected into the standalone MeshCat page.

MeshCat hides its animation controls two folders deep in "Open Controls". The standalone page
gets, on top of the scene: the plan's title, play / pause / restart buttons, a time slider with
a readout in seconds of plan time, a speed choice, and a short legend of what is drawn. The
controls drive MeshCat's own animator (``viewer.animator``: ``play``, ``pause``, ``reset``,
``seek``, ``mixer.timeScale``); the animation clip runs at ``speed`` times real time, so plan
time is the clip's time multiplied by ``speed``.

Element ids (for tests and user styling): ``ff-title``, ``ff-play``, ``ff-pause``,
``ff-restart``, ``ff-time`` (slider), ``ff-readout``, ``ff-speed``, ``ff-legend``.
"""

from __future__ import annotations

import html
import json
import math
from pathlib import Path

from ..errors import ModelError
from ..excerpts import shortened
from ..plans.format import Plan
from ..robot.urdf_checks import urdf_document

__all__ = [
    "CM_COLOR",
    "EE_COLOR",
    "LEGEND",
    "TRAIL_COLORS",
    "inject_controls",
    "legend_entries",
    "plan_title",
    "robot_label",
]

#: Colours of the end-effector paths, in end-effector order (RGB; the fifth takes the first's).
TRAIL_COLORS = (0x1F77B4, 0xFF7F0E, 0x9467BD, 0x8C564B)
#: Colours of the end-effector marker and the CM marker (RGB).
EE_COLOR, CM_COLOR = 0x2CA02C, 0xD62728

#: What the page draws, with the colours playback.py uses (CSS hex); a plan with several end
#: effectors gets one path line per end effector (:func:`legend_entries`).
LEGEND = (
    (f"#{TRAIL_COLORS[0]:06x}", "end-effector path"),
    (f"#{EE_COLOR:06x}", "end effector (drawn over the arm)"),
    (f"#{CM_COLOR:06x}", "system centre of mass (origin, drawn over the spacecraft)"),
    ("linear-gradient(90deg,#f00,#0f0,#00f)", "axes: large inertial, small base (x y z)"),
)


def robot_label(plan: Plan) -> str:
    """The plan's robot as titles name it: its URDF copy's ``<robot name>``, else the file stem.

    (A composed or inline servicer's URDF lives in a cache under a content hash: its file name
    says nothing to a reader.)
    """
    if plan.robot.urdf_text:
        try:
            name = urdf_document(plan.robot.urdf_text).get("name", "").strip()
        except ModelError:
            name = ""
        if name:
            return shortened(name)
    return shortened(Path(plan.robot.urdf).stem)


def plan_title(plan: Plan) -> str:
    """One line naming the plan: robot, duration and the base attitude change (deg)."""
    start = plan.base.start_zyx_deg
    target = plan.base.target_zyx_deg
    angles = ", ".join(
        f"{axis} {a:.1f} to {b:.1f} deg"
        for axis, a, b in zip(("yaw", "pitch", "roll"), start, target, strict=True)
        if abs(a) > 1e-9 or abs(b) > 1e-9
    )
    title = f"{robot_label(plan)}: T = {plan.duration:g} s"
    return f"{title}, base {angles}" if angles else title


_STYLE = """
#ff-panel{position:fixed;left:12px;top:12px;z-index:10;max-width:420px;padding:10px 12px;
font:13px/1.4 system-ui,sans-serif;color:#222;background:rgba(255,255,255,.92);
border-radius:8px;box-shadow:0 1px 6px rgba(0,0,0,.25)}
#ff-title{font-size:15px;font-weight:600;margin:0 0 6px}
#ff-panel button{font:13px system-ui,sans-serif;padding:3px 10px;margin-right:4px;cursor:pointer}
#ff-time{width:100%;margin:6px 0 2px}
#ff-readout{font-variant-numeric:tabular-nums}
#ff-legend{margin:6px 0 0;padding:0;list-style:none;font-size:12px}
#ff-legend span{display:inline-block;width:14px;height:4px;margin-right:6px;vertical-align:middle}
"""

_SCRIPT = """
(function () {
  const cfg = __CONFIG__;
  const $ = (id) => document.getElementById(id);
  const slider = $("ff-time"), readout = $("ff-readout");
  let dragging = false;
  const animator = () => (window.viewer && viewer.animator) || null;
  const ready = () => { const a = animator(); return a && a.actions.length > 0 ? a : null; };
  const show = (t) => {
    readout.textContent = "t = " + t.toFixed(2) + " s / " + cfg.duration.toFixed(2) + " s";
    readout.dataset.seconds = t.toFixed(4);
  };
  $("ff-play").onclick = () => { const a = ready(); if (a && !a.playing) a.play(); };
  $("ff-pause").onclick = () => { const a = ready(); if (a) a.pause(); };
  $("ff-restart").onclick = () => { const a = ready(); if (a) { a.reset(); a.play(); } };
  $("ff-speed").onchange = (e) => {
    const a = ready(); if (a) a.mixer.timeScale = +e.target.value;
  };
  slider.oninput = () => {
    dragging = true; const a = ready();
    if (a) { a.seek(+slider.value / cfg.speed); a.display_progress(+slider.value / cfg.speed); }
    show(+slider.value);
  };
  slider.onchange = () => { dragging = false; };
  const tick = () => {
    const a = ready();
    if (a && !dragging) {
      const clip = a.actions.reduce((m, x) => Math.max(m, x.time), 0);
      const t = Math.min(cfg.duration, clip * cfg.speed);
      slider.value = t; show(t);
    }
  };
  show(0); setInterval(tick, 50);
})();
"""


def legend_entries(plan: Plan) -> list[tuple[str, str]]:
    """The page's legend for ``plan``: (CSS colour, text) per line.

    :data:`LEGEND`, with one path line per end effector when there are several (each in its
    trail's colour, named by its frame), and the keep-out objects when there are any.
    """
    frames = plan.robot.frames
    trails = [LEGEND[0]]
    if len(frames) > 1:
        trails = [
            (f"#{TRAIL_COLORS[k % len(TRAIL_COLORS)]:06x}", f"end-effector path ({frame})")
            for k, frame in enumerate(frames)
        ]
    kept_out = [("rgba(224,32,32,.45)", "keep-out objects")] if plan.safety.obstacles else []
    return [*trails, *LEGEND[1:], *kept_out]


def inject_controls(page: str, plan: Plan, speed: float = 1.0) -> str:
    """The standalone MeshCat ``page`` with the controls panel added before ``</body>``."""
    title = html.escape(plan_title(plan))
    legend = "".join(
        f'<li><span style="background:{colour}"></span>{html.escape(text)}</li>'
        for colour, text in legend_entries(plan)
    )
    speeds = "".join(
        f'<option value="{s}"{" selected" if s == 1 else ""}>{s:g}x</option>'
        for s in (0.25, 0.5, 1, 2, 4)
    )
    step = plan.duration / max(1, len(plan.samples.t) - 1)
    panel = (
        f'<div id="ff-panel"><div id="ff-title">{title}</div>'
        '<button id="ff-play" type="button">&#9654; Play</button>'
        '<button id="ff-pause" type="button">&#10074;&#10074; Pause</button>'
        '<button id="ff-restart" type="button">&#8634; Restart</button>'
        f'<label> speed <select id="ff-speed">{speeds}</select></label>'
        f'<input id="ff-time" type="range" min="0" max="{plan.duration!r}" '
        f'step="{step!r}" value="0" aria-label="time [s]">'
        '<div id="ff-readout">t = 0.00 s</div>'
        f'<ul id="ff-legend">{legend}</ul></div>'
    )
    config = json.dumps({"duration": plan.duration, "speed": speed if math.isfinite(speed) else 1})
    script = _SCRIPT.replace("__CONFIG__", config)
    addition = f"<style>{_STYLE}</style>{panel}<script>{script}</script>"
    page = page.replace("<title>MeshCat</title>", f"<title>{title} - freefloat</title>", 1)
    index = page.rfind("</body>")
    if index < 0:
        return page + addition
    return page[:index] + addition + page[index:]
