"""A meshcat scene kept in this process, and its self-contained page: no server needed.

meshcat's Python side turns each drawing call into a command (``set_object``,
``set_transform``, ``set_property``, ``set_animation``, ``delete``) and hands it to its
window, which normally forwards it to a server subprocess; the server keeps the latest state of
every node of the scene tree and writes the standalone page from it. :class:`RecordedScene` is
a window that keeps that state itself, node by node with the server's rules (a new object
drops the node's properties, a transform or an animation replaces the last, properties
accumulate, ``delete`` removes a subtree), and writes the page the same way: the viewer's
script, then one embedded command per kept state in tree order. A page then costs neither a
subprocess (about 0.3 s to start on a 2-core machine) nor a network port.
"""

from __future__ import annotations

import base64
from pathlib import Path
from typing import Any

__all__ = ["RecordedScene"]

#: The page around the viewer's script and the scene's commands.
_PAGE = """<!DOCTYPE html>
<html>
<head><meta charset=utf-8><title>MeshCat</title></head>
<body>
<div id="meshcat-pane"></div>
<script>
__VIEWER_SCRIPT__
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
__COMMANDS__
</script>
<style>
body {margin: 0;}
#meshcat-pane {width: 100vw; height: 100vh; overflow: hidden;}
</style>
</body>
</html>
"""
#: One embedded command: msgpack bytes, base64, handed to the viewer.
_COMMAND = (
    'fetch("data:application/octet-binary;base64,{data}")\n'
    "    .then(res => res.arrayBuffer())\n"
    "    .then(buffer => viewer.handle_command_bytearray(new Uint8Array(buffer)));\n"
)


class _Node:
    """One node of the scene tree: its latest object, properties, transform and animation."""

    def __init__(self) -> None:
        self.children: dict[str, _Node] = {}
        self.object: bytes | None = None
        self.properties: list[bytes] = []
        self.transform: bytes | None = None
        self.animation: bytes | None = None

    def find(self, parts: list[str]) -> _Node:
        """The node below this one at ``parts``, made on the way when missing."""
        node = self
        for part in parts:
            node = node.children.setdefault(part, _Node())
        return node

    def walk(self) -> list[_Node]:
        """This node and every node below it, depth first in the order they were made."""
        out = [self]
        for child in self.children.values():
            out.extend(child.walk())
        return out


class RecordedScene:
    """A meshcat window (``meshcat.Visualizer(window=RecordedScene())``) that keeps the scene.

    Attributes:
        web_url: empty: no server serves this scene.
    """

    web_url = ""

    def __init__(self) -> None:
        self._root = _Node()

    def send(self, command: Any) -> None:
        """Keep one meshcat command (``SetObject``, ``SetTransform``, ... from meshcat)."""
        import umsgpack  # meshcat's own encoder: the viewer decodes what it writes

        data = command.lower()
        kind = data["type"]
        parts = [part for part in str(data["path"]).split("/") if part]
        if kind == "delete":
            if parts:
                self._root.find(parts[:-1]).children.pop(parts[-1], None)
            else:
                self._root = _Node()
            return
        packed = umsgpack.packb(data)
        node = self._root.find(parts)
        if kind == "set_object":
            node.object, node.properties = packed, []
        elif kind == "set_transform":
            node.transform = packed
        elif kind == "set_property":
            node.properties.append(packed)
        elif kind == "set_animation":
            node.animation = packed
        else:
            raise ValueError(f"meshcat command {kind!r} cannot be kept in a page")

    def get_scene(self) -> str:
        """The standalone page of the kept scene (what ``Visualizer.static_html`` returns)."""
        commands = []
        for node in self._root.walk():
            kept = [node.object, *node.properties, node.transform, node.animation]
            commands += [_COMMAND.format(data=base64.b64encode(k).decode()) for k in kept if k]
        return _PAGE.replace("__VIEWER_SCRIPT__", _viewer_script()).replace(
            "__COMMANDS__", "".join(commands)
        )


def _viewer_script() -> str:
    """The browser viewer meshcat ships (its ``main.min.js``)."""
    import meshcat

    path = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
    return path.read_text(encoding="utf-8")
