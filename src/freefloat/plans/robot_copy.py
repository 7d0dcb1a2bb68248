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

from pathlib import Path

from ..errors import PlanFileError
from ..files import read_text_file
from ..progress import LOGGER
from ..robot.model import MAX_URDF_BYTES, Robot, load_robot
from .format import Plan, sha256_hex

__all__ = ["plan_robot"]


def _on_disk(path: str) -> str | None:
    """The text of the URDF file at ``path``, or None when there is none."""
    if not Path(path).exists():
        return None
    return read_text_file(path, "URDF", MAX_URDF_BYTES, PlanFileError)


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
        robot = load_robot(ref.urdf, ref.end_effector, text=ref.urdf_text)
    else:
        LOGGER.warning(
            "a %s plan carries no copy of its URDF: read from %s as it is now (a plan made by "
            "this freefloat carries its URDF)",
            plan.format,
            ref.urdf,
        )
        robot = load_robot(ref.urdf, ref.end_effector)
    if robot.joint_names != list(ref.joints):
        raise PlanFileError(
            f"the plan's joints {ref.joints} do not match the URDF's {robot.joint_names}"
        )
    return robot
