"""Dotted keys into a scenario's TOML tables (``goal.joints.q2``, ``goal.base_zyx_deg.0``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from ..errors import ScenarioError, UnknownNameError

__all__ = ["leaf", "put", "split_key"]


def split_key(key: str, base: Mapping[str, Any]) -> tuple[str | int, ...]:
    """Resolve a dotted key against the base scenario; refuse it naming the valid keys."""
    if not key:
        raise ScenarioError('axis key must be a dotted key such as "goal.joints.q2"')
    path: list[str | int] = []
    node: Any = base
    for part in key.split("."):
        prefix = ".".join(str(p) for p in path)
        where = f"{prefix}." if prefix else ""
        if isinstance(node, Mapping):
            if part not in node:
                raise UnknownNameError("sweep key", key, [f"{where}{k}" for k in node])
            path.append(part)
            node = node[part]
        elif isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                raise UnknownNameError("sweep key", key, [f"{where}{i}" for i in range(len(node))])
            path.append(int(part))
            node = node[int(part)]
        else:
            raise ScenarioError(f"sweep key {key!r}: {prefix!r} is a value, not a table or list")
    if isinstance(node, (Mapping, list)):
        inner = node if isinstance(node, Mapping) else range(len(node))
        raise UnknownNameError(
            "sweep key (it names a table or list, not a value)",
            key,
            [f"{key}.{k}" for k in inner],
        )
    return tuple(path)


def leaf(base: Mapping[str, Any], path: Sequence[str | int]) -> Any:
    """The value at ``path`` in nested tables and lists."""
    node: Any = base
    for part in path:
        node = node[part]
    return node


def put(data: Any, path: Sequence[str | int], value: Any) -> None:
    """Set the value at ``path`` in nested tables and lists."""
    node = data
    for part in path[:-1]:
        node = node[part]
    node[path[-1]] = value
