"""A first link hinged at the face of the spacecraft's hull that its joint can swing into the
hull is not "touching by design": its pair with the hull is checked (the trial's 1 m link
ran 0.29 m through the hull in a verified plan). Pairs that do not swing stay spared."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import freefloat as ff
from freefloat.cli import main
from freefloat.robot.collision import CollisionModel

import urdfs
from conftest import ROOT

HULL = '<collision><geometry><box size="1 1 1"/></geometry></collision>'


def _arm(tmp_path, length: float, axis=(0, 0, 1), limits=(-3.1, 3.1), yaw=0.0) -> str:
    """Base: a 1 m cube (hull), the joint q1 on its +x face, about ``axis``; link1 a box from
    2 cm beyond the joint out to ``length`` m; link2 a short stub. Closed form: about z, at
    q1 = 180 deg link1 lies along -x from x = 0.48 to 0.5 - length, inside the cube; about x
    (the face's normal) it turns about its own length, always outside."""
    body = urdfs.BASE.format(mass=500.0, i=83.0).replace("</visual>", "</visual>" + HULL)
    q1 = urdfs.joint("q1", "base", "link1", "revolute", axis, (0.5, 0, 0), limits)
    body += q1.replace('<origin xyz="0.5 0 0"/>', f'<origin xyz="0.5 0 0" rpy="0 0 {yaw}"/>')
    reach = length - 0.02
    body += urdfs.link("link1", mass=4.0).replace(
        "</link>",
        f'<collision><origin xyz="{0.02 + reach / 2} 0 0"/>'
        f'<geometry><box size="{reach} 0.1 0.1"/></geometry></collision></link>',
    )
    body += urdfs.joint("q2", "link1", "link2", "revolute", (0, 0, 1), (length + 0.1, 0, 0))
    body += urdfs.link("link2", mass=1.0)
    path = tmp_path / f"hinged_{length}_{axis[0]}{axis[2]}_{limits[0]}_{limits[1]}_{yaw}.urdf"
    path.write_text(urdfs.robot(body, "hinged"))
    return str(path)


def _pairs(urdf: str) -> set[tuple[str, str]]:
    model = CollisionModel(ff.load_robot(urdf))
    objects = model.geometry.geometryObjects
    return {(objects[a].name, objects[b].name) for a, b in model.pairs}


def test_a_long_first_link_that_swings_into_the_hull_is_checked(tmp_path, capsys):
    urdf = _arm(tmp_path, 1.0)
    assert ("base_0", "link1_0") in _pairs(urdf)
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        f'robot = "{urdf}"\nduration = 10.0\n[start]\njoints = {{ q1 = 0.0, q2 = 0.0 }}\n'
        "[goal]\njoints = { q1 = 170.0, q2 = 0.0 }\n"
    )
    assert main(["check", str(scenario), "--at", "start"]) == 0  # 2 cm clear at the start
    assert (
        "base_0 / link1_0                                      0.0200 m" in capsys.readouterr().out
    )
    assert main(["check", str(scenario), "--at", "180,0"]) == 1  # inside the cube
    out = capsys.readouterr().out
    assert "base_0 / link1_0" in out and "configuration: NOT OK" in out
    assert main(["plan", str(scenario), "-o", str(tmp_path / "p.json"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "goal configuration: base_0 / link1_0 overlap" in err
    assert "checked because the joint between them swings one into the other" in err


def test_a_link_turning_about_its_own_length_and_the_shipped_robots_stay_spared(tmp_path):
    """The same link turning about the face's normal never enters the hull: spared, as
    parent and child. Every shipped servicer's pairs are those of the parent-and-child rule
    on Pinocchio's bodies, worked out here."""
    assert ("base_0", "link1_0") not in _pairs(_arm(tmp_path, 1.0, axis=(1, 0, 0)))
    for name in ("ur5_servicer", "panda_servicer"):
        robot = ff.load_robot(ROOT / "robots" / f"{name}.urdf")
        model = CollisionModel(robot)
        objects = list(model.geometry.geometryObjects)
        parents = [int(j) for j in robot.model.parents]
        joints = [int(o.parentJoint) for o in objects]
        expected = {
            (a, b)
            for a in range(len(objects))
            for b in range(a + 1, len(objects))
            if joints[a] != joints[b]
            and parents[joints[a]] != joints[b]
            and parents[joints[b]] != joints[a]
        }
        assert set(model.pairs) == expected, name


def test_two_robots_of_one_name_get_their_own_pairs(tmp_path):
    """The pairs were cached by names: a non-swinging variant loaded first gave its pairs to
    the swinging one of the same names (a link 0.54 m inside the hull verified)."""
    assert ("base_0", "link1_0") not in _pairs(_arm(tmp_path, 1.0, axis=(1, 0, 0)))
    assert ("base_0", "link1_0") in _pairs(_arm(tmp_path, 1.0))


@pytest.mark.parametrize(
    ("limits", "yaw", "why"),
    [
        ((-0.2, 0.2), math.pi, "lodged inside at every value of its joint"),
        ((0.0, 6.4), -math.pi / 2, "a range over a full turn, from 0"),
    ],
)
def test_a_link_inside_the_hull_over_its_range_is_checked(tmp_path, limits, yaw, why):
    """Closed form: turned by pi about z, link1 lies along -x from 0.48 m, inside the cube
    for every value within +-0.2 rad; with limits 0 to 6.4 rad and the origin turned by
    -pi/2, 3 pi/2 points it along -x. Either pair is checked, however little its overlap
    varies, or wherever the turn starts."""
    assert ("base_0", "link1_0") in _pairs(_arm(tmp_path, 1.0, limits=limits, yaw=yaw)), why


def test_a_link_a_lock_holds_inside_the_hull_is_refused(tmp_path, capsys):
    """q1 locked at 177 deg ([robot] lock) holds link1 inside the cube: that pair, constant
    now, is checked, and the start refused."""
    urdf = _arm(tmp_path, 1.0)
    scenario = tmp_path / "locked.toml"
    scenario.write_text(
        f'duration = 10.0\n[robot]\nurdf = "{urdf}"\nlock = [{{ joint = "q1", value = 177.0 }}]\n'
        "[start]\njoints = { q2 = 0.0 }\n[goal]\njoints = { q2 = 10.0 }\n"
    )
    assert main(["check", str(scenario)]) == 1
    out = capsys.readouterr().out
    assert "base_0 / link1_0" in out and "configuration: NOT OK" in out


def test_the_swing_note_names_a_pair_whose_link_name_holds_a_slash(tmp_path, capsys):
    """Link names may hold " / ", as the pairs' names do between their two objects: the note
    still finds the pair (it read the two names back from the pair's name, and a third part
    lost the note)."""
    urdf = _arm(tmp_path, 1.0)
    renamed = tmp_path / "slashed.urdf"
    renamed.write_text(Path(urdf).read_text().replace('"link1"', '"arm / one"'))
    scenario = tmp_path / "slashed.toml"
    scenario.write_text(
        f'robot = "{renamed}"\nduration = 10.0\n[start]\njoints = {{ q1 = 0.0, q2 = 0.0 }}\n'
        "[goal]\njoints = { q1 = 170.0, q2 = 0.0 }\n"
    )
    assert main(["plan", str(scenario), "-o", str(tmp_path / "p.json"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "goal configuration: base_0 / arm / one_0 overlap" in err
    assert "checked because the joint between them swings one into the other" in err


def _coaxial(tmp_path) -> str:
    """Three links turning about one z axis, stacked along it; link1 and link3 carry balls
    centred on that axis, 0.1 m apart surface to surface at every configuration (closed form:
    centres 0.3 m apart on the axis, radii 0.1 m each)."""
    body = urdfs.BASE.format(mass=500.0, i=83.0)
    ball = (
        '<collision><origin xyz="0 0 {z}"/><geometry><sphere radius="0.1"/></geometry></collision>'
    )
    body += urdfs.joint("q1", "base", "link1", "revolute", (0, 0, 1), (0.0, 0.0, 0.6))
    body += urdfs.link("link1", com=(0, 0, 0)).replace("</link>", ball.format(z=0.0) + "</link>")
    body += urdfs.joint("q2", "link1", "link2", "revolute", (0, 0, 1), (0.0, 0.0, 0.15))
    body += urdfs.link("link2", com=(0.2, 0, 0))
    body += urdfs.joint("q3", "link2", "link3", "revolute", (0, 0, 1), (0.0, 0.0, 0.15))
    body += urdfs.link("link3", com=(0.3, 0, 0)).replace("</link>", ball.format(z=0.0) + "</link>")
    path = tmp_path / "coaxial.urdf"
    path.write_text(urdfs.robot(body, "coaxial"))
    return str(path)


def test_a_pair_no_joints_move_is_not_refused_with_move_the_joints(tmp_path, capsys):
    """ETS-VII's Link_3 / Link_5 lie 0.1 m apart at every configuration: a 0.15 m margin was
    refused with "move the start joints", which no joint values help."""
    urdf = _coaxial(tmp_path)
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        f'robot = "{urdf}"\nduration = 10.0\n[start]\njoints = {{ q1 = 0.0, q2 = 0.0, q3 = 0.0 }}\n'
        "[goal]\njoints = { q1 = 30.0, q2 = 20.0, q3 = 10.0 }\n[safety]\nmargin_m = 0.15\n"
    )
    assert main(["plan", str(scenario), "-o", str(tmp_path / "p.json"), "-q"]) == 2
    err = capsys.readouterr().err
    assert (
        "start configuration: link1_0 / link3_0 are 0.1 m apart, below the clearance margin" in err
    )
    assert err.rstrip().endswith(
        "no joint values change this pair's distance: disable it in an SRDF or lower "
        "[safety] margin_m"
    )
    assert "move the start joints" not in err

    # a keep-out object on that axis: no SRDF spares it; move or shrink it
    scenario.write_text(
        scenario.read_text().replace("margin_m = 0.15", "margin_m = 0.05")
        + '[[obstacles]]\nname = "dish"\nsphere = 0.1\nxyz = [0.0, 0.0, 1.12]\n'
    )
    assert main(["plan", str(scenario), "-o", str(tmp_path / "p.json"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "link3_0 / obstacle:dish are 0.02 m apart" in err
    assert err.rstrip().endswith(
        "no joint values change this pair's distance: move or shrink the keep-out object or "
        "lower [safety] margin_m"
    )
