"""The scene kept in this process against meshcat's own server, and the robot's visuals
against Pinocchio's meshcat visualizer (two other implementations of the same pages)."""

from __future__ import annotations

import base64
import contextlib
import io
import re

import meshcat
import meshcat.animation
import meshcat.geometry as g
import numpy as np
import pinocchio as pin
import pytest
import umsgpack

import freefloat as ff
from freefloat.viz.scene import RecordedScene
from freefloat.viz.urdf_visuals import visual_model
from freefloat.viz.visuals import draw_visuals

from conftest import ROOT

_EMBEDDED = re.compile(r'fetch\("data:application/octet-binary;base64,([A-Za-z0-9+/=]*)"\)')


def _commands(page: str) -> list[dict]:
    """The scene commands a standalone page embeds, decoded, in page order."""
    return [umsgpack.unpackb(base64.b64decode(m)) for m in _EMBEDDED.findall(page)]


def _draw(viewer) -> None:
    """Every kind of command, with the cases the server's rules decide: a property dropped by
    a new object, a transform replaced, a subtree deleted, the root's own animation."""
    viewer["a/box"].set_object(g.Box([0.1, 0.2, 0.3]), g.MeshLambertMaterial(color=0xFF0000))
    viewer["a/box"].set_property("visible", False)
    viewer["a/box"].set_object(g.Sphere(0.2))  # a new object: the property goes
    viewer["a/box"].set_property("opacity", 0.5)
    viewer["a/box"].set_transform(np.diag([1.0, 2.0, 3.0, 1.0]))
    viewer["a/box"].set_transform(np.eye(4))  # the later transform stays
    viewer["a/gone/deep"].set_object(g.Sphere(0.1))
    viewer["a/gone"].delete()
    viewer["b"].set_object(g.Cylinder(0.4, 0.1))
    animation = meshcat.animation.Animation()
    for k in range(3):
        with animation.at_frame(viewer, k) as frame:
            pose = np.eye(4)
            pose[0, 3] = 0.1 * k
            frame["b"].set_transform(pose)
    viewer.set_animation(animation, play=True, repetitions=5)


def test_the_kept_scene_writes_the_page_meshcats_server_writes():
    with contextlib.redirect_stdout(io.StringIO()):
        served = meshcat.Visualizer()
    try:
        kept = meshcat.Visualizer(window=RecordedScene())
        _draw(served)
        _draw(kept)
        want = _commands(served.static_html())
        got = _commands(kept.window.get_scene())
    finally:
        served.window.server_proc.kill()
        served.window.server_proc.wait(timeout=10)
    # the objects are drawn twice, each draw with its own identifiers: compare without them
    assert [_without_ids(c) for c in got] == [_without_ids(c) for c in want]
    kinds = [c["type"] for c in got]
    assert kinds.count("set_animation") == 1 and kinds.count("set_property") == 1
    assert not any("gone" in c["path"] for c in got)


def _without_ids(data):
    """``data`` without meshcat's identifiers (fresh for every object drawn)."""
    if isinstance(data, dict):
        ids = ("uuid", "geometry", "material")
        return {k: _without_ids(v) for k, v in data.items() if k not in ids}
    if isinstance(data, list):
        return [_without_ids(v) for v in data]
    return data


def _world_matrices(page: str) -> dict[str, tuple[np.ndarray, dict]]:
    """Per drawn node: its transform times its object's own matrix (three.js reads both
    column by column), and the object's first geometry or its mesh file."""
    objects, transforms = {}, {}
    for command in _commands(page):
        if command["type"] == "set_object":
            objects[command["path"]] = command["object"]
        elif command["type"] == "set_transform":
            transforms[command["path"]] = np.reshape(command["matrix"], (4, 4)).T
    out = {}
    for path, obj in objects.items():
        own = np.reshape(obj["object"]["matrix"], (4, 4)).T
        shape = obj["geometries"][0] if obj["geometries"] else obj["object"]
        out[path] = (transforms.get(path, np.eye(4)) @ own, shape)
    return out


def _their_visuals(robot) -> pin.GeometryModel:
    dirs = [str(d) for d in robot.package_dirs]
    return pin.buildGeomFromUrdfString(
        robot.model, robot.urdf_text, pin.GeometryType.VISUAL, package_dirs=dirs
    )


