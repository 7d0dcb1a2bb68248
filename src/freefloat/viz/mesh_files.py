"""A visual's mesh file checked before it goes into a page: the viewer must be able to read it.

The page's viewer parses each mesh file in the browser and, when it cannot, leaves the link out
without a word. So each file is read here first and refused, naming it, unless it has the
structure of its format: an STL file binary (an 84-byte head, then exactly 50 bytes per
triangle it announces) or ASCII (``solid``, complete facets of three ``vertex`` lines of three
numbers each, ``endsolid``); a Wavefront OBJ file with at least three vertices of three numbers
and one face; a COLLADA file well-formed XML whose root is ``COLLADA``.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

from ..errors import ViewerError

__all__ = ["checked_mesh"]

_VERTEX = re.compile(rb"^\s*vertex\s+(\S+)\s+(\S+)\s+(\S+)\s*$", re.M)
_FACET_END = re.compile(rb"^\s*endfacet\b", re.M)
_OBJ_VERTEX = re.compile(rb"^v\s+(\S+)\s+(\S+)\s+(\S+)", re.M)
_OBJ_FACE = re.compile(rb"^f\s+\S+\s+\S+\s+\S+", re.M)


def checked_mesh(path: Path) -> bytes:
    """The bytes of an STL, OBJ or COLLADA file the viewer can read.

    Raises:
        ViewerError: the file cannot be read, or lacks its format's structure (named).
    """
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ViewerError(f"cannot read the mesh {path}: {exc}") from None
    suffix = path.suffix.lower()
    reason = _stl(data) if suffix == ".stl" else _obj(data) if suffix == ".obj" else _collada(data)
    if reason:
        raise ViewerError(f"cannot draw the mesh {path}: {reason}")
    return data


def _numbers(groups: list[tuple[bytes, ...]]) -> bool:
    try:
        for group in groups:
            for value in group:
                float(value)
    except ValueError:
        return False
    return True


def _stl(data: bytes) -> str:
    """Why ``data`` is not an STL file ("" when it is one)."""
    if len(data) >= 84:
        count = int.from_bytes(data[80:84], "little")
        if count > 0 and len(data) == 84 + 50 * count:
            return ""
    if not data.lstrip().startswith(b"solid"):
        return "neither a binary STL (84 bytes, then 50 per triangle) nor an ASCII one ('solid')"
    vertices = _VERTEX.findall(data)
    facets = len(_FACET_END.findall(data))
    if facets == 0 or len(vertices) != 3 * facets or b"endsolid" not in data:
        return (
            f"an ASCII STL cut short or malformed ({facets} complete facet(s), "
            f"{len(vertices)} vertex line(s), {'an' if b'endsolid' in data else 'no'} 'endsolid')"
        )
    if not _numbers(vertices):
        return "an ASCII STL vertex that is not three numbers"
    return ""


def _obj(data: bytes) -> str:
    """Why ``data`` is not a Wavefront OBJ file ("" when it is one)."""
    vertices = _OBJ_VERTEX.findall(data)
    if len(vertices) < 3 or not _OBJ_FACE.search(data) or not _numbers(vertices):
        return f"an OBJ file needs three vertices of three numbers and a face ({len(vertices)} 'v')"
    return ""


def _collada(data: bytes) -> str:
    """Why ``data`` is not a COLLADA file ("" when it is one)."""
    try:
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        return f"not well-formed COLLADA XML ({exc})"
    if not root.tag.endswith("COLLADA"):
        return f"an XML file whose root is <{root.tag}>, not <COLLADA>"
    return ""
