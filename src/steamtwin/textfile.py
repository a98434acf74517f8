"""Reading the project's small text inputs (specs, tag maps, parameter files) with clear errors.

Each is UTF-8 text (a byte-order mark, as Windows editors write it, is accepted). A file that
cannot be read, is not UTF-8 (a GBK or binary file) or is empty gives one message naming the
file, the byte and its line, and what the file should be — in the caller's own error type.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["read_utf8_text"]


def read_utf8_text(path: str | Path, what: str, syntax: str, error: type[ValueError]) -> str:
    """The text of ``path``. ``what`` names the file in messages ("turbine spec"), ``syntax``
    its format ("TOML"); problems raise ``error`` (a ValueError subclass) naming the file."""
    path = Path(path)
    try:
        content = path.read_bytes()
    except OSError as problem:
        raise error(f"{path}: cannot read the {what}: {problem.strerror or problem}") from None
    try:
        text = content.decode("utf-8-sig")
    except UnicodeDecodeError as problem:
        line = content.count(b"\n", 0, problem.start) + 1
        raise error(f"{path}: not UTF-8 text (byte 0x{content[problem.start]:02x} at offset "
                    f"{problem.start}, line {line}); a {what} is a {syntax} file saved as "
                    "UTF-8 — re-save it in that encoding") from None
    if not text.strip():
        raise error(f"{path}: the file is empty; a {what} is a {syntax} file")
    return text
