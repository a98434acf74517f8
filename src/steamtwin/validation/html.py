"""A small HTML report writer (standard library only): tables, figures, notes, provenance.

:class:`ValidationReport` collects, in order, sections of four kinds — tables (a DataFrame,
shown as an HTML table and written as ``<name>.csv`` next to the report), figures (PNG files,
referenced by relative path and copied into the report folder when they lie elsewhere), data
files (e.g. Parquet series, listed with links, placed like figures) and notes (paragraphs of
text) — plus the run's settings, package versions and timings (stage →
seconds). :meth:`ValidationReport.write` writes ``report.html`` and ``report.json`` (the same
content machine-readable: settings, versions, timings, tables as records at full precision,
figures, data files and notes). Every text is HTML-escaped; numbers are shown with four significant
digits in the HTML (the CSV and JSON files keep full precision).
"""

from __future__ import annotations

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

__all__ = ["FigureSection", "FilesSection", "NotesSection", "ReportError", "Section",
           "TableSection", "ValidationReport", "format_value", "package_versions"]

BASE_PACKAGES = ("steamtwin", "numpy", "scipy", "pandas", "matplotlib")
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
_STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em; color: #222; max-width: 1400px; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; margin-top: 1.6em; }
table { border-collapse: collapse; margin: 0.5em 0 1em; font-size: 0.85em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.5em; }
td.number { text-align: right; font-variant-numeric: tabular-nums; }
th { background: #f0f0f0; } caption { caption-side: top; text-align: left; font-weight: bold; }
figure { margin: 1em 0; } img { max-width: 100%; } figcaption { font-size: 0.9em; }
p.meta { color: #666; font-size: 0.85em; }
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


def format_value(value: object) -> str:
    """Text of a table cell: integers as they are, floats with 4 significant digits (fixed
    notation within 1e-3 … 1e6, scientific outside), NaN/None as "–", times in ISO 8601."""
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
        if 1e-3 <= magnitude < 1e6:
            decimals = min(max(3 - math.floor(math.log10(magnitude)), 0), 6)
            return f"{number:.{decimals}f}"
        return f"{number:.3e}"
    if isinstance(value, pd.Timestamp | dt.datetime):
        return value.isoformat()
    return str(value)


@dataclass
class ValidationReport:
    """Sections of a validation report in the order added; :meth:`write` makes the files.

    ``settings`` (name → value), ``versions`` (package → version; Python, steamtwin, numpy,
    scipy, pandas and matplotlib by default) and ``timings`` (stage → seconds) head the report.
    """

    title: str
    settings: dict[str, object] = field(default_factory=dict)
    versions: dict[str, str] = field(default_factory=package_versions)
    timings: dict[str, float] = field(default_factory=dict)
    sections: list[Section] = field(default_factory=list)

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
        body = [f"<h1>{_text(self.title)}</h1>",
                f'<p class="meta">written {_text(created)} by steamtwin</p>']
        body += _key_value("Settings", {k: _setting_text(v) for k, v in self.settings.items()})
        body += _key_value("Versions", self.versions)
        body += _key_value("Timings", {k: f"{format_value(float(v))} s"
                                       for k, v in self.timings.items()})
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
                body.append(f'<figure><img src="{_text(quote(relative))}" alt="'
                            f'{_text(section.caption or relative)}"><figcaption>'
                            f"{_text(section.caption)}</figcaption></figure>")
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
        document = {
            "title": self.title, "created_utc": created,
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
    if isinstance(value, Mapping):
        return json.dumps(_json_value(value), ensure_ascii=False)
    if isinstance(value, list | tuple):
        return ", ".join(format_value(v) for v in value)
    return format_value(value)


def _key_value(heading: str, items: Mapping[str, object]) -> list[str]:
    if not items:
        return []
    rows = "".join(f"<tr><th>{_text(k)}</th><td>{_text(v)}</td></tr>" for k, v in items.items())
    return [f"<h2>{_text(heading)}</h2>", f"<table>{rows}</table>"]


def _table_html(section: TableSection, csv_name: str, keep_index: bool) -> list[str]:
    frame = section.frame
    header = [str(frame.index.name or "")] if keep_index else []
    header += [str(c) for c in frame.columns]
    lines = [f"<h2>{_text(section.caption or section.name)}</h2>",
             f'<p class="meta">CSV: <a href="{_text(quote(csv_name))}">{_text(csv_name)}</a>'
             "</p>", "<table>",
             "<tr>" + "".join(f"<th>{_text(h)}</th>" for h in header) + "</tr>"]
    for label, row in zip(frame.index, frame.itertuples(index=False, name=None), strict=True):
        cells = [f"<th>{_text(format_value(label))}</th>"] if keep_index else []
        for value in row:
            numeric = isinstance(value, int | float | np.integer | np.floating) and not isinstance(
                value, bool | np.bool_)
            css = ' class="number"' if numeric else ""
            cells.append(f"<td{css}>{_text(format_value(value))}</td>")
        lines.append("<tr>" + "".join(cells) + "</tr>")
    lines.append("</table>")
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
