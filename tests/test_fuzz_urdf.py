"""Seeded fuzz of URDFs (issue 26): XML tricks and the inertias of the model Pinocchio builds.

XML tricks: a shipped URDF is mutated at random (document types, entities, character
references, comments, CDATA, namespaces, processing instructions, repeated elements, numbers
spelled the ways Python reads and urdfdom does not). Every outcome is either a one-line
refusal, or a robot identical to the one Pinocchio builds from the raw text on its own (same
joints, same body masses and inertias): what was checked is what is loaded.

Built-model inertias: random trees with links fixed to moving bodies, masses sometimes zero,
inertias sometimes indefinite. The merged bodies are computed independently here (rotation
matrices from rpy by hand, the parallel-axis theorem); a robot is accepted exactly when every
link and every merged body is physical, and then Pinocchio's bodies equal the independent ones.
"""

from __future__ import annotations

import math
import random

import numpy as np
import pinocchio as pin
import pytest

import freefloat as ff
from freefloat.robot.parser_messages import parser_messages

from conftest import ROOT

PLANAR = (ROOT / "robots" / "planar_2dof.urdf").read_text()

#: (old, new) text substitutions, each applied to the first occurrence.
TRICKS = [
    ('<robot name="planar_2dof">', '<!DOCTYPE robot>\n<robot name="planar_2dof">'),
    (
        '<robot name="planar_2dof">',
        '<!DOCTYPE robot [<!ENTITY m "41.0">]><robot name="planar_2dof">',
    ),
    (
        '<robot name="planar_2dof">',
        "<!DOCTYPE robot [<!ENTITY e \"x> <robot name='evil'><link name='base'/></robot> <!--\">]>"
        '<!-- --><robot name="planar_2dof">',
    ),
    ('<mass value="40.0"/>', '<mass value="&#52;0.0"/>'),
    ('<mass value="40.0"/>', '<mass value="4_0.0"/>'),
    ('<mass value="40.0"/>', '<mass value=" 40.0"/>'),
    ('<mass value="40.0"/>', '<mass value="40.0 "/>'),
    ('<mass value="40.0"/>', '<mass value="+4e1"/>'),
    ('<mass value="40.0"/>', '<mass value="1e400"/>'),
    ('<mass value="40.0"/>', '<mass value="40.0"/><mass value="41.0"/>'),
    ('<mass value="40.0"/>', '<mass value="\u0664\u0660"/>'),
    ('<mass value="40.0"/>', '<mass value="40.0" value="41.0"/>'),
    ("<inertial>", '<inertial><!-- <mass value="41.0"/> -->'),
    ("<inertial>", "<inertial><![CDATA[ <mass value='41.0'/> ]]>"),
    ("<inertial>", '<inertial><?pi <mass value="41.0"/> ?>'),
    ('<link name="link1">', '<link name="link1" xmlns="urn:x">'),
    ('<link name="link1">', '<x:link xmlns:x="urn:x" name="ghost"/><link name="link1">'),
    ("</robot>", '<link name="extra"/></robot>'),
    ("</robot>", "</robot><robot name='second'/>"),
    ("</robot>", "</robot><!-- trailing -->"),
    (
        '<joint name="q2" type="continuous">',
        '<joint name="q2" type="continuous">\n<mimic joint="q1"/>',
    ),
    ('<axis xyz="0 0 1"/>', '<axis xyz="0&#10;0&#9;1"/>'),
    ('<axis xyz="0 0 1"/>', '<axis xyz="0 0 1 0"/>'),
    ('ixy="0"', 'ixy="0" ixy2="1"'),
    ('ixy="0"', ""),
    ('izz="3.33"', 'izz="-3.33"'),
    ('izz="3.33"', 'izz="1e308"'),
    ('<?xml version="1.0"?>', '\ufeff<?xml version="1.0"?>'),
    ('<?xml version="1.0"?>', '<?xml version="1.0" encoding="latin-1"?>'),
    ('<origin xyz="1.0 0 0"/>', '<origin xyz="1.0 0 0" xyz2="5"/><origin xyz="9 0 0"/>'),
    ('name="q1"', 'name="q&#x31;"'),
    ('name="q1"', 'name="q1&#x0;"'),
    ('<child link="link1"/>', '<child link="link1"/><child link="link2"/>'),
]


def _bodies(model: pin.Model) -> list[tuple[float, np.ndarray, np.ndarray]]:
    return [(float(i.mass), np.array(i.lever), np.array(i.inertia)) for i in model.inertias]


def _same_robot(robot: ff.Robot, raw: pin.Model) -> None:
    assert list(raw.names[2:]) == robot.joint_names
    for (m1, c1, i1), (m2, c2, i2) in zip(_bodies(robot.model), _bodies(raw), strict=True):
        assert m1 == pytest.approx(m2, rel=1e-12)
        np.testing.assert_allclose(c1, c2, atol=1e-12)
        np.testing.assert_allclose(i1, i2, atol=1e-12)
    np.testing.assert_allclose(
        robot.model.jointPlacements[2].translation, raw.jointPlacements[2].translation
    )


@pytest.mark.parametrize("seed", range(4))
def test_xml_tricks_load_the_robot_that_was_checked(tmp_path, seed):
    rng = random.Random(seed)
    accepted = refused = 0
    for case in range(40):
        text = PLANAR
        for old, new in rng.sample(TRICKS, rng.randint(1, 3)):
            text = text.replace(old, new, 1)
        path = tmp_path / f"r{case}.urdf"
        path.write_text(text, encoding="utf-8")
        try:
            robot = ff.load_robot(path)
        except (ff.ModelError, ff.UnknownNameError, ff.FileError) as exc:
            assert "\n" not in str(exc) and len(str(exc)) < 600, str(exc)
            refused += 1
            continue
        accepted += 1
        with parser_messages():
            raw = pin.buildModelFromXML(text.removeprefix("\ufeff"), pin.JointModelFreeFlyer())
        _same_robot(robot, raw)
    assert accepted and refused  # both outcomes are exercised


