"""Unknown-key checks for the project's TOML and JSON inputs, with a "did you mean" hint.

Specs, parameter files and tag maps are strict: a key the schema does not know is an error,
never silently ignored (a misspelled ``[[extraction]]`` would otherwise drop a bleed). The hint
is the closest known key by :func:`difflib.get_close_matches` (Ratcliff–Obershelp similarity,
cutoff 0.6, the standard library's default).
"""

from __future__ import annotations

import difflib
from collections.abc import Collection, Mapping

__all__ = ["did_you_mean", "unknown_key_message"]


def did_you_mean(key: str, known: Collection[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest known key, or an empty string if none is close."""
    close = difflib.get_close_matches(str(key), [str(k) for k in known], n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def unknown_key_message(table: Mapping[str, object], known: Collection[str],
                        path: str, source: str, what: str) -> str | None:
    """Error text for the first key of ``table`` not in ``known``, or None if all are known.

    ``path`` is the TOML/JSON path of ``table`` (empty at top level), ``source`` the file name
    and ``what`` the kind of file ("turbine spec", "parameter file", ...).
    """
    for key in table:
        if key not in known:
            field = f"{path}.{key}" if path else str(key)
            return (f"{source}: {field} is not a {what} field{did_you_mean(key, known)}; "
                    f"expected one of: {', '.join(sorted(known))}")
    return None
