"""The API reference at ``/docs``, rendered on the server from the OpenAPI schema as plain
HTML. FastAPI's own Swagger UI page loads its script from a CDN and starts it with an inline
script: the plant network has no internet, and the service's Content-Security-Policy forbids
inline script (:mod:`steamtwin.web.access`). The machine-readable schema stays at
``/openapi.json`` (OpenAPI 3.1) for any client generator."""

from __future__ import annotations

from html import escape
from typing import Any

__all__ = ["render_api_docs"]

METHODS = ("get", "post", "put", "patch", "delete")


def _parameters(operation: dict[str, Any]) -> str:
    rows = []
    for parameter in operation.get("parameters", []):
        schema = parameter.get("schema", {})
        kind = schema.get("type") or " | ".join(
            str(option.get("type", "")) for option in schema.get("anyOf", []))
        rows.append(f"<tr><td><code>{escape(parameter['name'])}</code></td>"
                    f"<td>{escape(parameter.get('in', ''))}</td><td>{escape(kind)}</td>"
                    f"<td>{'yes' if parameter.get('required') else 'no'}</td>"
                    f"<td>{escape(parameter.get('description', '') or '')}</td></tr>")
    if "requestBody" in operation:
        rows.append("<tr><td><code>body</code></td><td>body</td><td>JSON</td><td>"
                    f"{'yes' if operation['requestBody'].get('required') else 'no'}</td>"
                    "<td>see the schema</td></tr>")
    if not rows:
        return ""
    return ("<table><thead><tr><th>name</th><th>in</th><th>type</th><th>required</th>"
            f"<th>meaning</th></tr></thead><tbody>{''.join(rows)}</tbody></table>")


def render_api_docs(schema: dict[str, Any]) -> str:
    """An HTML page listing every path, method, summary, description and parameter."""
    info = schema.get("info", {})
    sections = []
    for path, item in schema.get("paths", {}).items():
        for method in METHODS:
            operation = item.get(method)
            if operation is None:
                continue
            responses = ", ".join(escape(code) for code in operation.get("responses", {}))
            sections.append(
                f"<section><h2><span class=\"method\">{method.upper()}</span> "
                f"<code>{escape(path)}</code></h2><p>{escape(operation.get('summary', ''))}</p>"
                f"<pre>{escape(operation.get('description', '') or '')}</pre>"
                f"{_parameters(operation)}<p>responses: {responses}</p></section>")
    return ("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>{escape(info.get('title', 'API'))} — API</title>"
            "<link rel=\"stylesheet\" href=\"/static/style.css\"></head><body><main>"
            f"<h1>{escape(info.get('title', 'API'))} {escape(info.get('version', ''))}</h1>"
            f"<p>{escape(info.get('description', ''))}</p>"
            "<p>Machine-readable: <a href=\"/openapi.json\">/openapi.json</a> (OpenAPI "
            f"{escape(schema.get('openapi', ''))}).</p>{''.join(sections)}</main></body></html>")
