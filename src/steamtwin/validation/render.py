"""HTML pieces of a report (standard library only): cells, tables, summary, contents, figures.

Used by :class:`steamtwin.validation.html.ValidationReport`. Headers are "Readable name [unit]"
and numbers rounded by quantity (:mod:`steamtwin.validation.labels`); a table wider than
:data:`MAX_COLUMNS` is shown in parts that repeat its leading label columns, so that each fits a
1366-px screen; figures are embedded as base64 PNG; every text is HTML-escaped (:func:`escape`).
"""

from __future__ import annotations

import base64
import datetime as dt
import html
import json
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from urllib.parse import quote

import numpy as np
import pandas as pd

from steamtwin.validation.labels import (
    LABEL_COLUMNS,
    RESOLUTION,
    ROW_UNIT_COLUMNS,
    column_label,
    header_text,
    round_digits,
    unit_text,
    value_label,
)
from steamtwin.validation.summary import Headline

__all__ = ["MAX_COLUMNS", "MAX_KEY_COLUMNS", "STYLE", "escape", "figure_html", "format_value",
           "json_value", "provenance_html", "setting_text", "summary_html", "table_html",
           "with_contents"]

MAX_COLUMNS = 10
"""Most columns of one HTML table: at 0.85 em (13.6 px) a column takes ≤ 120 px when its header
wraps at word boundaries, so 10 fit the 1302 px a 1366-px screen leaves inside the margins."""
MAX_KEY_COLUMNS = 3
"""Most leading label columns (index, text, times) repeated in each part of a split table."""
STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; padding: 0 2em; color: #222;
       max-width: 1366px; box-sizing: border-box; line-height: 1.35; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; } h2 { font-size: 1.2em; margin-top: 1.6em; }
h3 { font-size: 1.05em; margin-top: 1.2em; }
.table-wrap { max-width: 100%; overflow-x: auto; }
table { border-collapse: collapse; margin: 0.5em 0 1em; font-size: 0.85em; max-width: 100%; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.5em; vertical-align: top;
         overflow-wrap: break-word; }
