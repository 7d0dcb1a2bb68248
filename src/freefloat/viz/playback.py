"""Browser 3D playback of a plan in MeshCat (a visualisation leaf: it only reads a plan).

The robot's visual geometry (URDF primitives or meshes) is drawn as meshcat objects
(:mod:`freefloat.viz.visuals`); each sample of the plan becomes one animation frame that places
every visual (base and arm together), so meshcat's animation controls play, pause and scrub it.
Also drawn: the end-effector trail, the system centre of mass (a fixed point at the origin),
the inertial axes and the base frame's axes. A link whose mesh file cannot be found is drawn
as a small sphere, with a warning (the dynamics never need the meshes). The plan's keep-out
objects (``plan.safety.obstacles``) are drawn semi-transparent red, fixed to the spacecraft
(animated with the base pose; a capsule is a cylinder and two spheres).

The scene is kept in this process (:class:`~freefloat.viz.scene.RecordedScene` as the
viewer's window): no meshcat server is started, and the page is written from the kept scene.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import FreeFloatError, ViewerError
from ..files import atomic_write_text
from ..plans.format import Plan
from ..plans.robot_copy import plan_robot
from ..progress import LOGGER
from ..robot.collision import Obstacle
from ..robot.model import Robot
from .controls import CM_COLOR, EE_COLOR, TRAIL_COLORS

__all__ = ["Playback", "build_playback", "serve", "write_html"]


ROOT_NODE = "freefloat"
EXTRAS = "freefloat_extras"
#: Repetitions of the animation loop in the viewer (meshcat has no "forever").
LOOPS = 10000
#: Colour (hex RGB) and opacity of the keep-out objects.
OBSTACLE_COLOR = 0xE02020
#: Material settings of a marker drawn over the meshes (three.js: no depth test; transparent
#: materials are drawn after the opaque ones).
ON_TOP = {"depthTest": False, "transparent": True, "opacity": 0.95}
OBSTACLE_OPACITY = 0.35


def _import_viewer() -> Any:
    """The meshcat package (its animation and geometry modules loaded), or a one-line error."""
    try:
        import meshcat
        import meshcat.animation
        import meshcat.geometry
    except Exception as exc:
        raise ViewerError(
            f"the 3D viewer needs meshcat, which failed to import ({type(exc).__name__}: {exc});"
            " reinstall it with: pip install 'meshcat>=0.3.2'"
        ) from None
    return meshcat


@dataclass(eq=False)
class Playback:
    """An animated plan in a meshcat scene kept in this process.

    Attributes:
        viewer: the ``meshcat.Visualizer``; its window is a
            :class:`~freefloat.viz.scene.RecordedScene` (no server).
        animation: the ``meshcat.animation.Animation`` sent to the viewer.
        frames: per animation frame, the 4 x 4 pose (inertial frame) of every animated node,
            keyed by meshcat path; the base frame is ``freefloat_extras/base_frame``.
        fps: animation frames per second of animation time (samples per second x speed).
    """

    viewer: Any
    frames: list[dict[str, np.ndarray]] = field(default_factory=list)
    fps: float = 30.0
    animation: Any = None

    def html(self) -> str:
        """Self-contained HTML of the scene and its animation (meshcat's standalone page)."""
        return str(self.viewer.window.get_scene())


def _tip_nodes(count: int) -> list[tuple[str, str]]:
    """Viewer nodes (trail, marker) per end effector: the first unnumbered, then ``_2``..."""
    tags = [""] + [f"_{k}" for k in range(2, count + 1)]
    return [(f"{EXTRAS}/trail{tag}", f"{EXTRAS}/end_effector{tag}") for tag in tags[:count]]


def obstacle_node(name: str) -> str:
    """Meshcat path of a keep-out object's node (animated with the spacecraft)."""
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in name) or "obstacle"
    return f"{EXTRAS}/obstacles/{safe}"