# -- built-model inertias ------------------------------------------------------------------


def _rpy_matrix(r: float, p: float, y: float) -> np.ndarray:
    """URDF rpy: Rz(y) Ry(p) Rx(r)."""
    cr, sr, cp, sp, cy, sy = (
        math.cos(r),
        math.sin(r),
        math.cos(p),
        math.sin(p),
        math.cos(y),
        math.sin(y),
    )
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def _inertia(rng: np.random.Generator, kind: str) -> np.ndarray:
    a = rng.normal(size=(3, 3))
    base = a @ a.T + 0.05 * np.eye(3)
    if kind == "indefinite":
        values, vectors = np.linalg.eigh(base)
        values[0] = -abs(values[0]) - 0.01
        return vectors @ np.diag(values) @ vectors.T
    return np.zeros((3, 3)) if kind == "zero" else base


def _v(*values) -> str:
    return " ".join(repr(float(v)) for v in values)


def _link_xml(name: str, mass: float, com, rpy, inertia: np.ndarray) -> str:
    i = inertia
    keys = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
    entries = (i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2])
    attrs = " ".join(f'{k}="{_v(e)}"' for k, e in zip(keys, entries, strict=True))
    return (
        f'<link name="{name}"><inertial><origin xyz="{_v(*com)}" rpy="{_v(*rpy)}"/>'
        f'<mass value="{mass!r}"/><inertia {attrs}/></inertial></link>'
    )


def _random_tree(rng: np.random.Generator):
    """A base and 2 movable links, each with 0 to 2 links fixed to it; the URDF text and,
    per body, its links as (mass, com, inertia) in the body's frame."""
    links, joints, bodies = [], [], []
    for b, name in enumerate(["base", "l1", "l2"]):
        members = []
        for k in range(1 + int(rng.integers(0, 3))):
            kind = rng.choice(["pd", "pd", "pd", "indefinite", "zero"])
            mass = 0.0 if kind == "zero" or rng.random() < 0.15 else float(rng.uniform(0.5, 20))
            inertia = _inertia(rng, str(kind))
            com, rpy = rng.uniform(-0.5, 0.5, 3), rng.uniform(-3, 3, 3)
            link = name if k == 0 else f"{name}_f{k}"
            links.append(_link_xml(link, mass, com, rpy, inertia))
            place, turn = rng.uniform(-1, 1, 3), rng.uniform(-3, 3, 3)
            if k:
                joints.append(
                    f'<joint name="{link}_fix" type="fixed"><parent link="{name}"/>'
                    f'<child link="{link}"/><origin xyz="{_v(*place)}" rpy="{_v(*turn)}"/></joint>'
                )
                rotation, offset = _rpy_matrix(*turn), place
            else:
                rotation, offset = np.eye(3), np.zeros(3)
            frame = rotation @ _rpy_matrix(*rpy)
            members.append((mass, rotation @ com + offset, frame @ inertia @ frame.T))
        bodies.append(members)
        if b:
            parent = ["base", "l1"][b - 1]
            joints.append(
                f'<joint name="j{b}" type="revolute"><parent link="{parent}"/>'
                f'<child link="{name}"/>'
                f'<origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>'
                f'<limit lower="-2" upper="2" effort="10" velocity="1"/></joint>'
            )
    return f'<robot name="fuzz">{"".join(links)}{"".join(joints)}</robot>', bodies


def _merged(members):
    mass = sum(m for m, _, _ in members)
    if mass <= 0:
        return mass, np.zeros(3), np.zeros((3, 3))
    com = sum(m * c for m, c, _ in members) / mass
    inertia = sum(
        i + m * (np.dot(c - com, c - com) * np.eye(3) - np.outer(c - com, c - com))
        for m, c, i in members
    )
    return mass, com, inertia


def _physical(members) -> bool:
    for mass, _, inertia in members:  # each link on its own, as the file states it
        low = np.linalg.eigvalsh(inertia).min()
        if (mass > 0 and low <= 0) or low < -1e-12 * max(1.0, np.abs(inertia).max()):
            return False
    mass, _, inertia = _merged(members)
    return mass > 0 and np.linalg.eigvalsh(inertia).min() > 0


@pytest.mark.parametrize("seed", range(3))
def test_merged_bodies_are_physical_exactly_when_accepted(tmp_path, seed):
    rng = np.random.default_rng(seed)
    accepted = refused = 0
    for case in range(40):
        text, bodies = _random_tree(rng)
        path = tmp_path / f"t{case}.urdf"
        path.write_text(text)
        expected = all(_physical(members) for members in bodies)
        try:
            robot = ff.load_robot(path)
        except ff.ModelError as exc:
            assert not expected, str(exc)
            assert "\n" not in str(exc)
            refused += 1
            continue
        assert expected, text
        accepted += 1
        for index, members in enumerate(bodies, start=1):
            mass, com, inertia = _merged(members)
            body = robot.model.inertias[index]
            assert body.mass == pytest.approx(mass, rel=1e-12)
            np.testing.assert_allclose(body.lever, com, atol=1e-12)
            np.testing.assert_allclose(body.inertia, inertia, atol=1e-10)
    assert accepted and refused