td.number { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
th { background: #f0f0f0; text-align: left; font-weight: 600; }
tbody th { font-weight: normal; }
figure { margin: 1em 0; } img { max-width: 100%; height: auto; }
figcaption { font-size: 0.9em; }
p.meta { color: #666; font-size: 0.85em; margin-top: 0; }
section.summary { border: 1px solid #bbb; border-radius: 6px; padding: 0.2em 1em 0.6em;
                  background: #fafafa; }
section.summary h2 { margin-top: 0.6em; }
p.verdict { font-weight: 600; margin: 0.3em 0; }
tr.pass td.status { color: #17612a; background: #e5f4e8; font-weight: 600; }
tr.fail td.status { color: #9b1c1c; background: #fbe5e5; font-weight: 600; }
section.provenance { margin-top: 3em; border-top: 2px solid #ddd; }
nav.contents ol { columns: 2; column-gap: 2em; font-size: 0.85em; margin: 0.3em 0; }
"""

def format_value(value: object, unit: str = "") -> str:
    """Text of a table cell: integers as they are, floats rounded by the rule of
    :mod:`steamtwin.validation.labels` for ``unit`` (3 significant figures, never finer than the
    unit's resolution; scientific with 3 significant figures below 1e-3 or from 1e6 when the
    unit sets no resolution), NaN/None as "–", times as "YYYY-MM-DD HH:MM:SS±HH:MM"."""
    if value is None or value is pd.NaT or value is pd.NA:
        return "–"
    if isinstance(value, bool | np.bool_):
        return "yes" if value else "no"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        number = float(value)
        if not math.isfinite(number):
            return "–" if math.isnan(number) else str(number)
        if number == 0.0:
            return "0"
        magnitude = abs(number)
        if unit not in RESOLUTION and not 1e-3 <= magnitude < 1e6:
            return f"{number:.2e}"
        decimals = round_digits(number, unit)
        text = f"{round(number, decimals):.{max(decimals, 0)}f}"
        return text.removeprefix("-") if float(text) == 0.0 else text
    if isinstance(value, pd.Timestamp | dt.datetime):
        return value.isoformat(sep=" ", timespec="seconds")
    return str(value)


def escape(value: object) -> str:
    """``value`` as text safe inside HTML elements and quoted attributes."""
    return html.escape(str(value), quote=True)


def setting_text(value: object) -> str:
    """A setting as given (floats to 6 significant figures: what the user chose, not a
    measured figure)."""
    if isinstance(value, Mapping):
        return json.dumps(json_value(value), ensure_ascii=False)
    if isinstance(value, list | tuple):
        return ", ".join(setting_text(v) for v in value)
    if isinstance(value, float | np.floating):
        return f"{float(value):g}"
    return format_value(value)


def summary_html(headlines: Sequence[Headline]) -> list[str]:
    """The summary: each headline figure beside its limit and the published value, marked."""
    if not headlines:
        return []
    passed = sum(h.passed for h in headlines)
    rows = []
    for h in headlines:
        status = ("✓ within" if h.passed else "✗ outside" if math.isfinite(h.value)
                  else "✗ no value")
        rows.append(f'<tr class="{"pass" if h.passed else "fail"}"><td>{escape(h.figure)}</td>'
                    f'<td class="number">{escape(_with_unit(h.value, h.unit))}</td>'
                    f'<td class="number">≤ {escape(f"{h.limit:g} {h.unit}")}</td>'
                    f"<td>{escape(h.published)}</td><td>{escape(h.source)}</td>"
                    f'<td class="status">{status}</td></tr>')
    return ['<section class="summary">', "<h2>Summary</h2>",
            f'<p class="verdict">{passed} of {len(headlines)} headline figures within their '
            "limits</p>", '<div class="table-wrap"><table class="headlines">',
            "<thead><tr><th>Figure</th><th>This run</th><th>Limit</th>"
            "<th>The method (published)</th><th>Limit from</th><th>Result</th></tr></thead>",
            "<tbody>" + "".join(rows) + "</tbody></table></div>", "</section>"]


def with_contents(body: list[str], after: int) -> list[str]:
    """``body`` with an id on every section heading and, after its first ``after`` lines (title
    and summary), a list of links to them (each heading shortened, :func:`_short`)."""
    lines, links = [], []
    for line in body:
        if line.startswith("<h2>") and line != "<h2>Summary</h2>":
            anchor = f"section-{len(links) + 1}"
            heading = html.unescape(line.removeprefix("<h2>").removesuffix("</h2>"))
            short = _short(heading)
            links.append(f'<li><a href="#{anchor}">{escape(short)}</a></li>')
            line = f'<h2 id="{anchor}">{line.removeprefix("<h2>")}'
        lines.append(line)
    if not links:
        return lines
    return [*lines[:after], '<nav class="contents"><h2>Contents</h2><ol>', *links, "</ol></nav>",
            *lines[after:]]


def _short(heading: str, keep: int = 25, most: int = 90) -> str:
    """A heading for the contents: cut at its first " (" or ": " after ``keep`` characters,
    then at a word boundary before ``most`` characters (with "…")."""
    for separator in (" (", ": "):
        position = heading.find(separator, keep)
        if position > 0:
            heading = heading[:position]
    if len(heading) > most:
        heading = heading[:heading.rfind(" ", 0, most)] + " …"
    return heading


def _with_unit(value: float, unit: str) -> str:
    text = format_value(float(value), unit)
    return f"{text} {unit}" if unit and text != "–" else text


def provenance_html(settings: Mapping[str, object], versions: Mapping[str, str],
                     timings: Mapping[str, float]) -> list[str]:
    """Settings, versions and timings: the page's last section."""
    parts = _key_value("Settings", {header_text(k): setting_text(v)
                                    for k, v in settings.items()})
    parts += _key_value("Versions", versions)
    if timings:
        total = sum(float(v) for v in timings.values())
        parts += _key_value("Timings", {k: _with_unit(float(v), "s")
                                        for k, v in timings.items()}
                            | {"total": _with_unit(total, "s")})
    if not parts:
        return []
    return ['<section class="provenance">', "<h2>Run settings, versions and timings</h2>",
            *parts, "</section>"]


def _key_value(heading: str, items: Mapping[str, object]) -> list[str]:
    if not items:
        return []
    rows = "".join(f"<tr><th>{escape(k)}</th><td>{escape(v)}</td></tr>" for k, v in items.items())
    return [f"<h3>{escape(heading)}</h3>", f'<div class="table-wrap"><table>{rows}</table></div>']


def figure_html(path: Path, caption: str, relative: str) -> str:
    """The figure at ``path`` embedded as a base64 PNG (``data-file``: the file beside the
    report, ``relative`` to it)."""
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return (f'<figure><img src="data:image/png;base64,{data}" data-file="{escape(relative)}" '
            f'alt="{escape(caption or relative)}"><figcaption>'
            f"{escape(caption)}</figcaption></figure>")


def table_html(frame: pd.DataFrame, heading: str, csv_name: str, keep_index: bool
               ) -> list[str]:
    """The table (its index a column when ``keep_index``) with readable headers and rounded
    numbers, in parts of ≤ MAX_COLUMNS columns that repeat the leading label columns when it is
    wider; under ``heading``, with a link to its CSV file."""
    frame = frame.reset_index() if keep_index else frame
    columns = list(frame.columns)
    keys = 0
    while (keys < min(MAX_KEY_COLUMNS, len(columns) - 1)
           and _is_text(frame[columns[keys]])):
        keys += 1
    if keys == 0 and keep_index:
        keys = 1
    rest = columns[keys:]
    width = MAX_COLUMNS - keys
    parts = max(1, math.ceil(len(rest) / width))
    size = math.ceil(len(rest) / parts)
    lines = [f"<h2>{escape(heading)}</h2>",
             f'<p class="meta">CSV: <a href="{escape(quote(csv_name))}">{escape(csv_name)}</a>'
             "</p>"]
    for part in range(parts):
        chosen = columns[:keys] + rest[part * size:(part + 1) * size]
        if parts > 1:
            lines.append(f'<p class="meta">part {part + 1} of {parts}</p>')
        lines += _table_part(frame, chosen, keys)
    return lines


_FLOAT_NOISE = re.compile(r"(?<![\w.:-])-?\d+\.\d{6,}(?![\w.])")
"""A decimal number with six or more decimals standing alone in text (e.g. ``0.8116022099447515``
in a provenance list; not part of a time, version or hash)."""


def _tidy_numbers(text: str) -> str:
    """Text with each float written at full precision (:data:`_FLOAT_NOISE`) rounded like a
    cell (:func:`format_value`)."""
    return _FLOAT_NOISE.sub(lambda match: format_value(float(match[0])), text)


def _is_text(column: pd.Series) -> bool:
    """Whether a column holds labels (text), not numbers, flags or times."""
    types = pd.api.types
    return not (types.is_numeric_dtype(column) or types.is_bool_dtype(column)
                or types.is_datetime64_any_dtype(column))


def _table_part(frame: pd.DataFrame, columns: Sequence[object], keys: int) -> list[str]:
    names = [str(c) for c in frame.columns]
    position = {c: names.index(str(c)) for c in columns}
    units = [column_label(c)[1] for c in columns]
    # right-aligned: the cells of number columns (not numbers among text, e.g. item → value)
    numbers = [pd.api.types.is_numeric_dtype(frame[c]) for c in columns]
    row_units = [names.index(ROW_UNIT_COLUMNS[str(c)])
                 if not unit and ROW_UNIT_COLUMNS.get(str(c)) in names else None
                 for c, unit in zip(columns, units, strict=True)]
    lines = ['<div class="table-wrap"><table>', "<thead><tr>" + "".join(
        f"<th>{escape(header_text(c))}</th>" for c in columns) + "</tr></thead>", "<tbody>"]
    for row in frame.itertuples(index=False, name=None):  # each column's own type kept
        cells = []
        for k, column in enumerate(columns):
            value = row[position[column]]
            unit = units[k] if row_units[k] is None else unit_text(row[row_units[k]])
            numeric = numbers[k] and not isinstance(value, bool | np.bool_)
            text = format_value(value, unit)
            if isinstance(value, str):
                text = (header_text(value) if str(column) in LABEL_COLUMNS
                        else _tidy_numbers(value_label(value)))
            tag = "th" if k < keys else "td"
            css = ' class="number"' if numeric and tag == "td" else ""
            cells.append(f"<{tag}{css}>{escape(text)}</{tag}>")
        lines.append("<tr>" + "".join(cells) + "</tr>")
    lines.append("</tbody></table></div>")
    return lines


def json_value(value: object) -> object:
    """JSON-ready copy: numpy scalars to Python, NaN/inf and NaT to null, times to ISO text."""
    if isinstance(value, Mapping):
        return {str(k): json_value(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [json_value(v) for v in value]
    if value is None or value is pd.NaT or value is pd.NA:
        return None
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, pd.Timestamp | dt.datetime):
        return value.isoformat()
    if isinstance(value, str):
        return value
    return str(value)
