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
HTML-escaped. The pieces of the page are made by :mod:`steamtwin.validation.render`.
"""

from __future__ import annotations

import datetime as dt
import json
import platform
import re
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from urllib.parse import quote

import pandas as pd

from steamtwin.errors import SteamtwinError
from steamtwin.validation.render import (
    MAX_COLUMNS,
    STYLE,
    escape,
    figure_html,
    format_value,
    json_value,
    provenance_html,
    summary_html,
    table_html,
    with_contents,
)
from steamtwin.validation.summary import Headline, headline_figures

__all__ = ["MAX_COLUMNS", "FigureSection", "FilesSection", "NotesSection", "ReportError",
           "Section", "TableSection", "ValidationReport", "format_value", "package_versions"]

BASE_PACKAGES = ("steamtwin", "numpy", "scipy", "pandas", "matplotlib")
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
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
        body = [f"<h1>{escape(self.title)}</h1>",
                f'<p class="meta">written {escape(created)} by steamtwin</p>']
        summary = summary_html(headlines)
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
                    "records": [{str(k): json_value(v) for k, v in row.items()}
                                for row in records.to_dict(orient="records")],
                }
                body += table_html(section.frame, section.caption or section.name, csv_name,
                                   keep_index)
            elif isinstance(section, FigureSection):
                relative = figures[id(section)]
                figure_list.append({"file": relative, "caption": section.caption})
                body.append(figure_html(section.path, section.caption, relative))
            elif isinstance(section, FilesSection):
                body.append(f"<h2>{escape(section.heading)}</h2>")
                items = []
                for path, description in section.files:
                    relative = _place_figure(path, directory)
                    file_list.append({"heading": section.heading, "file": relative,
                                      "description": description})
                    items.append(f'<li><a href="{escape(quote(relative))}">{escape(relative)}'
                                 f"</a> — {escape(description)}</li>")
                body.append("<ul>" + "".join(items) + "</ul>")
            else:
                notes.append({"heading": section.heading,
                              "paragraphs": list(section.paragraphs)})
                body.append(f"<h2>{escape(section.heading)}</h2>")
                body += [f"<p>{escape(p)}</p>" for p in section.paragraphs]
        body += provenance_html(self.settings, self.versions, self.timings)
        body = with_contents(body, after=2 + len(summary))  # after the title, meta, summary
        document = {
            "title": self.title, "created_utc": created,
            "headlines": [{"figure": h.figure, "value": json_value(h.value), "unit": h.unit,
                           "limit": h.limit, "published": h.published, "source": h.source,
                           "passed": h.passed} for h in headlines],
            "settings": json_value(self.settings), "versions": dict(self.versions),
            "timings_s": {k: float(v) for k, v in self.timings.items()},
            "tables": tables, "figures": figure_list, "files": file_list, "notes": notes,
        }
        (directory / "report.json").write_text(
            json.dumps(document, indent=2, ensure_ascii=False, allow_nan=False) + "\n",
            encoding="utf-8")
        page = ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                f"<title>{escape(self.title)}</title>\n<style>{STYLE}</style>\n</head>\n"
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
