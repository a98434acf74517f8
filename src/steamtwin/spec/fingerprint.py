"""A turbine spec's identity: a SHA-256 content hash of its validated form, and its TOML text.

The hash is taken over a canonical JSON form of the validated :class:`TurbineSpec` (SI
values), not over the TOML text: the same turbine written with other whitespace, comments, key
order or units ("16.7 MPa" or "167 bar" when both give the same float) has the same hash, and
any change of a value changes it. Canonical form (:data:`CANONICAL_FORM` = 1): every dataclass
as a JSON object of its fields, sorted keys, numbers as ``repr(float(x))`` text (the shortest
text that reads back to the same double, so the hash is exact and platform-independent), tuples
as arrays; a field with a default that holds its default is left out, so a field added to the
spec format later (always with a default, see docs/spec.md) leaves the hashes of existing specs
unchanged.
"""

from __future__ import annotations

import hashlib
import json
import numbers
from dataclasses import MISSING, fields, is_dataclass
from importlib import resources
from pathlib import Path

from steamtwin.spec.loader import BUILT_IN, SpecError, parse_spec
from steamtwin.spec.turbine import TurbineSpec
from steamtwin.textfile import read_utf8_text

__all__ = ["CANONICAL_FORM", "builtin_spec_text", "canonical_spec_json", "load_spec_and_text",
           "short_hash", "spec_hash"]

CANONICAL_FORM = 1
SHORT_HASH_LENGTH = 12  # hex digits shown in messages (48 bits)


def _canonical(value: object) -> object:
    if is_dataclass(value) and not isinstance(value, type):
        document = {}
        for field in fields(value):
            item = getattr(value, field.name)
            default = (field.default if field.default is not MISSING
                       else field.default_factory() if field.default_factory is not MISSING
                       else MISSING)
            if default is not MISSING and item == default:
                continue
            document[field.name] = _canonical(item)
        return document
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, numbers.Real):
        return repr(float(value))
    if isinstance(value, tuple | list):
        return [_canonical(item) for item in value]
    raise TypeError(f"cannot put a {type(value).__name__} into a spec's canonical form")


def canonical_spec_json(spec: TurbineSpec) -> str:
    """The canonical JSON text of ``spec`` (module docstring) that :func:`spec_hash` hashes."""
    document = {"canonical_form": CANONICAL_FORM, "spec": _canonical(spec)}
    return json.dumps(document, sort_keys=True, separators=(",", ":"), ensure_ascii=True)


def spec_hash(spec: TurbineSpec) -> str:
    """SHA-256 (64 hex digits) of :func:`canonical_spec_json`."""
    return hashlib.sha256(canonical_spec_json(spec).encode("ascii")).hexdigest()


def short_hash(digest: str) -> str:
    """The first 12 hex digits of a hash, as messages show it."""
    return digest[:SHORT_HASH_LENGTH]


def load_spec_and_text(source: str | Path) -> tuple[TurbineSpec, str]:
    """Like :func:`~steamtwin.spec.load_spec`, also returning the TOML text it was read from."""
    if str(source) in BUILT_IN:
        text = (resources.files("steamtwin.spec") / "data" / f"{source}.toml").read_text(
            encoding="utf-8")
        return parse_spec(text, f"built-in '{source}'"), text
    path = Path(source)
    if not path.is_file():
        raise SpecError(
            f"turbine spec {str(source)!r} is neither a built-in ({', '.join(BUILT_IN)}) nor a file"
        )
    text = read_utf8_text(path, "turbine spec", "TOML", SpecError)
    return parse_spec(text, str(path)), text


def builtin_spec_text(spec: TurbineSpec) -> str | None:
    """The TOML text of the built-in turbine ``spec`` is (same hash), None if it is none."""
    digest = spec_hash(spec)
    for name in BUILT_IN:
        built_in, text = load_spec_and_text(name)
        if spec_hash(built_in) == digest:
            return text
    return None