def _draw_obstacle(viewer: Any, g: Any, node: str, obstacle: Obstacle) -> None:
    """Set the meshcat objects of one keep-out object below ``node`` (in its own frame)."""
    material = g.MeshLambertMaterial(
        color=OBSTACLE_COLOR, transparent=True, opacity=OBSTACLE_OPACITY
    )
    size = obstacle.size
    if obstacle.shape == "box":
        viewer[node].set_object(g.Box(list(size)), material)
    elif obstacle.shape == "sphere":
        viewer[node].set_object(g.Sphere(size[0]), material)
    else:  # capsule: radius, cylinder length; its axis is local z (meshcat's cylinder: y)
        radius, length = size
        viewer[f"{node}/cylinder"].set_object(g.Cylinder(length, radius), material)
        turn = np.eye(4)
        turn[:3, :3] = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]  # y -> z
        viewer[f"{node}/cylinder"].set_transform(turn)
        for end, sign in (("top", 1.0), ("bottom", -1.0)):
            cap = np.eye(4)
            cap[2, 3] = sign * length / 2.0
            viewer[f"{node}/{end}"].set_object(g.Sphere(radius), material)
            viewer[f"{node}/{end}"].set_transform(cap)


def build_playback(plan: Plan, speed: float = 1.0, robot: Robot | None = None) -> Playback:
    """Draw the plan's robot, extras and animation into a meshcat scene kept in this process.

    Args:
        plan: the plan to show.
        speed: playback speed (1.0 = real time).
        robot: the loaded robot, to skip reloading the URDF.

    Raises:
        ViewerError: meshcat is missing or broken, or the visual geometry cannot be loaded.
        InputError: ``speed`` is not a positive finite number.
    """
    from ..errors import InputError

    if not (np.isfinite(speed) and speed > 0):
        raise InputError(f"--speed must be a positive number, got {speed}")
    meshcat = _import_viewer()
    from meshcat.animation import Animation

    from .scene import RecordedScene
    from .urdf_visuals import visual_model
    from .visuals import draw_visuals

    robot = robot or plan_robot(plan)
    visual = visual_model(robot)
    samples = plan.samples
    n = len(samples.t)
    fps = (n - 1) / plan.duration * speed if n > 1 else 30.0
    viewer = meshcat.Visualizer(window=RecordedScene())
    playback = Playback(viewer=viewer, fps=fps)
    try:
        nodes = draw_visuals(viewer, visual, ROOT_NODE)
        obstacles, tips = _draw_extras(viewer, plan, robot)
        base_link = robot.model.getFrameId(robot.base_link)
        animation = Animation(default_framerate=fps)
        data = robot.model.createData()
        ee_frames = robot.end_effector_frames
        for k in range(n):
            q = robot.configuration(
                samples.q[k], samples.base_position[k], samples.base_quaternion_xyzw[k]
            )
            pin.forwardKinematics(robot.model, data, q)
            pin.updateFramePlacements(robot.model, data)
            poses = {
                node: (data.oMi[v.joint] * v.placement).homogeneous
                for v, node in zip(visual, nodes, strict=True)
            }
            base = np.eye(4)
            base[:3, :3] = pin.Quaternion(np.asarray(samples.base_quaternion_xyzw[k])).matrix()
            base[:3, 3] = samples.base_position[k]
            poses[f"{EXTRAS}/base_frame"] = base
            for frame, (_, tip_node) in zip(ee_frames, tips, strict=True):
                tip = np.eye(4)
                tip[:3, 3] = data.oMf[frame].translation
                poses[tip_node] = tip
            for node, obstacle in obstacles.items():  # as the collision model places them
                poses[node] = (data.oMf[base_link] * obstacle.placement()).homogeneous.copy()
            playback.frames.append(poses)
            with animation.at_frame(viewer, k) as frame:
                for name, pose in poses.items():
                    frame[name].set_transform(pose)
            if k == 0:  # the static placement too: the page shows it before the animation
                for name, pose in poses.items():
                    viewer[name].set_transform(pose)
        viewer.set_animation(animation, play=True, repetitions=LOOPS)
        playback.animation = animation
    except FreeFloatError:
        raise
    except Exception as exc:
        raise ViewerError(f"the 3D viewer failed: {type(exc).__name__}: {exc}") from None
    return playback


