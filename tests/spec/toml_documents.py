"""Test helpers shared by the spec tests: parsed TOML documents written back and walked."""

from __future__ import annotations

import datetime
import json
from typing import Any

KeyPath = tuple[str | int, ...]


def toml_value(value: Any) -> str:
    """``value`` as TOML (tables inline), enough for the types a parsed document holds."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)  # JSON string escapes are valid TOML basic-string escapes
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, datetime.date):
        return value.isoformat()
    if isinstance(value, list):
        return "[" + ", ".join(map(toml_value, value)) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(v)}" for k, v in value.items()) + "}"


def toml_text(document: dict[str, Any]) -> str:
    """A parsed TOML document written back as TOML text (tables inline)."""
    return "\n".join(f"{json.dumps(k)} = {toml_value(v)}" for k, v in document.items()) + "\n"


def key_paths(node: Any, prefix: KeyPath = ()) -> list[KeyPath]:
    """Every key of every table under ``node``, as a path of keys and list positions."""
    paths: list[KeyPath] = []
    if isinstance(node, dict):
        for key, value in node.items():
            paths.append((*prefix, key))
            paths += key_paths(value, (*prefix, key))
    elif isinstance(node, list):
        for index, item in enumerate(node):
            paths += key_paths(item, (*prefix, index))
    return paths
