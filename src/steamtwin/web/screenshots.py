"""Screenshots of the dashboard pages for a report (issue 22, item 4: the demo report shows
every page), taken with the system's Chromium in headless mode — no Python dependency (the
Playwright driver is only in the ``test`` extra).

Each page is one ``chromium --headless=new --screenshot=FILE --dump-dom
--window-size=1366,768 --virtual-time-budget=MS URL`` run (Chromium's command-line switches,
https://developer.chrome.com/docs/chromium/headless): the page loads and runs its scripts for
the budget of virtual time, then Chromium writes the PNG and prints the page's DOM as it is
then. The DOM says whether the page drew: its script sets ``data-ready="yes"`` on the body
when it has drawn the database's answers (``static/*.js``), ``#status`` has the class ``bad``
when a request failed, and every chart carries ``data-points``, the number of finite values
it drew (``static/common.js``; the blade view: the surface's nodes, ``static/blade.js``).

The executable is ``$STEAMTWIN_CHROMIUM``, else ``chromium`` or ``chromium-browser`` on the
PATH; without one, :func:`screenshot_pages` takes none and :func:`dashboard_sections` says
what to install — a missing browser never stops the caller.
"""

from __future__ import annotations

import os
import shutil
import struct
import subprocess
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from html.parser import HTMLParser
from pathlib import Path

from steamtwin.validation.html import FigureSection, NotesSection, Section

__all__ = ["CHROMIUM_ENV", "DASHBOARD_PAGES", "DashboardPage", "PageShot", "dashboard_sections",
           "find_chromium", "missing_browser_message", "page_check", "png_size",
           "screenshot_pages"]

CHROMIUM_ENV = "STEAMTWIN_CHROMIUM"
"""Environment variable naming the Chromium executable (takes precedence over the PATH)."""


@dataclass(frozen=True)
class DashboardPage:
    """A page: its ``name`` (as in the navigation), ``path`` (``{unit}`` is replaced by the
    unit's name) and whether it must draw at least one chart (``charts``)."""

    name: str
    path: str
    charts: bool


DASHBOARD_PAGES = (
    DashboardPage("Unit", "/units/{unit}", True),
    DashboardPage("History", "/units/{unit}/history", True),
    DashboardPage("Alarms", "/units/{unit}/alarms", False),  # a chart only for an alarm
    DashboardPage("Calibration", "/units/{unit}/calibration", True),
    DashboardPage("Blade", "/units/{unit}/blade", True),
    DashboardPage("Fleet", "/", False),
)
"""The dashboard's pages (:mod:`steamtwin.web.pages`), in the navigation's order."""


@dataclass(frozen=True)
class PageShot:
    """One page's screenshot: ``png`` (None when Chromium wrote none), whether the page drew
    its data (``rendered``), what the DOM showed (``detail``) and the run's wall time (s)."""

    page: DashboardPage
    url: str
    png: Path | None
    rendered: bool
    detail: str
    seconds: float