def _draw_extras(
    viewer: Any, plan: Plan, robot: Robot
) -> tuple[dict[str, Any], list[tuple[str, str]]]:
    """Every end effector's trail and marker, the CM, frames and keep-out objects; the camera.

    Returns the obstacles by viewer node, and each end effector's (trail, marker) nodes.
    """
    import meshcat.geometry as g

    samples = plan.samples
    paths = [np.asarray(samples.path_of(f), dtype=float) for f in robot.end_effectors]
    extent = float(max(max(np.linalg.norm(p, axis=1).max() for p in paths), 0.5))
    tips = _tip_nodes(len(paths))
    for number, (path, (trail, _)) in enumerate(zip(paths, tips, strict=True)):
        viewer[trail].set_object(
            g.Line(
                g.PointsGeometry(path.T.astype(np.float32)),
                g.LineBasicMaterial(color=TRAIL_COLORS[number % len(TRAIL_COLORS)], linewidth=2),
            )
        )
    # The markers are drawn over everything (no depth test, after the opaque meshes): the
    # system CM lies inside the spacecraft and an end effector inside its own link.
    viewer[f"{EXTRAS}/cm"].set_object(
        g.Sphere(0.03 * extent), g.MeshLambertMaterial(color=CM_COLOR, **ON_TOP)
    )
    viewer[f"{EXTRAS}/inertial_axes"].set_object(g.triad(0.5 * extent))
    viewer[f"{EXTRAS}/base_frame"].set_object(g.triad(0.25 * extent))
    for _, tip_node in tips:
        viewer[tip_node].set_object(
            g.Sphere(0.04 * extent), g.MeshLambertMaterial(color=EE_COLOR, **ON_TOP)
        )
    obstacles = {obstacle_node(o.name): o for o in plan.safety.obstacles}
    for node, obstacle in obstacles.items():
        _draw_obstacle(viewer, g, node, obstacle)
    # Camera: meshcat 0.3.2 API (Pinocchio's helpers need a newer meshcat). Inside the
    # y-up "rotated" node, a world point (x, y, z) is (x, z, -y); it looks at the origin.
    eye = np.array([0.5, -1.0, 1.1]) * 1.5 * extent
    viewer["/Grid"].set_property("visible", False)  # no floor in orbit
    viewer["/Cameras/default/rotated/<object>"].set_property(
        "position", [float(eye[0]), float(eye[2]), float(-eye[1])]
    )
    return obstacles, tips


def page_html(plan: Plan, speed: float = 1.0) -> str:
    """The self-contained playback page of ``plan`` (no server is left running).

    The page carries visible controls (:mod:`freefloat.viz.controls`): title, play / pause /
    restart, a time slider with a readout in seconds, speed and a legend.
    """
    from .compact import compact_page
    from .controls import inject_controls

    return inject_controls(compact_page(build_playback(plan, speed).html()), plan, speed)


def write_html(plan: Plan, path: str | Path, speed: float = 1.0) -> Path:
    """Write one self-contained HTML file that plays the plan offline; no server is left.

    The file is written atomically: a failure leaves nothing behind.
    """
    return atomic_write_text(path, page_html(plan, speed))


def serve(plan: Plan, speed: float = 1.0, announce: Any = print) -> None:
    """Serve the playback page (with its controls) on 127.0.0.1 until Ctrl-C, then stop.

    The page is the same self-contained page :func:`write_html` writes, so the served and the
    written playback look and behave alike; a plain HTTP server on loopback serves it, and
    nothing is left running afterwards. Ctrl-C's ``KeyboardInterrupt`` is raised again once
    the server has stopped (the command line exits 130, as every command does).
    """
    import http.server
    import threading

    body = page_html(plan, speed).encode("utf-8")

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            self.send_response(200)
            self.send_header("Content-Type", "text/html; charset=utf-8")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, format: str, *args: Any) -> None:
            return  # quiet: the terminal shows the URL only

    class Server(http.server.ThreadingHTTPServer):
        def handle_error(self, request: Any, client_address: Any) -> None:
            """A browser that leaves mid-page is no error; anything else is one line."""
            failure = sys.exc_info()[1]
            if not isinstance(failure, ConnectionError):
                LOGGER.warning("show: a request from %s failed: %s", client_address[0], failure)

    server = Server(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        announce(f"freefloat show: open http://127.0.0.1:{server.server_port}/ (Ctrl-C to stop)")
        while True:
            time.sleep(3600)
    finally:
        server.shutdown()
        server.server_close()
