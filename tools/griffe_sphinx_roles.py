"""A griffe extension for the API reference (mkdocs.yml): Sphinx roles in docstrings → links.

steamtwin's docstrings cross-reference in the Sphinx/reST way (``:class:`~steamtwin.spec.
TurbineSpec```, ``:meth:`save```, ``:mod:`steamtwin.twinfile```). mkdocstrings renders
docstrings as Markdown, where a role would show as literal ``:class:`` text. This extension
rewrites each role, once the package is loaded, into an optional autorefs cross-reference
(``<autoref identifier="…" optional><code>…</code></autoref>``; mkdocs-autorefs' own
markup): a link when the target is rendered on some page, plain code otherwise — never a
warning, so ``mkdocs build --strict`` fails only on the references written in Markdown.

Names are resolved as Sphinx resolves them (Sphinx docs, "Cross-referencing Python
objects"): a dotted path as given, else relative to the object, its parents and the
package, or one of the names ``steamtwin`` re-exports lazily (its ``_EXPORTS`` table, PEP 562);
``~`` shows only the last component; ``title <target>`` gives an explicit title.
"""

from __future__ import annotations

import ast
import re
from typing import Any

import griffe

ROLE = re.compile(
    r":(?:py:)?(?:class|func|meth|mod|attr|data|exc|obj|const):`(?P<body>[^`]+)`")
EXPLICIT = re.compile(r"^(?P<title>.*?)\s*<(?P<target>[^>]+)>$")
LITERAL = re.compile(r"(?P<before>\S?)(?P<space>[ \t]*)::\n(?=[ \t]*\n)")
"""reST's ``text::`` before a blank line and an indented block (which Markdown shows as code
too): ``text:``; a lone ``::`` goes."""


def _find(root: griffe.Object, path: str) -> griffe.Object | griffe.Alias | None:
    """The object at dotted ``path`` under ``root`` (whose own path is its first part)."""
    parts = path.split(".")
    if parts[0] != root.path:
        return None
    node: Any = root
    for part in parts[1:]:
        try:
            members = node.members
        except griffe.AliasResolutionError:  # an import from outside the package
            return None
        if part not in members:
            return None
        node = members[part]
    return node


def _lazy_exports(root: griffe.Module) -> dict[str, str]:
    """Re-exported name → its path, from the package's ``_EXPORTS = {name: module}`` table."""
    table = root.members.get("_EXPORTS")
    if not isinstance(table, griffe.Attribute) or table.value is None:
        return {}
    modules = ast.literal_eval(str(table.value))
    return {f"{root.path}.{name}": f"{module}.{name}" for name, module in modules.items()}


def _resolve(root: griffe.Object, scope: griffe.Object, name: str,
             lazy: dict[str, str]) -> str | None:
    """The canonical path ``name`` refers to from ``scope``, None when it is not found."""
    name = name.lstrip(".")
    bases = [name]
    node: griffe.Object | None = scope
    while node is not None:
        bases.append(f"{node.path}.{name}")
        node = node.parent
    for candidate in bases:
        if candidate in lazy:
            return lazy[candidate]
        found = _find(root, candidate)
        if found is not None:
            return found.target_path if isinstance(found, griffe.Alias) else found.path
    return None


def _rewrite(root: griffe.Object, scope: griffe.Object, text: str, lazy: dict[str, str]
             ) -> str:
    def replace(match: re.Match[str]) -> str:
        body = match["body"].strip()
        explicit = EXPLICIT.match(body)
        target = explicit["target"] if explicit else body
        short = target.startswith("~")
        target = target.lstrip("~")
        title = explicit["title"] if explicit else (target.rsplit(".", 1)[-1] if short
                                                      else target)
        resolved = _resolve(root, scope, target, lazy)
        code = f"<code>{title}</code>"
        if resolved is None:
            return code
        return f'<autoref identifier="{resolved}" optional>{code}</autoref>'

    def literal(match: re.Match[str]) -> str:
        if match["before"] and not match["space"]:
            return f"{match['before']}:\n"
        return f"{match['before']}\n"

    return LITERAL.sub(literal, ROLE.sub(replace, text))


class SphinxRoles(griffe.Extension):
    """Rewrite the Sphinx roles of every docstring in the package once it is loaded."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        """Walk the package's own objects (not the aliases of imported names)."""
        lazy = _lazy_exports(pkg)
        pending: list[griffe.Object] = [pkg]
        while pending:
            obj = pending.pop()
            if obj.docstring is not None:
                obj.docstring.value = _rewrite(pkg, obj, obj.docstring.value, lazy)
            pending.extend(member for member in obj.members.values()
                           if not isinstance(member, griffe.Alias))
