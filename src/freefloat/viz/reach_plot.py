"""Figure of a reachable attitude set (inner estimate); matplotlib is imported here only."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import ViewerError
from ..files import atomic_write
from ..solvers.reach import ReachEstimate

__all__ = ["save_reach_figure"]


def save_reach_figure(estimate: ReachEstimate, path: str | Path, title: str = "") -> Path:
    """Draw each direction's reached rotation vector (deg) from the quintic attitude; save.

    Returns the absolute path written (its folder is made if needed).

    Raises:
        FileError: the figure cannot be written.
    """
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - matplotlib is a dependency
        raise ViewerError(f"matplotlib is not available: {exc}") from exc
    figure = plt.figure(figsize=(6.5, 6.0))
    axes = figure.add_subplot(projection="3d")
    for d in estimate.directions:
        tip = np.degrees(d.reached) * d.axis
        axes.plot([0.0, tip[0]], [0.0, tip[1]], [0.0, tip[2]], color="tab:blue", lw=1.5)
        marker = "o" if d.stopped_by else "^"
        axes.scatter(*tip, color="tab:red" if d.stopped_by else "tab:green", marker=marker)
    axes.scatter([0.0], [0.0], [0.0], color="black")
    axes.set_xlabel("about base x [deg]")
    axes.set_ylabel("about base y [deg]")
    axes.set_zlabel("about base z [deg]")
    asked = max((math.degrees(d.asked) for d in estimate.directions), default=0.0)
    axes.set_title(
        (title + "\n" if title else "")
        + f"inner estimate of the reachable attitudes (asked up to {asked:.0f} deg);\n"
        "red: stopped (limit, singular map, budget), green: reached the asked angle",
        fontsize=9,
    )
    path = Path(path)
    kind = path.suffix.lower().lstrip(".") or "png"
    try:  # atomically, its folder made as every output's is
        return atomic_write(path, lambda tmp: figure.savefig(tmp, format=kind), path.suffix)
    finally:
        plt.close(figure)