def find_chromium() -> Path | None:
    """The Chromium executable: ``$STEAMTWIN_CHROMIUM`` if set (None when it is not a file),
    else ``chromium`` or ``chromium-browser`` on the PATH; None when there is none."""
    named = os.environ.get(CHROMIUM_ENV)
    if named:
        return Path(named) if Path(named).is_file() else None
    for name in ("chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return Path(found)
    return None


def missing_browser_message() -> str:
    """What to install (or set) when :func:`find_chromium` finds no browser."""
    named = os.environ.get(CHROMIUM_ENV)
    where = (f"${CHROMIUM_ENV} = {named!r} is not a file" if named
             else "no chromium or chromium-browser on the PATH")
    return (f"Dashboard screenshots were not taken: {where}. Install Debian's chromium "
            f"(apt-get install chromium; tools/install-system-deps.sh does it) or set "
            f"{CHROMIUM_ENV} to a Chromium executable, then run the demo again.")


def png_size(path: str | Path) -> tuple[int, int]:
    """Width and height (px) of the PNG at ``path``, from its IHDR chunk (PNG specification,
    ISO/IEC 15948:2004, §11.2.2: the first chunk, width and height as 4-byte big-endian)."""
    head = Path(path).read_bytes()[:24]
    if len(head) < 24 or head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        raise ValueError(f"{path}: not a PNG file (no PNG signature and IHDR chunk)")
    width, height = struct.unpack(">II", head[16:24])
    return width, height


class _PageDom(HTMLParser):
    """What the check needs from a dumped DOM: the body's data attributes, the status line
    (class and text) and each chart's ``data-points``."""

    def __init__(self) -> None:
        super().__init__()
        self.body: dict[str, str] = {}
        self.status_bad = False
        self.status_text = ""
        self.charts: list[tuple[str, int]] = []
        self._in_status = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        found = {name: value or "" for name, value in attrs}
        if tag == "body":
            self.body = found
        if found.get("id") == "status":
            self._in_status = True
            self.status_bad = "bad" in found.get("class", "").split()
        if "data-points" in found:
            name = found.get("id") or found.get("data-signal") or tag
            points = found["data-points"]
            self.charts.append((name, int(points) if points.isdigit() else 0))

    def handle_endtag(self, tag: str) -> None:
        if tag == "span":
            self._in_status = False

    def handle_data(self, data: str) -> None:
        if self._in_status:
            self.status_text += data


def page_check(dom: str, page: DashboardPage) -> tuple[bool, str]:
    """Whether the dumped ``dom`` of ``page`` shows it drawn with data, and what it showed:
    the body's ``data-ready`` is "yes", the status line is not an error, every chart drew
    at least one value and (``page.charts``) there is a chart."""
    parsed = _PageDom()
    parsed.feed(dom)
    ready = parsed.body.get("data-ready", "")
    charts = ", ".join(f"{name}: {n} points" for name, n in parsed.charts) or "no chart"
    if parsed.status_bad:
        return False, f"error on the page: {parsed.status_text.strip()}; {charts}"
    if ready != "yes":
        why = {"": "its script did not finish drawing within the time budget",
               "no-rom": "the unit has no blade ROM"}.get(ready, f"data-ready = {ready!r}")
        return False, f"not drawn ({why}); {charts}"
    if page.charts and not parsed.charts:
        return False, "drawn without a chart"
    empty = [name for name, n in parsed.charts if n == 0]
    if empty:
        return False, f"chart(s) without data: {', '.join(empty)}; {charts}"
    if page.path == "/" and parsed.body.get("data-unit"):
        charts = f"one unit: forwarded to its Unit page; {charts}"
    return True, charts


def _chromium_command(chromium: Path, profile: str, png: Path, url: str,
                      size: tuple[int, int], budget_ms: int) -> list[str]:
    command = [str(chromium), "--headless=new", f"--user-data-dir={profile}",
               "--disable-gpu", "--hide-scrollbars", "--mute-audio", "--no-first-run",
               "--disable-background-networking", "--disable-component-update",
               "--disable-sync", "--dump-dom", f"--screenshot={png}",
               f"--window-size={size[0]},{size[1]}", f"--virtual-time-budget={budget_ms}"]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        command.append("--no-sandbox")  # Chromium refuses to start as root with its sandbox
    return [*command, url]


def screenshot_pages(base_url: str, unit: str, folder: str | Path,
                     pages: Sequence[DashboardPage] = DASHBOARD_PAGES, *,
                     chromium: str | Path | None = None, size: tuple[int, int] = (1366, 768),
                     budget_ms: int = 15_000, timeout_s: float = 60.0) -> list[PageShot]:
    """A screenshot of each of ``pages`` of the service at ``base_url`` (e.g.
    ``http://127.0.0.1:8080``) for ``unit``, written as ``folder/dashboard-<name>.png`` at
    ``size`` (px), and whether each page drew its data (:func:`page_check`).

    ``chromium``: the executable (default :func:`find_chromium`); none found → ``[]``.
    ``budget_ms``: the virtual time each page is given to load and draw (ms); ``timeout_s``:
    the wall-clock limit of one Chromium run (s). Blocking: call it from a thread
    (``asyncio.to_thread``) when the service runs in the caller's event loop. A page whose
    run fails or times out is reported (``rendered`` False), never raised.
    """
    executable = Path(chromium) if chromium is not None else find_chromium()
    if executable is None:
        return []
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    shots = []
    with tempfile.TemporaryDirectory(prefix="steamtwin-chromium-") as profile:
        for page in pages:
            url = base_url.rstrip("/") + page.path.format(unit=unit)
            png = folder / f"dashboard-{page.name.lower()}.png"
            png.unlink(missing_ok=True)
            start = time.perf_counter()
            try:
                done = subprocess.run(
                    _chromium_command(executable, profile, png, url, size, budget_ms),
                    capture_output=True, text=True, timeout=timeout_s, check=False)
            except subprocess.TimeoutExpired:
                rendered, detail = False, f"Chromium did not finish within {timeout_s:g} s"
            except OSError as error:
                rendered, detail = False, f"Chromium ({executable}) did not start: {error}"
            else:
                rendered, detail = page_check(done.stdout, page)
                if done.returncode != 0:
                    rendered = False
                    detail = f"Chromium exited with {done.returncode}; {detail}"
            shots.append(PageShot(page, url, png if png.is_file() else None, rendered,
                                  detail, time.perf_counter() - start))
    return shots


def dashboard_sections(shots: Sequence[PageShot], note: str = "") -> list[Section]:
    """The report's dashboard section: a heading paragraph (``note`` first, then which
    pages did not draw) and each screenshot as a figure; with no ``shots`` (no browser),
    the paragraph saying what to install."""
    if not shots:
        return [NotesSection("Dashboard screenshots", (missing_browser_message(),))]
    failed = [f"{shot.page.name} ({shot.url}): {shot.detail}" for shot in shots
              if not shot.rendered]
    paragraphs = [note] if note else []
    seconds = sum(shot.seconds for shot in shots)
    paragraphs.append(
        f"{len(shots) - len(failed)} of {len(shots)} pages drew the database's values "
        f"(headless Chromium, {seconds:.1f} s in all)"
        + (". Did not render: " + "; ".join(failed) if failed else "."))
    sections: list[Section] = [NotesSection("Dashboard screenshots", tuple(paragraphs))]
    for shot in shots:
        if shot.png is not None:
            state = "" if shot.rendered else " — did not render"
            sections.append(FigureSection(shot.png, f"Dashboard, {shot.page.name} page "
                                                    f"({shot.url}){state}: {shot.detail}"))
    return sections
