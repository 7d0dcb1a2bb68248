"""The robot a plan was made for: from the URDF copy it carries, or from its path.

A ``freefloat.plan/4`` file carries the text of its URDF and that text's SHA-256 (checked when
the file is read). The robot is built from that copy, so a plan stays verifiable when its URDF
is gone (a cleared cache, another machine); the path then only names the folder its meshes are
looked for in. If a file is at that path, it must still be the one the plan was made with: a
URDF edited since (a lower effort limit, another mass) is another robot, and the plan is
refused for it, naming both SHA-256 sums. Older plans carry no copy: they are checked against
the file at their path as it is now, and a warning says so.
"""

from __future__ import annotations

import atexit
import shutil
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

from ..errors import PlanFileError
from ..files import read_text_file
from ..progress import LOGGER
from ..robot.model import MAX_URDF_BYTES, Robot, load_robot
from ..robot.urdf_checks import urdf_document
from .format import Plan
from .records import sha256_hex
from .versions import BASIS_FORMATS

__all__ = ["plan_robot"]


def _on_disk(path: str) -> str | None:
    """The text of the URDF file at ``path``, or None when there is none."""
    if not Path(path).exists():
        return None
    return read_text_file(path, "URDF", MAX_URDF_BYTES, PlanFileError)


def _materialised(text: str, original: Path) -> Path:
    """The plan's URDF copy as a file in a private temporary folder (removed at exit).

    Relative mesh paths are made absolute against the original URDF's folder, where they
    were looked for when the plan was made; ``package://`` paths are left to the package
    folders.
    """
    root = urdf_document(text)
    for element in root.iter():
        name = element.get("filename")
        if name and "://" not in name and not Path(name).is_absolute():
            element.set("filename", str(original.parent / name))
    folder = Path(tempfile.mkdtemp(prefix="freefloat-urdf-"))
    atexit.register(shutil.rmtree, folder, True)
    path = folder / original.name
    path.write_text(ET.tostring(root, encoding="unicode"), encoding="utf-8")
    return path


def plan_robot(plan: Plan) -> Robot:
    """Load the robot ``plan`` was made for (its URDF copy when it carries one).

    Raises:
        PlanFileError: the file at the plan's URDF path differs from the plan's copy, or the
            robot's joints are not the plan's.
        ModelError: the URDF (copy or file) is not a valid robot.
    """
    ref = plan.robot
    if ref.urdf_text:
        text = _on_disk(ref.urdf)
        if text is not None and sha256_hex(text) != ref.urdf_sha256:
            raise PlanFileError(
                f"the URDF {ref.urdf} has changed since the plan was made (SHA-256 "
                f"{sha256_hex(text)[:16]}..., the plan's copy {ref.urdf_sha256[:16]}...); re-plan "
                "for it, or move it away to check the plan against the copy it carries"
            )
        robot = load_robot(ref.urdf, ref.frames, text=ref.urdf_text)
        if text is None:  # gone: readers that take a path (the page's mesh check) get one
            robot = replace(robot, urdf=_materialised(ref.urdf_text, Path(ref.urdf)))
    else:
        LOGGER.warning(
            "a plan written before %s carries no copy of its URDF: read from %s as it is now "
            "(a plan made by this freefloat carries its URDF)",
            BASIS_FORMATS[0],
            ref.urdf,
        )
        robot = load_robot(ref.urdf, ref.frames)
    if robot.joint_names != list(ref.joints):
        raise PlanFileError(
            f"the plan's joints {ref.joints} do not match the URDF's {robot.joint_names}"
        )
    return robot
