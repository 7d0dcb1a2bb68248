"""JSON Schemas of the plan file and the scenario file, shipped in ``freefloat/schemas/``.

:func:`schema` returns one (``"plan"`` or ``"scenario"``); :func:`schema_errors` lists what is
wrong with a document as one line per problem, naming the field by its path (for example
``samples.tau[3][1]: expected a number, got 'x'``); :func:`check_plan_file` reads a plan file
and raises :class:`~freefloat.errors.PlanFileError` naming the first bad field;
:func:`load_plan_file` reads a plan file once, checks it against the schema and the limits of
:mod:`freefloat.plans.limits`, and returns the plan. The schema
describes ``freefloat.plan/5`` and ``/4`` (the URDF copy and the records they require, the optional
robustness record), ``/3`` (the objective record it requires) and ``/2``; ``/1`` files are left
to :meth:`Plan.load`.

The names of plug-ins in the schemas (objectives, recorded constraints) come from their
registries: :func:`schema` fills them in from the live registries (so a plug-in registered at
run time is accepted), and the shipped files hold those of the built-in plug-ins, which
``tests/test_structure.py`` checks against the registries (:func:`schema_text` writes them).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import PlanFileError, ViewerError
from .format import Plan
from .io import read_plan_json
from .limits import MAX_SAMPLES
from .versions import FORMAT, FORMAT_2, FORMAT_3, FORMAT_4

__all__ = [
    "SCHEMAS",
    "check_plan_file",
    "field_path",
    "load_plan_file",
    "registry_names",
    "schema",
    "schema_errors",
    "schema_text",
]

#: The shipped schemas by name.
SCHEMAS = ("plan", "scenario")

_TYPES = {
    "number": "a number",
    "integer": "an integer",
    "string": "a string",
    "boolean": "true or false",
    "array": "a list",
    "object": "an object",
    "null": "null",
}


#: Where each schema lists plug-in names: the path of the ``enum`` and the registry's kind.
_REGISTRY_ENUMS: dict[str, tuple[tuple[tuple[str, ...], str], ...]] = {
    "plan": (
        (("properties", "objective", "properties", "name"), "objectives"),
        (("properties", "constraints", "items", "properties", "name"), "recorded constraints"),
    ),
    "scenario": (
        (("properties", "path", "properties", "objective"), "objectives"),
        (("properties", "constraints", "propertyNames"), "scenario constraints"),
    ),
}


def registry_names(kind: str) -> list[str]:
    """Names in a registry, as the schemas list them.

    ``kind``: ``objectives``, ``recorded constraints`` (a plan's records) or ``scenario
    constraints`` (a scenario's tables: not the joint limits, always honoured).
    """
    from ..problem.constraints import default_constraints, recorded_constraints
    from ..problem.objectives import OBJECTIVES

    if kind == "objectives":
        return list(OBJECTIVES)
    if kind == "recorded constraints":
        return recorded_constraints()
    always = {c.name for c in default_constraints()}
    return [name for name in recorded_constraints() if name not in always]


def _shipped(name: str) -> dict[str, Any]:
    if name not in SCHEMAS:
        raise ValueError(f"unknown schema {name!r}; valid: {', '.join(SCHEMAS)}")
    text = (resources.files("freefloat") / "schemas" / f"{name}.schema.json").read_text("utf-8")
    loaded: dict[str, Any] = json.loads(text)
    return loaded


@cache
def _filled(name: str, names: tuple[tuple[str, ...], ...]) -> dict[str, Any]:
    document = _shipped(name)
    for (path, _), enum in zip(_REGISTRY_ENUMS[name], names, strict=True):
        node = document
        for key in path:
            node = node[key]
        node["enum"] = list(enum)
    return document


def schema(name: str) -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) ``name``: ``"plan"`` or ``"scenario"``.

    Plug-in names are those of the registries now (see the module docstring). Shared between
    callers: read-only.
    """
    if name not in SCHEMAS:
        raise ValueError(f"unknown schema {name!r}; valid: {', '.join(SCHEMAS)}")
    names = tuple(tuple(registry_names(kind)) for _, kind in _REGISTRY_ENUMS[name])
    return _filled(name, names)


def schema_text(name: str) -> str:
    """The text of the shipped schema file ``name`` with the registries' names filled in."""
    return json.dumps(schema(name), indent=1) + "\n"


def field_path(parts: Iterable[str | int]) -> str:
    """``['samples', 'tau', 3]`` -> ``samples.tau[3]`` (``(top level)`` when empty)."""
    out = ""
    for part in parts:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out or "(top level)"


def _describe(error: Any) -> str:
    where = field_path(error.absolute_path)
    got = repr(error.instance)
    if len(got) > 40:
        got = got[:37] + "..."
    kind = error.validator
    if kind == "type":
        wanted = error.validator_value
        wanted = [wanted] if isinstance(wanted, str) else wanted
        return f"{where}: expected {' or '.join(_TYPES.get(w, w) for w in wanted)}, got {got}"
    if kind == "required":
        missing = next((k for k in error.validator_value if k not in error.instance), "?")
        return f"{field_path([*error.absolute_path, missing])}: missing"
    if kind == "additionalProperties":
        allowed = error.schema.get("properties", {})
        extra = sorted(k for k in error.instance if k not in allowed)
        return f"{where}: unknown key {', '.join(map(repr, extra))}; valid: {', '.join(allowed)}"
    if kind == "anyOf" and all(set(o) == {"required"} for o in error.validator_value):
        keys = [k for o in error.validator_value for k in o["required"]]
        return f"{where}: give {' or '.join(map(repr, keys))}"
    if kind in ("const", "enum"):
        valid = [error.validator_value] if kind == "const" else error.validator_value
        return f"{where}: expected {' or '.join(map(repr, valid))}, got {got}"
    if kind == "minLength":
        return f"{where}: {got} is empty; give at least {error.validator_value} character(s)"
    if kind in ("minItems", "maxItems"):
        least = "at least" if kind == "minItems" else "at most"
        count = error.validator_value
        return f"{where}: expected {least} {count} entr{'y' if count == 1 else 'ies'}, got {got}"
    bounds = {
        "minimum": "less than the minimum of",
        "maximum": "greater than the maximum of",
        "exclusiveMinimum": "at most the exclusive minimum of",
        "exclusiveMaximum": "at least the exclusive maximum of",
    }
    if kind in bounds:
        return f"{where}: {got} is {bounds[kind]} {error.validator_value}"
    message = str(error.message)
    return f"{where}: {message if len(message) <= 120 else message[:117] + '...'}"


def schema_errors(document: Any, name: str = "plan") -> list[str]:
    """Every schema violation of ``document``, one line each, most relevant first.

    Raises:
        ViewerError: jsonschema is missing.
    """
    try:
        import jsonschema
        from jsonschema.exceptions import relevance
    except ImportError as exc:  # pragma: no cover - a dependency
        raise ViewerError(
            f"schema checks need jsonschema ({exc}): pip install jsonschema"
        ) from None
    validator = jsonschema.Draft202012Validator(schema(name))
    errors = sorted(validator.iter_errors(document), key=relevance)
    return [_describe(_deepest(e)) for e in errors]


def _deepest(error: Any) -> Any:
    """For oneOf/anyOf failures, the sub-error that went deepest (the likely intent)."""
    if error.context:
        best = max(error.context, key=lambda e: len(e.absolute_path))
        if len(best.absolute_path) > len(error.absolute_path):
            return _deepest(best)
    return error


def check_plan_file(path: str | Path) -> None:
    """Check a plan file against the plan schema before it is read.

    Files of other formats are not checked here (:meth:`Plan.load` converts or refuses them).

    Raises:
        PlanFileError: missing, not JSON, or a field that breaks the schema (named).
    """
    path = Path(path).expanduser()
    _check_schema(read_plan_json(path), path)


def _check_schema(data: Any, path: Path) -> None:
    if isinstance(data, dict) and data.get("format") not in (FORMAT, FORMAT_4, FORMAT_3, FORMAT_2):
        return
    _check_list_lengths(data, str(path))  # before the schema's walk over every entry
    errors = schema_errors(data, "plan")
    if errors:
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        raise PlanFileError(f"{path}: does not match the plan schema: {errors[0]}{more}")


def _check_list_lengths(data: Any, where: str = "plan") -> None:
    """Refuse a list longer than :data:`MAX_SAMPLES` entries anywhere in a parsed plan file.

    Before the schema check, which walks every entry (95 million entries in a 181 MiB file
    took minutes): a long list is refused without a look at its entries.

    Raises:
        PlanFileError: the first such list, named by its field.
    """
    stack: list[tuple[Any, list[str | int]]] = [(data, [])]
    while stack:
        node, path = stack.pop()
        if isinstance(node, Mapping):
            stack += [(value, [*path, key]) for key, value in node.items()]
        elif isinstance(node, list):
            if len(node) > MAX_SAMPLES:
                field = ".".join(str(p) for p in path) or "(top level)"
                raise PlanFileError(
                    f"{where}: {field} has {len(node)} entries, more than the "
                    f"{MAX_SAMPLES} a plan file may have"
                )
            stack += [
                (value, [*path, k])
                for k, value in enumerate(node)
                if isinstance(value, (list, Mapping))
            ]


def load_plan_file(path: str | Path) -> Plan:
    """Read a plan file once: the schema first (formats 2 to 5), then its limits, then the plan.

    Raises:
        PlanFileError: not a regular file, too large, not JSON, a field that breaks the schema
            or a limit (named), another format version.
    """
    path = Path(path).expanduser()
    data = read_plan_json(path)
    _check_schema(data, path)
    return Plan.from_dict(data, str(path), path.parent)
