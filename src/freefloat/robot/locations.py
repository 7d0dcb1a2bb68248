"""Where robots are: shipped robots and scenarios, example-robot-data, a name or a path."""

from __future__ import annotations

import importlib.metadata
from pathlib import Path

from ..errors import ModelError, UnknownNameError
from ..files import absolute_path

__all__ = [
    "example_robot_data_dir",
    "is_path_like",
    "resolve_robot",
    "robots_dir",
    "shipped_robots",
]


def example_robot_data_dir() -> Path | None:
    """The ``share`` folder holding ``example-robot-data`` (its package dir), if installed."""
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    share = Path(str(dist.locate_file("cmeel.prefix/share")))
    return share if (share / "example-robot-data").is_dir() else None


def robots_dir() -> Path:
    """Folder of the shipped robots and scenarios (installed package data or the checkout)."""
    installed = Path(__file__).resolve().parents[1] / "robots"
    if installed.is_dir():
        return installed
    checkout = Path(__file__).resolve().parents[3] / "robots"
    if checkout.is_dir():
        return checkout
    raise ModelError("the shipped robots folder is missing from this installation")


def shipped_robots() -> list[str]:
    """Names of the shipped robots (URDF files in :func:`robots_dir`)."""
    return sorted(p.stem for p in robots_dir().glob("*.urdf"))


def is_path_like(text: str) -> bool:
    """Whether a robot or arm given as text names a file rather than a robot or arm.

    A file has a folder in it (a slash or a backslash), a leading ``~`` or a ``.urdf`` suffix (any
    case); ``robot = "..."`` and a servicer's ``arm`` use this one rule.
    """
    return "/" in text or "\\" in text or text.startswith("~") or text.lower().endswith(".urdf")


def resolve_robot(name_or_path: str | Path, relative_to: Path | None = None) -> Path:
    """Resolve a shipped robot name or a URDF path to an absolute URDF path.

    A name (``"planar_2dof"``; see :func:`is_path_like`) is a shipped robot; anything else is a
    path, relative to ``relative_to`` (a folder) when not absolute.
    """
    text = str(name_or_path)
    if "://" in text:  # a URL or package:// path: read as a path, it loses a slash
        raise ModelError(
            f"robot {text!r} is a URL; give a shipped robot name or the path of a URDF file "
            "(package:// paths are read inside a URDF, for its meshes, not here)"
        )
    if not is_path_like(text):
        path = robots_dir() / f"{text}.urdf"
        if not path.is_file():
            raise UnknownNameError("robot", text, shipped_robots())
        return path
    path = Path(text).expanduser()
    if not path.is_absolute() and relative_to is not None:
        path = relative_to / path
    return absolute_path(path, "URDF", ModelError)
