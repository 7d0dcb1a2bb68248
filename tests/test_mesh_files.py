"""Mesh files checked before a page: every real file coal's loader reads is accepted, and
files cut short or of the wrong kind are refused, naming the file."""

from __future__ import annotations

import importlib.metadata
import struct
import subprocess
import sys
from pathlib import Path

import coal
import pytest

from freefloat.errors import ViewerError
from freefloat.viz.mesh_files import checked_mesh

from conftest import ROOT

SHARE = Path(
    importlib.metadata.distribution("example-robot-data").locate_file("cmeel.prefix/share")
)


def _sample(suffix: str, count: int) -> list[Path]:
    found = sorted(p for p in SHARE.rglob(f"*{suffix}"))
    return found[:: max(1, len(found) // count)][:count]


@pytest.mark.parametrize("suffix", [".stl", ".dae", ".obj"])
def test_real_mesh_files_that_coal_reads_are_accepted(suffix):
    """A spread of example-robot-data's files of each kind: those coal's loader (assimp) reads
    into a mesh with triangles are accepted here too."""
    read = 0
    for path in _sample(suffix, 12):
        try:
            model = coal.MeshLoader().load(str(path))
        except Exception:
            continue  # not a mesh coal reads: no claim either way
        if model.num_tris == 0:
            continue
        assert checked_mesh(path) == path.read_bytes(), path
        read += 1
    assert read >= 6


def _binary_stl(triangles: int) -> bytes:
    head = b"freefloat test".ljust(80, b" ") + struct.pack("<I", triangles)
    return head + b"\0" * (50 * triangles)


@pytest.mark.parametrize(
    ("name", "data", "reason"),
    [
        ("cut.stl", _binary_stl(4)[:-7], "neither a binary STL"),
        ("ascii.stl", b"solid x\nfacet normal 0 0 1\nouter loop\n", "cut short or malformed"),
        (
            "nan.stl",
            b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
            b"vertex 0 one 0\nendloop\nendfacet\nendsolid x\n",
            "not three numbers",
        ),
        ("faceless.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "a face"),
        ("html.dae", b"<html><body/></html>", "not <COLLADA>"),
        ("torn.dae", b"<COLLADA><asset>", "not well-formed"),
    ],
)
def test_broken_mesh_files_are_refused_by_name(tmp_path, name, data, reason):
    path = tmp_path / name
    path.write_bytes(data)
    with pytest.raises(ViewerError) as caught:
        checked_mesh(path)
    assert str(path) in str(caught.value) and reason in str(caught.value)


def test_a_whole_binary_stl_is_accepted(tmp_path):
    path = tmp_path / "whole.stl"
    path.write_bytes(_binary_stl(4))
    assert checked_mesh(path) == _binary_stl(4)


def test_the_page_of_a_robot_with_a_broken_mesh_is_refused(tmp_path):
    """``freefloat show --html`` of a plan whose URDF draws a link with a broken STL: exit 2,
    one line naming the file, no page left behind (the plan needs no mesh: it plans)."""
    cylinder = '<geometry><cylinder radius="0.05" length="1.0"/></geometry>'
    broken = tmp_path / "broken.stl"
    broken.write_bytes(b"solid x\nfacet normal 0 0 1\nouter loop\n")
    urdf = (ROOT / "robots" / "planar_2dof.urdf").read_text()
    assert cylinder in urdf
    (tmp_path / "arm.urdf").write_text(
        urdf.replace(cylinder, f'<geometry><mesh filename="{broken}"/></geometry>', 1)
    )
    scenario = (ROOT / "robots" / "scenarios" / "worked_example.toml").read_text()
    (tmp_path / "arm.toml").write_text(
        scenario.replace('robot = "planar_2dof"', f'robot = "{tmp_path / "arm.urdf"}"')
    )

    def freefloat(*args: str) -> subprocess.CompletedProcess:
        code = f"import sys\nfrom freefloat.cli import main\nsys.exit(main({list(args)!r}))"
        return subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path
        )

    assert freefloat("plan", "arm.toml", "-o", "arm.json", "-q").returncode == 0
    shown = freefloat("show", "arm.json", "--html", "arm.html")
    assert shown.returncode == 2
    assert "broken.stl" in shown.stderr and "Traceback" not in shown.stderr
    assert len(shown.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "arm.html").exists()


def test_a_mesh_of_another_format_is_drawn_as_a_sphere_with_a_warning(tmp_path, caplog):
    """A visual mesh the page's viewer cannot read (a PLY file, which exists) is drawn as the
    small sphere a missing mesh gets, and said so; the other links keep their shapes."""
    import logging

    import freefloat as ff
    from freefloat.viz.urdf_visuals import MISSING_MESH_RADIUS, visual_model

    cylinder = '<geometry><cylinder radius="0.05" length="1.0"/></geometry>'
    ply = tmp_path / "link.ply"
    ply.write_text("ply\nformat ascii 1.0\nend_header\n")
    urdf = (ROOT / "robots" / "planar_2dof.urdf").read_text()
    path = tmp_path / "arm.urdf"
    path.write_text(urdf.replace(cylinder, f'<geometry><mesh filename="{ply}"/></geometry>', 1))
    with caplog.at_level(logging.WARNING, logger="freefloat"):
        visuals = visual_model(ff.load_robot(path))
    spheres = [v for v in visuals if v.size == (MISSING_MESH_RADIUS,)]
    assert len(spheres) == 1 and spheres[0].shape == "sphere"
    assert {v.shape for v in visuals} >= {"box", "cylinder"}  # the rest as the URDF says
    assert any(
        "link.ply" in r.getMessage() and "not STL, OBJ or COLLADA" in r.getMessage()
        for r in caplog.records
    )
