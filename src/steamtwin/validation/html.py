"""A small HTML report writer (standard library only): summary, tables, figures, notes, provenance.

:class:`ValidationReport` collects, in order, sections of four kinds — tables (a DataFrame,
shown as an HTML table and written as ``<name>.csv`` next to the report), figures (PNG files,
embedded in the page and also placed in the report folder, copied in when they lie elsewhere),
data files (e.g. Parquet series, listed with links, placed like figures) and notes (paragraphs of
text) — plus the run's headline figures, settings, package versions and timings (stage →
seconds). :meth:`ValidationReport.write` writes ``report.html`` and ``report.json`` (the same
content machine-readable: headlines, settings, versions, timings, tables as records at full
precision, figures, data files and notes).

The page reads top down: a one-screen summary (each headline figure beside its limit and the
method's published value, pass/fail marked; :mod:`steamtwin.validation.summary`), the sections
in order, then the settings, versions and timings. Column names are shown as "Readable name
[unit]" and numbers rounded by quantity (:mod:`steamtwin.validation.labels`: 3 significant
figures, never finer than the unit's resolution; the CSV and JSON files keep full precision).
Tables fit a 1366-px screen: at most :data:`MAX_COLUMNS` columns each (a wider table is shown in
parts that repeat its key columns), cells wrap between words (a word longer than its column
breaks; a table still too wide scrolls inside its own box, never the page). The page is
self-contained: CSS inline, figures as base64 PNG, no script, no external URL. Every text is
HTML-escaped.
"""

from __future__ import annotations

import base64
import datetime as dt
import html
import json
import math
import platform
import re
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from urllib.parse import quote

import numpy as np
import pandas as pd

from steamtwin.errors import SteamtwinError
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
from steamtwin.validation.summary import Headline, headline_figures

__all__ = ["MAX_COLUMNS", "FigureSection", "FilesSection", "NotesSection", "ReportError",
           "Section", "TableSection", "ValidationReport", "format_value", "package_versions"]

