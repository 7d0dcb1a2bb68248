"""Plug-in registries: the built-in plug-ins of one kind plus those other packages install.

Each kind of plug-in (constraints, objectives, solver strategies, export formats) is listed in
one :class:`Registry`, a mapping from name to plug-in. Besides the built-ins, a registry holds
the plug-ins that installed packages declare as entry points of its group, for example in a
package's ``pyproject.toml``::

    [project.entry-points."freefloat.constraints"]
    ceiling = "mypkg.ceiling:Ceiling"

The entry points are loaded once, when the registry is first read (not when freefloat is
imported), so that every process (``freefloat plan``, then ``freefloat verify`` of its file)
knows the same plug-ins. An entry point that cannot be imported, that is not a plug-in of its
kind, or whose name is already taken raises :class:`~freefloat.errors.PluginError`, one line
naming the package, the entry point and what went wrong. Registering by hand
(``REGISTRY[name] = plugin``) still works, for the running process only.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, MutableMapping
from importlib.metadata import EntryPoint, entry_points
from typing import Any, Generic, TypeVar

from .errors import PluginError

__all__ = ["GROUPS", "Registry", "plugin_class", "plugin_function"]

T = TypeVar("T")

#: The entry point group of each kind of plug-in.
GROUPS = {
    "constraint": "freefloat.constraints",
    "objective": "freefloat.objectives",
    "strategy": "freefloat.strategies",
    "export format": "freefloat.exports",
}


class Registry(MutableMapping[str, T], Generic[T]):
    """The plug-ins of one kind by name: built-ins, then installed entry points.

    Args:
        kind: the kind, a key of :data:`GROUPS` (named in messages).
        builtins: the built-in plug-ins by name, in order.
        accept: turns a loaded entry point into a plug-in, or raises ``TypeError`` /
            ``ValueError`` saying why it is not one (the message's end).
    """

    def __init__(
        self, kind: str, builtins: Mapping[str, T], accept: Callable[[str, object], T]
    ) -> None:
        self.kind, self.group = kind, GROUPS[kind]
        self._items: dict[str, T] = dict(builtins)
        self._accept = accept
        self._state = "new"  # "new", "loading", "loaded"

    def _load(self) -> None:
        if self._state != "new":
            return
        self._state = "loading"  # a plug-in reading its registry while imported sees the rest
        try:
            for point in entry_points(group=self.group):
                self._add(point)
        except BaseException:
            self._state = "new"  # the next read reports the same error again
            raise
        self._state = "loaded"

    def _add(self, point: EntryPoint) -> None:
        dist = point.dist.name if point.dist is not None else "(unknown)"
        if point.name in self._items:
            taken = _describe(self._items[point.name])
            reason = f"the name is already taken by {taken}; choose another name"
            raise PluginError(self.group, point.name, dist, reason)
        try:
            loaded = point.load()
        except Exception as exc:  # its import failed: say why, in one line
            reason = f"cannot load {point.value!r}: {type(exc).__name__}: {exc}"
            raise PluginError(self.group, point.name, dist, reason.splitlines()[0]) from None
        try:
            plugin = self._accept(point.name, loaded)
        except (TypeError, ValueError) as exc:
            raise PluginError(self.group, point.name, dist, str(exc)) from None
        self._items[point.name] = plugin

    def __getitem__(self, name: str) -> T:
        self._load()
        return self._items[name]

    def __setitem__(self, name: str, plugin: T) -> None:
        self._load()
        self._items[name] = plugin

    def __delitem__(self, name: str) -> None:
        self._load()
        del self._items[name]

    def __iter__(self) -> Iterator[str]:
        self._load()
        return iter(list(self._items))

    def __len__(self) -> int:
        self._load()
        return len(self._items)

    def __contains__(self, name: object) -> bool:
        self._load()
        return name in self._items

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {list(self)!r})"


def _describe(plugin: object) -> str:
    """``module.Name`` of a plug-in (a class or a function)."""
    module = getattr(plugin, "__module__", "?")
    return f"{module}.{getattr(plugin, '__qualname__', type(plugin).__name__)}"


def plugin_class(base: type, kind: str) -> Callable[[str, object], type]:
    """An ``accept`` for a :class:`Registry` of classes: a subclass of ``base`` named ``name``.

    The class's ``name`` attribute is what plans record, so it must be the entry point's name.
    """

    def accept(name: str, loaded: object) -> type:
        if not (isinstance(loaded, type) and issubclass(loaded, base)):
            raise TypeError(f"{_describe(loaded)} is not a {kind} (a subclass of {base.__name__})")
        if getattr(loaded, "name", None) != name:
            raise ValueError(
                f"{_describe(loaded)} is named {getattr(loaded, 'name', None)!r}; "
                f"the entry point must carry the same name"
            )
        return loaded

    return accept


def plugin_function(kind: str) -> Callable[[str, object], Any]:
    """An ``accept`` for a :class:`Registry` of functions (strategies, export writers)."""

    def accept(name: str, loaded: object) -> Any:
        if isinstance(loaded, type) or not callable(loaded):
            raise TypeError(f"{_describe(loaded)} is not a {kind} function")
        return loaded

    return accept
