"""URDF text builders for test robots (spatial arms, bad inputs)."""

from __future__ import annotations

from collections.abc import Sequence

BASE = """
  <link name="base">
    <inertial><mass value="{mass}"/>
      <inertia ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><box size="1 1 1"/></geometry></visual>
  </link>"""


def link(
    name: str,
    mass: float = 5.0,
    inertia: Sequence[float] = (0.1, 0.1, 0.1),
    com: Sequence[float] = (0.25, 0.0, 0.0),
) -> str:
    ixx, iyy, izz = inertia
    return f"""
  <link name="{name}">
    <inertial><origin xyz="{com[0]} {com[1]} {com[2]}"/><mass value="{mass}"/>
      <inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>"""


def joint(
    name: str,
    parent: str,
    child: str,
    kind: str = "revolute",
    axis: Sequence[float] = (0, 0, 1),
    xyz: Sequence[float] = (0.5, 0, 0),
    limits: tuple[float, float] = (-3.0, 3.0),
) -> str:
    limit = ""
    if kind in ("revolute", "prismatic"):
        limit = f'<limit lower="{limits[0]}" upper="{limits[1]}" effort="50" velocity="2"/>'
    elif kind == "continuous":
        limit = '<limit effort="50" velocity="2"/>'
    return f"""
  <joint name="{name}" type="{kind}">
    <parent link="{parent}"/><child link="{child}"/>
    <origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}"/><axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>
    {limit}
  </joint>"""


def robot(body: str, name: str = "test") -> str:
    return f'<?xml version="1.0"?>\n<robot name="{name}">{body}\n</robot>\n'


def spatial_arm(
    kinds: Sequence[str] = ("revolute", "revolute", "revolute"),
    axes: Sequence[Sequence[float]] = ((0, 0, 1), (0, 1, 0), (0, 0.6, 0.8)),
    base_mass: float = 100.0,
) -> str:
    """A base with a serial arm; joint i moves link i; link i is 0.5 m long."""
    body = BASE.format(mass=base_mass, i=base_mass / 6.0)
    parent = "base"
    for i, (kind, axis) in enumerate(zip(kinds, axes, strict=True), start=1):
        body += joint(f"j{i}", parent, f"l{i}", kind, axis, (0.5, 0.1 * i, 0.05))
        body += link(
            f"l{i}", mass=6.0 - i, inertia=(0.05, 0.12, 0.1 + 0.01 * i), com=(0.25, 0.06, 0.03)
        )
        parent = f"l{i}"
    body += joint("tip_joint", parent, "tip", "fixed")
    body += '\n  <link name="tip"/>'
    return robot(body, "spatial")


def slider_arm() -> str:
    """A planar arm with a prismatic joint (along base x) and a revolute one (about base z)."""
    body = BASE.format(mass=50.0, i=8.0)
    body += joint("slide", "base", "l1", "prismatic", (1, 0, 0), limits=(-0.2, 0.4))
    body += link("l1", mass=4.0)
    body += joint("turn", "l1", "l2", "revolute", (0, 0, 1))
    body += link("l2", mass=3.0)
    return robot(body)


def chain(n: int, spatial: bool = False) -> str:
    """A 500 kg base with an n-joint serial arm of light links (0.3 m, 2 kg each).

    Planar: every axis along z. Spatial: axes z, y, x in turn.
    """
    body = BASE.format(mass=500.0, i=80.0)
    axes = [(0, 0, 1), (0, 1, 0), (1, 0, 0)] if spatial else [(0, 0, 1)]
    parent = "base"
    for i in range(1, n + 1):
        xyz = (0.5 if i == 1 else 0.3, 0, 0)
        body += joint(f"j{i}", parent, f"l{i}", "revolute", axes[(i - 1) % len(axes)], xyz)
        body += link(f"l{i}", mass=2.0, inertia=(0.02, 0.02, 0.02), com=(0.15, 0.0, 0.0))
        parent = f"l{i}"
    return robot(body, f"chain{n}")