def _compare(robot) -> int:
    """Draw ``robot`` at one configuration with Pinocchio's visual model and MeshcatVisualizer,
    and with this project's reading of the URDF and :func:`draw_visuals`; compare every node."""
    from pinocchio.visualize import MeshcatVisualizer

    q = robot.configuration(np.linspace(-0.7, 0.9, robot.n))
    theirs = meshcat.Visualizer(window=RecordedScene())
    viz = MeshcatVisualizer(robot.model, pin.GeometryModel(), _their_visuals(robot))
    viz.initViewer(viewer=theirs)
    viz.loadViewerModel(rootNodeName="robot")
    viz.display(q)
    mine = meshcat.Visualizer(window=RecordedScene())
    # the URDF's visuals (a link that states none is drawn from its collisions: not theirs)
    visuals = [v for v in visual_model(robot) if v.element == "visual"]
    nodes = draw_visuals(mine, visuals, "robot")
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, q)
    for visual, node in zip(visuals, nodes, strict=True):
        mine[node].set_transform((data.oMi[visual.joint] * visual.placement).homogeneous)
    their_page, my_page = theirs.window.get_scene(), mine.window.get_scene()
    want, got = _world_matrices(their_page), _world_matrices(my_page)
    assert set(got) == set(want) and len(got) == len(visuals)
    for path, (matrix, shape) in got.items():
        their_matrix, their_shape = want[path]
        keys = ("width", "height", "depth", "radius", "radiusTop", "radiusBottom")
        sizes = [float(shape.get(k, "nan")) for k in keys]
        their_sizes = [float(their_shape.get(k, "nan")) for k in keys]
        np.testing.assert_allclose(sizes, their_sizes, rtol=1e-6, err_msg=path)
        assert (shape.get("type"), shape.get("data")) == (
            their_shape.get("type"),
            their_shape.get("data"),
        ), path
        if shape.get("type") == "CylinderGeometry":  # the axis either way up
            their_matrix = their_matrix.copy()
            flip = np.abs(their_matrix[:3, 1] + matrix[:3, 1]).max() < 1e-12
            their_matrix[:3, 1:3] *= -1.0 if flip else 1.0
        np.testing.assert_allclose(matrix, their_matrix, atol=1e-12, err_msg=path)
    mine_colours, their_colours = _colours(my_page), _colours(their_page)
    assert set(mine_colours) == set(their_colours)
    for path, colours in mine_colours.items():
        assert len(colours) == len(their_colours[path]), path
        assert np.abs(np.subtract(colours, their_colours[path])).max(initial=0) <= 1, path
    return len(got)


def _colours(page: str) -> dict[str, list[int]]:
    """Per node, its material colours as (r, g, b) bytes."""
    out = {}
    for command in _commands(page):
        if command["type"] == "set_object":
            colours = [m["color"] for m in command["object"].get("materials", [])]
            out[command["path"]] = [c >> shift & 255 for c in colours for shift in (16, 8, 0)]
    return out


@pytest.mark.parametrize("urdf", ["panda_servicer.urdf", "ur5_servicer.urdf", "planar_2dof.urdf"])
def test_visuals_are_where_pinocchios_visualizer_puts_them(urdf):
    """The same robot drawn at one configuration from Pinocchio's visual geometry model by
    Pinocchio's MeshcatVisualizer, and from this project's reading of the URDF (no mesh
    loaded) by :func:`draw_visuals`: every visual node holds the same shape (box and sphere
    sizes, a cylinder's radius and height, a mesh file's text or bytes) in the same colour
    (to a unit of 255: Pinocchio truncates, this project rounds), at the same place once its
    transform and its object's own matrix are combined (Pinocchio scales the transform, this
    project the object; the products agree to double rounding, checked to 1e-12). A
    cylinder's axis may come out flipped: it is symmetric."""
    assert _compare(ff.load_robot(ROOT / "robots" / urdf)) >= 4


