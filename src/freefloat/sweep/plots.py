"""Feasibility maps of a sweep (matplotlib, Agg backend, imported when a plot is drawn).

One axis: the status and the attitude error along it and, for planar robots, the requested
yaw change against the planar bounds. Two axes: heat maps of the status and of the error.
Axis values are shown in the scenario file's units (degrees for angles).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from .jobs import STATUSES, SweepRow
from .spec import SweepSpec

__all__ = ["check_plottable", "plot_sweep"]

_COLOURS = {"planned": "tab:green", "infeasible": "tab:orange", "failed": "tab:red"}


def check_plottable(spec: SweepSpec) -> None:
    """Refuse, before any job runs, a sweep whose map cannot be drawn.

    Raises:
        InputError: not one or two axes, or an axis of non-numeric values.
    """
    if len(spec.axes) not in (1, 2):
        raise InputError(f"plots need 1 or 2 axes; this sweep has {len(spec.axes)}")
    for axis in spec.axes:
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in axis.values):
            raise InputError(f"plots need numeric axes; {axis.key!r} is not")


def plot_sweep(spec: SweepSpec, rows: Sequence[SweepRow], directory: str | Path) -> list[Path]:
    """Draw the feasibility map into ``directory`` (PNG); return the files written.

    Raises:
        InputError: the sweep cannot be drawn (see :func:`check_plottable`).
        ViewerError: matplotlib is missing or broken.
    """
    check_plottable(spec)
    from ..viz.plots import _pyplot

    plt = _pyplot()
    files = plot_files(spec, directory)
    files[0].parent.mkdir(parents=True, exist_ok=True)
    ordered = sorted(rows, key=lambda r: r.index)
    draw = _line_map if len(spec.axes) == 1 else _heat_map
    fig = draw(plt, spec, ordered)
    fig.savefig(files[0], dpi=120)
    plt.close(fig)
    return files


def plot_files(spec: SweepSpec, directory: str | Path) -> list[Path]:
    """The files :func:`plot_sweep` writes into ``directory``.

    The command checks each before any job runs (:func:`freefloat.files.check_output`).
    """
    folder = Path(directory).expanduser().resolve()
    return [folder / ("sweep_map.png" if len(spec.axes) == 1 else "sweep_heatmap.png")]


def _error(row: SweepRow) -> float:
    if row.status != "planned" or row.attitude_error_rad is None:
        return math.nan
    return max(row.attitude_error_rad, 1e-17)


def _or_nan(value: float | None) -> float:
    return math.nan if value is None else value


def _line_map(plt: Any, spec: SweepSpec, rows: Sequence[SweepRow]) -> Any:
    key = spec.axes[0].key
    x = np.array([float(r.values[0]) for r in rows])
    planar = any(r.yaw_change_min_deg is not None for r in rows)
    fig, axes = plt.subplots(3 if planar else 2, 1, sharex=True, figsize=(8, 7))
    ax = axes[0]
    for level, status in enumerate(STATUSES):
        mask = np.array([r.status == status for r in rows])
        ax.scatter(x[mask], np.full(mask.sum(), level), color=_COLOURS[status], s=12)
    ax.set_yticks(range(len(STATUSES)), STATUSES)
    ax.set_ylim(-0.5, len(STATUSES) - 0.5)
    planned = sum(r.status == "planned" for r in rows)
    ax.set_title(f"sweep over {key}: {planned}/{len(rows)} planned")
    ax = axes[1]
    ax.semilogy(x, [_error(r) for r in rows], "o", ms=3, color=_COLOURS["planned"])
    ax.set_ylabel("attitude error [rad]")
    if planar:
        ax = axes[2]
        req = [_or_nan(r.requested_yaw_change_deg) for r in rows]
        lo = [_or_nan(r.yaw_change_min_deg) for r in rows]
        hi = [_or_nan(r.yaw_change_max_deg) for r in rows]
        ax.fill_between(x, lo, hi, color="0.85", label="planar bounds (reachable)")
        for status in STATUSES:
            pts = [(xi, yi) for xi, yi, r in zip(x, req, rows, strict=True) if r.status == status]
            if pts:
                px, py = zip(*pts, strict=True)
                ax.plot(px, py, "o", ms=3, color=_COLOURS[status], label=status)
        ax.set_ylabel("yaw change [deg]")
        ax.legend(fontsize=8)
    axes[-1].set_xlabel(key)
    fig.tight_layout()
    return fig


def _heat_map(plt: Any, spec: SweepSpec, rows: Sequence[SweepRow]) -> Any:
    from matplotlib.colors import ListedColormap

    first, second = spec.axes
    shape = (len(first.values), len(second.values))
    status = np.full(shape, np.nan)
    error = np.full(shape, np.nan)
    for row in rows:
        i, j = divmod(row.index, shape[1])
        status[i, j] = STATUSES.index(row.status)
        error[i, j] = np.log10(_error(row))
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 5))
    extent_x = [float(v) for v in second.values]
    extent_y = [float(v) for v in first.values]
    cmap = ListedColormap([_COLOURS[s] for s in STATUSES])
    image = left.pcolormesh(
        extent_x, extent_y, status, cmap=cmap, vmin=-0.5, vmax=2.5, shading="nearest"
    )
    bar = fig.colorbar(image, ax=left, ticks=range(len(STATUSES)))
    bar.ax.set_yticklabels(STATUSES)
    left.set_title("status")
    image = right.pcolormesh(extent_x, extent_y, error, shading="nearest")
    fig.colorbar(image, ax=right, label="log10 attitude error [rad]")
    right.set_title("attitude error (planned)")
    for ax in (left, right):
        ax.set_xlabel(second.key)
        ax.set_ylabel(first.key)
    fig.tight_layout()
    return fig