BASE_PACKAGES = ("steamtwin", "numpy", "scipy", "pandas", "matplotlib")
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
MAX_COLUMNS = 10
"""Most columns of one HTML table: at 0.85 em (13.6 px) a column takes ≤ 120 px when its header
wraps at word boundaries, so 10 fit the 1302 px a 1366-px screen leaves inside the margins."""
MAX_KEY_COLUMNS = 3
"""Most leading label columns (index, text, times) repeated in each part of a split table."""
_STYLE = """
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

class ReportError(SteamtwinError, ValueError):
    """A report cannot be written: a section is empty, missing or named twice."""


@dataclass(frozen=True)
class TableSection:
    """A table: ``name`` is its CSV file stem (letters, digits, ``_ . -``)."""

    name: str
    frame: pd.DataFrame
    caption: str = ""


@dataclass(frozen=True)
class FigureSection:
    """A figure file (PNG) with its caption."""

    path: Path
    caption: str = ""


@dataclass(frozen=True)
class NotesSection:
    """A heading with paragraphs of free text."""

    heading: str
    paragraphs: tuple[str, ...]


@dataclass(frozen=True)
class FilesSection:
    """Data files beside the report (e.g. per-sample series), each with a description."""

    heading: str
    files: tuple[tuple[Path, str], ...]


Section = TableSection | FigureSection | NotesSection | FilesSection


def package_versions(extra: Mapping[str, str] | None = None) -> dict[str, str]:
    """Versions of Python, steamtwin, numpy, scipy, pandas, matplotlib, then ``extra``."""
    versions = {"python": platform.python_version()}
    for name in BASE_PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions | dict(extra or {})


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


@dataclass
class ValidationReport:
    """Sections of a validation report in the order added; :meth:`write` makes the files.

    ``headlines`` (:class:`~steamtwin.validation.summary.Headline`) open the report as its
    summary; None (the default): those :func:`~steamtwin.validation.summary.headline_figures`
    finds in the report's tables when it is written. ``settings`` (name → value), ``versions``
    (package → version; Python, steamtwin, numpy, scipy, pandas and matplotlib by default) and
    ``timings`` (stage → seconds) close it.
    """

    title: str
    settings: dict[str, object] = field(default_factory=dict)
    versions: dict[str, str] = field(default_factory=package_versions)
    timings: dict[str, float] = field(default_factory=dict)
    sections: list[Section] = field(default_factory=list)
    headlines: list[Headline] | None = None

    def add(self, section: Section) -> Section:
        """Append a section; table names and figure file names must be unique."""
        if isinstance(section, TableSection):
            if not _NAME.match(section.name):
                raise ReportError(f"table name {section.name!r}: use letters, digits, '_', '.' "
                                  "or '-' (it becomes the CSV file name)")
            if section.name in self.tables:
                raise ReportError(f"a table named {section.name!r} is already in the report")
        elif isinstance(section, FigureSection):
            taken = [s.path.name for s in self.sections if isinstance(s, FigureSection)]
            if section.path.name in taken:
                raise ReportError(f"a figure file named {section.path.name!r} is already in "
                                  "the report")
        elif isinstance(section, FilesSection):
            taken = {path.name for s in self.sections if isinstance(s, FilesSection)
                     for path, _ in s.files}
            names = [Path(path).name for path, _ in section.files]
            if taken & set(names) or len(set(names)) < len(names):
                raise ReportError(f"a data file named like one of {names} is already in the "
                                  "report")
        elif not isinstance(section, NotesSection):
            raise TypeError(f"not a report section: {section!r}")
        self.sections.append(section)
        return section

    def add_table(self, name: str, frame: pd.DataFrame, caption: str = "") -> TableSection:
        """Append a table, written as ``<name>.csv`` and shown in the HTML."""
        section = TableSection(name, frame, caption)
        self.add(section)
        return section

    def add_figure(self, path: str | Path, caption: str = "") -> FigureSection:
        """Append a figure file (PNG)."""
        section = FigureSection(Path(path), caption)
        self.add(section)
        return section

    def add_files(self, heading: str, files: Sequence[tuple[str | Path, str]]
                  ) -> FilesSection:
        """Append a list of data files (path, description), linked from the HTML."""
        section = FilesSection(heading, tuple((Path(p), text) for p, text in files))
        self.add(section)
        return section

    def add_notes(self, heading: str, paragraphs: Sequence[str]) -> NotesSection:
        """Append a heading with paragraphs of text."""
        section = NotesSection(heading, tuple(paragraphs))
        self.add(section)
        return section

    @property
    def tables(self) -> dict[str, pd.DataFrame]:
        """The tables by name, in order."""
        return {s.name: s.frame for s in self.sections if isinstance(s, TableSection)}

    def write(self, directory: str | Path) -> Path:
        """Write ``report.html``, ``report.json``, one CSV per table and copies of figures
        lying outside ``directory``; returns the HTML path.

        Raises :class:`ReportError` (before writing anything) for an empty table or a figure
        file that is missing or empty.
        """
        directory = Path(directory)
        self._check()
        directory.mkdir(parents=True, exist_ok=True)
        created = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
        figures = {id(s): _place_figure(s.path, directory) for s in self.sections
                   if isinstance(s, FigureSection)}
        tables: dict[str, object] = {}
        figure_list: list[dict[str, str]] = []
        file_list: list[dict[str, str]] = []
        notes: list[dict[str, object]] = []
        headlines = (headline_figures(self.tables) if self.headlines is None
                     else list(self.headlines))
        body = [f"<h1>{_text(self.title)}</h1>",
                f'<p class="meta">written {_text(created)} by steamtwin</p>']
        summary = _summary_html(headlines)
        body += summary
        for section in self.sections:
            if isinstance(section, TableSection):
                csv_name = f"{section.name}.csv"
                keep_index = _has_index(section.frame)
                section.frame.to_csv(directory / csv_name, index=keep_index)
                records = section.frame.reset_index() if keep_index else section.frame
                tables[section.name] = {
                    "caption": section.caption, "csv": csv_name,
                    "columns": [str(c) for c in records.columns],
                    "records": [{str(k): _json_value(v) for k, v in row.items()}
                                for row in records.to_dict(orient="records")],
                }
                body += _table_html(section, csv_name, keep_index)
            elif isinstance(section, FigureSection):
                relative = figures[id(section)]
                figure_list.append({"file": relative, "caption": section.caption})
                body.append(_figure_html(section, relative))
            elif isinstance(section, FilesSection):
                body.append(f"<h2>{_text(section.heading)}</h2>")
                items = []
                for path, description in section.files:
                    relative = _place_figure(path, directory)
                    file_list.append({"heading": section.heading, "file": relative,
                                      "description": description})
                    items.append(f'<li><a href="{_text(quote(relative))}">{_text(relative)}'
                                 f"</a> — {_text(description)}</li>")
                body.append("<ul>" + "".join(items) + "</ul>")
            else:
                notes.append({"heading": section.heading,
                              "paragraphs": list(section.paragraphs)})
                body.append(f"<h2>{_text(section.heading)}</h2>")
                body += [f"<p>{_text(p)}</p>" for p in section.paragraphs]
        body += _provenance_html(self.settings, self.versions, self.timings)
        body = _with_contents(body, after=2 + len(summary))  # after the title, meta, summary
        document = {
            "title": self.title, "created_utc": created,
            "headlines": [{"figure": h.figure, "value": _json_value(h.value), "unit": h.unit,
                           "limit": h.limit, "published": h.published, "source": h.source,
                           "passed": h.passed} for h in headlines],
            "settings": _json_value(self.settings), "versions": dict(self.versions),
            "timings_s": {k: float(v) for k, v in self.timings.items()},
            "tables": tables, "figures": figure_list, "files": file_list, "notes": notes,
        }
        (directory / "report.json").write_text(
            json.dumps(document, indent=2, ensure_ascii=False, allow_nan=False) + "\n",
            encoding="utf-8")
        page = ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                f"<title>{_text(self.title)}</title>\n<style>{_STYLE}</style>\n</head>\n"
                "<body>\n" + "\n".join(body) + "\n</body>\n</html>\n")
        path = directory / "report.html"
        path.write_text(page, encoding="utf-8")
        return path

    def _check(self) -> None:
        for section in self.sections:
            if isinstance(section, TableSection):
                if section.frame.empty:
                    raise ReportError(f"table {section.name!r} is empty")
            elif isinstance(section, FigureSection):
                if not section.path.is_file():
                    raise ReportError(f"figure file {section.path} does not exist")
                if section.path.stat().st_size == 0:
                    raise ReportError(f"figure file {section.path} is empty")
            elif isinstance(section, FilesSection):
                for path, _ in section.files:
                    if not path.is_file():
                        raise ReportError(f"data file {path} does not exist")


def _place_figure(path: Path, directory: Path) -> str:
    """A figure's (or data file's) path relative to ``directory`` (as URL-style text), copied
    in if outside."""
    try:
        return path.resolve().relative_to(directory.resolve()).as_posix()
    except ValueError:
        target = directory / path.name
        shutil.copy2(path, target)
        return path.name


def _has_index(frame: pd.DataFrame) -> bool:
    """Whether the index carries information (anything but an unnamed 0…n−1 range)."""
    index = frame.index
    return not (isinstance(index, pd.RangeIndex) and index.name is None and index.start == 0
                and index.step == 1)


def _text(value: object) -> str:
    return html.escape(str(value), quote=True)


def _setting_text(value: object) -> str:
    """A setting as given (floats to 6 significant figures: what the user chose, not a
    measured figure)."""
    if isinstance(value, Mapping):
        return json.dumps(_json_value(value), ensure_ascii=False)
    if isinstance(value, list | tuple):
        return ", ".join(_setting_text(v) for v in value)
    if isinstance(value, float | np.floating):
        return f"{float(value):g}"
    return format_value(value)


def _summary_html(headlines: Sequence[Headline]) -> list[str]:
    """The summary: each headline figure beside its limit and the published value, marked."""
    if not headlines:
        return []
    passed = sum(h.passed for h in headlines)
    rows = []
    for h in headlines:
        status = ("✓ within" if h.passed else "✗ outside" if math.isfinite(h.value)
                  else "✗ no value")
        rows.append(f'<tr class="{"pass" if h.passed else "fail"}"><td>{_text(h.figure)}</td>'
                    f'<td class="number">{_text(_with_unit(h.value, h.unit))}</td>'
                    f'<td class="number">≤ {_text(f"{h.limit:g} {h.unit}")}</td>'
                    f"<td>{_text(h.published)}</td><td>{_text(h.source)}</td>"
                    f'<td class="status">{status}</td></tr>')
    return ['<section class="summary">', "<h2>Summary</h2>",
            f'<p class="verdict">{passed} of {len(headlines)} headline figures within their '
            "limits</p>", '<div class="table-wrap"><table class="headlines">',
            "<thead><tr><th>Figure</th><th>This run</th><th>Limit</th>"
            "<th>The method (published)</th><th>Limit from</th><th>Result</th></tr></thead>",
            "<tbody>" + "".join(rows) + "</tbody></table></div>", "</section>"]


def _with_contents(body: list[str], after: int) -> list[str]:
    """``body`` with an id on every section heading and, after its first ``after`` lines (title
    and summary), a list of links to them (each heading cut at its first parenthesis)."""
    lines, links = [], []
    for line in body:
        if line.startswith("<h2>") and line != "<h2>Summary</h2>":
            anchor = f"section-{len(links) + 1}"
            heading = html.unescape(line.removeprefix("<h2>").removesuffix("</h2>"))
            short = heading.split(" (")[0]
            links.append(f'<li><a href="#{anchor}">{_text(short)}</a></li>')
            line = f'<h2 id="{anchor}">{line.removeprefix("<h2>")}'
        lines.append(line)
    if not links:
        return lines
    return [*lines[:after], '<nav class="contents"><h2>Contents</h2><ol>', *links, "</ol></nav>",
            *lines[after:]]


def _with_unit(value: float, unit: str) -> str:
    text = format_value(float(value), unit)
    return f"{text} {unit}" if unit and text != "–" else text


def _provenance_html(settings: Mapping[str, object], versions: Mapping[str, str],
                     timings: Mapping[str, float]) -> list[str]:
    """Settings, versions and timings: the page's last section."""
    parts = _key_value("Settings", {header_text(k): _setting_text(v)
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
    rows = "".join(f"<tr><th>{_text(k)}</th><td>{_text(v)}</td></tr>" for k, v in items.items())
    return [f"<h3>{_text(heading)}</h3>", f'<div class="table-wrap"><table>{rows}</table></div>']


def _figure_html(section: FigureSection, relative: str) -> str:
    """The figure embedded as a base64 PNG (``data-file``: the file beside the report)."""
    data = base64.b64encode(section.path.read_bytes()).decode("ascii")
    return (f'<figure><img src="data:image/png;base64,{data}" data-file="{_text(relative)}" '
            f'alt="{_text(section.caption or relative)}"><figcaption>'
            f"{_text(section.caption)}</figcaption></figure>")


def _table_html(section: TableSection, csv_name: str, keep_index: bool) -> list[str]:
    """The table with readable headers and rounded numbers, in parts of ≤ MAX_COLUMNS columns
    that repeat the leading label columns when it is wider."""
    frame = section.frame.reset_index() if keep_index else section.frame
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
    lines = [f"<h2>{_text(section.caption or section.name)}</h2>",
             f'<p class="meta">CSV: <a href="{_text(quote(csv_name))}">{_text(csv_name)}</a>'
             "</p>"]
    for part in range(parts):
        chosen = columns[:keys] + rest[part * size:(part + 1) * size]
        if parts > 1:
            lines.append(f'<p class="meta">part {part + 1} of {parts}</p>')
        lines += _table_part(frame, chosen, keys)
    return lines


def _is_text(column: pd.Series) -> bool:
    """Whether a column holds labels (text), not numbers, flags or times."""
    types = pd.api.types
    return not (types.is_numeric_dtype(column) or types.is_bool_dtype(column)
                or types.is_datetime64_any_dtype(column))


def _table_part(frame: pd.DataFrame, columns: Sequence[object], keys: int) -> list[str]:
    names = [str(c) for c in frame.columns]
    position = {c: names.index(str(c)) for c in columns}
    units = [column_label(c)[1] for c in columns]
    row_units = [names.index(ROW_UNIT_COLUMNS[str(c)])
                 if not unit and ROW_UNIT_COLUMNS.get(str(c)) in names else None
                 for c, unit in zip(columns, units, strict=True)]
    lines = ['<div class="table-wrap"><table>', "<thead><tr>" + "".join(
        f"<th>{_text(header_text(c))}</th>" for c in columns) + "</tr></thead>", "<tbody>"]
    for row in frame.itertuples(index=False, name=None):  # each column's own type kept
        cells = []
        for k, column in enumerate(columns):
            value = row[position[column]]
            unit = units[k] if row_units[k] is None else unit_text(row[row_units[k]])
            numeric = isinstance(value, int | float | np.integer | np.floating) and not isinstance(
                value, bool | np.bool_)
            text = format_value(value, unit)
            if isinstance(value, str):
                text = header_text(value) if str(column) in LABEL_COLUMNS else value_label(value)
            tag = "th" if k < keys else "td"
            css = ' class="number"' if numeric and tag == "td" else ""
            cells.append(f"<{tag}{css}>{_text(text)}</{tag}>")
        lines.append("<tr>" + "".join(cells) + "</tr>")
    lines.append("</tbody></table></div>")
    return lines


def _json_value(value: object) -> object:
    """JSON-ready copy: numpy scalars to Python, NaN/inf and NaT to null, times to ISO text."""
    if isinstance(value, Mapping):
        return {str(k): _json_value(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [_json_value(v) for v in value]
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