#: A robot with what the shipped ones lack: materials by urdfdom's rules (a robot-level colour
#: wins over a visual's own; a colour named in one visual serves later ones), scaled STL, OBJ
#: and COLLADA meshes, a turned origin, a cylinder, a link on a fixed joint.
_EDGE_URDF = """<?xml version="1.0"?>
<robot name="edge">
  <material name="blue"><color rgba="0 0 1 1"/></material>
  <link name="base">
    <inertial><mass value="100"/>
      <inertia ixx="10" iyy="10" izz="10" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><origin xyz="0.1 0.2 0.3" rpy="0.3 -0.4 1.2"/><geometry><box size="1 2 3"/></geometry>
      <material name="blue"><color rgba="1 0 0 1"/></material></visual>
    <visual><geometry><sphere radius="0.2"/></geometry>
      <material name="green"><color rgba="0 1 0 0.5"/></material></visual>
  </link>
  <link name="l1">
    <inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><origin rpy="0.5 0 0"/><geometry><cylinder radius="0.1" length="0.5"/></geometry>
      <material name="green"/></visual>
    <visual><origin xyz="0 0 0.4"/><geometry><mesh scale="2 3 4"
      filename="package://example-robot-data/robots/ur_description/meshes/ur5/visual/base.dae"/>
      </geometry></visual>
    <visual><geometry><mesh scale="0.5 0.5 2"
      filename="package://example-robot-data/robots/cassie_description/meshes/shin.stl"/>
      </geometry></visual>
    <visual><origin xyz="0.1 0 0" rpy="0 0.2 0"/><geometry><mesh scale="1 2 1"
      filename="package://example-robot-data/robots/laikago_description/meshes/calf.obj"/>
      </geometry><material name="blue"/></visual>
  </link>
  <link name="l2">
    <inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><origin xyz="0 0.1 0" rpy="0 0 0.5"/><geometry><box size="0.1 0.1 0.1"/></geometry>
      <material name="green"/></visual>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 1" rpy="0.1 0.2 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="f" type="fixed"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.3 0 0" rpy="0 0.5 0"/></joint>
</robot>
"""


def test_visuals_of_scaled_meshes_and_urdfdoms_materials_match_pinocchios(tmp_path):
    path = tmp_path / "edge.urdf"
    path.write_text(_EDGE_URDF)
    robot = ff.load_robot(path, end_effector="l2")
    assert _compare(robot) == 7
    colours = {v.name: v.rgba for v in visual_model(robot)}
    assert colours["base_0"] == (0.0, 0.0, 1.0, 1.0)  # the robot-level blue, not its own red
    assert colours["l1_0"] == colours["l2_0"] == (0.0, 1.0, 0.0, 0.5)  # green, named in base_1


def test_a_capsule_is_drawn_at_its_radius_from_its_segment():
    """The triangulated capsule's vertices lie at its radius from its axis segment (to
    float32 rounding: meshcat keeps vertices in float32)."""
    from freefloat.viz.visuals import _capsule

    radius, half = 0.07, 0.2
    vertices = np.asarray(_capsule(radius, half).vertices, dtype=float)
    along = np.clip(vertices[:, 2], -half, half)
    gap = np.linalg.norm(vertices - np.column_stack([0 * along, 0 * along, along]), axis=1)
    np.testing.assert_allclose(gap, radius, atol=1e-7)
    assert vertices[:, 2].max() == pytest.approx(half + radius)
    assert vertices[:, 2].min() == pytest.approx(-half - radius)


@pytest.mark.parametrize(
    ("broken", "said"),
    [
        ('rpy="0.3 -0.4 1.2"', 'rpy="0 0"'),
        ('<sphere radius="0.2"/>', '<sphere radius="abc"/>'),
        ('<color rgba="0 0 1 1"/>', '<color rgba="0 0 1"/>'),
    ],
)
def test_a_visual_number_in_the_wrong_form_is_refused_by_name(tmp_path, broken, said):
    from freefloat.errors import ViewerError

    path = tmp_path / "edge.urdf"
    path.write_text(_EDGE_URDF.replace(broken, said, 1))
    with pytest.raises(ViewerError, match=r"edge\.urdf: .* gives .*; expected \d finite number"):
        visual_model(ff.load_robot(path, end_effector="l2"))
