"""Screenshots of the dashboard pages for a report (issue 22, item 4: the demo report shows
every page), taken with the system's Chromium in headless mode — no Python dependency (the
Playwright driver is only in the ``test`` extra).

One ``chromium --headless=new --remote-debugging-pipe`` is driven over the DevTools protocol
(https://chromedevtools.github.io/devtools-protocol/: JSON commands on the browser's fd 3,
answers on its fd 4, each ended by a NUL byte): for each page, ``Page.navigate``, wait until
the page is drawn, read its DOM (``Runtime.evaluate``) and ``Page.captureScreenshot`` at the
viewport's size (``Emulation.setDeviceMetricsOverride``). One browser for all the pages: a
Chromium start per page (``--screenshot``) took about twice as long in all.

The DOM says whether the page drew: its script sets ``data-ready="yes"`` on the body when it
has drawn the database's answers (``static/*.js``), ``#status`` has the class ``bad`` when a
request failed, and every chart carries ``data-points``, the number of finite values it drew
(``static/common.js``; the blade view: the surface's nodes, ``static/blade.js``).

The executable is ``$STEAMTWIN_CHROMIUM``, else ``chromium`` or ``chromium-browser`` on the
PATH; without one, :func:`screenshot_pages` takes none and :func:`dashboard_sections` says
what to install — a missing browser never stops the caller.
"""

from __future__ import annotations

import base64
import contextlib
import fcntl
import json
import os
import select
import shutil
import signal
import struct
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from html.parser import HTMLParser
from pathlib import Path

from steamtwin.errors import SteamtwinError
from steamtwin.validation.html import FigureSection, NotesSection, Section

__all__ = ["CHROMIUM_ENV", "DASHBOARD_PAGES", "BrowserError", "DashboardPage", "PageShot",
           "dashboard_sections", "find_chromium", "missing_browser_message", "page_check",
           "png_size", "screenshot_pages"]

CHROMIUM_ENV = "STEAMTWIN_CHROMIUM"
"""Environment variable naming the Chromium executable (takes precedence over the PATH)."""


class BrowserError(SteamtwinError, RuntimeError):
    """Chromium did not start, answer or draw as asked (says which command)."""


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
    DashboardPage("Rotor", "/units/{unit}/rotor", True),
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
    """What the check needs from a page's DOM: the body's data attributes, the status line
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
    """Whether the DOM ``dom`` of ``page`` shows it drawn with data, and what it showed:
    the body's ``data-ready`` is "yes", the status line is not an error, every chart drew
    at least one value and (``page.charts``) there is a chart."""
    parsed = _PageDom()
    parsed.feed(dom)
    ready = parsed.body.get("data-ready", "")
    charts = ", ".join(f"{name}: {n} points" for name, n in parsed.charts) or "no chart"
    if parsed.status_bad:
        return False, f"error on the page: {parsed.status_text.strip()}; {charts}"
    if ready != "yes":
        why = {"": "its script did not finish drawing in the time given",
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


class _DevTools:
    """One headless Chromium driven over the DevTools protocol on a pipe
    (``--remote-debugging-pipe``: the browser reads commands from its fd 3 and writes answers
    and events to its fd 4, each a JSON message ended by a NUL byte;
    https://chromedevtools.github.io/devtools-protocol/), with one page :attr:`session` of
    ``size`` (px). Raises :class:`BrowserError` when the browser does not start or answer."""

    def __init__(self, executable: Path, profile: str, size: tuple[int, int],
                 timeout_s: float) -> None:
        self.timeout_s = timeout_s
        self.buffer = b""
        self.last_id = 0
        to_browser, self.commands = os.pipe()
        self.answers, from_browser = os.pipe()
        # the child's ends above fd 4, so that duplicating them onto 3 and 4 cannot clobber
        # one another (posix_spawn's dup2 clears close-on-exec on the target)
        child = [fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 5) for fd in (to_browser, from_browser)]
        for fd in (to_browser, from_browser):
            os.close(fd)
        arguments = [str(executable), "--headless=new", "--remote-debugging-pipe",
                     f"--user-data-dir={profile}", "--disable-gpu", "--hide-scrollbars",
                     "--mute-audio", "--no-first-run", "--disable-background-networking",
                     "--disable-component-update", "--disable-sync",
                     f"--window-size={size[0]},{size[1]}"]
        if os.geteuid() == 0:
            arguments.append("--no-sandbox")  # Chromium refuses to start as root with it
        try:
            # in a session of its own: nothing Chromium signals to its process group can
            # reach the caller's
            self.pid = os.posix_spawn(str(executable), [*arguments, "about:blank"], os.environ,
                                      setsid=True, file_actions=[
                                          (os.POSIX_SPAWN_OPEN, 1, os.devnull, os.O_WRONLY, 0),
                                          (os.POSIX_SPAWN_OPEN, 2, os.devnull, os.O_WRONLY, 0),
                                          (os.POSIX_SPAWN_DUP2, child[0], 3),
                                          (os.POSIX_SPAWN_DUP2, child[1], 4)])
        except OSError as error:
            self._close_pipes()
            raise BrowserError(f"{executable} did not start: {error}") from None
        finally:
            for fd in child:
                os.close(fd)
        try:
            target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
            self.session = self.call("Target.attachToTarget",
                                     {"targetId": target, "flatten": True})["sessionId"]
            self.call("Emulation.setDeviceMetricsOverride", {
                "width": size[0], "height": size[1], "deviceScaleFactor": 1, "mobile": False},
                self.session)
        except BrowserError:
            self.close()
            raise

    def call(self, method: str, params: dict | None = None, session: str | None = None
             ) -> dict:
        """Send a command and return its result (BrowserError on an error answer, a closed
        pipe or no answer within the time-out)."""
        self.last_id += 1
        message = {"id": self.last_id, "method": method, "params": params or {}}
        if session is not None:
            message["sessionId"] = session
        try:
            os.write(self.commands, json.dumps(message).encode() + b"\0")
        except OSError as error:
            raise BrowserError(f"Chromium closed its DevTools pipe ({error})") from None
        deadline = time.monotonic() + self.timeout_s
        while True:
            while b"\0" not in self.buffer:
                remaining = deadline - time.monotonic()
                if remaining <= 0 or not select.select([self.answers], [], [], remaining)[0]:
                    raise BrowserError(f"Chromium did not answer {method} within "
                                       f"{self.timeout_s:g} s")
                chunk = os.read(self.answers, 1 << 20)
                if not chunk:
                    raise BrowserError("Chromium closed its DevTools pipe")
                self.buffer += chunk
            raw, self.buffer = self.buffer.split(b"\0", 1)
            answer = json.loads(raw)
            if answer.get("id") == self.last_id:  # anything else is an event
                if "error" in answer:
                    raise BrowserError(f"{method}: {answer['error'].get('message')}")
                return answer["result"]

    def evaluate(self, expression: str) -> object:
        """The value of a JavaScript expression in the page."""
        result = self.call("Runtime.evaluate", {"expression": expression,
                                                "returnByValue": True}, self.session)
        return result["result"].get("value")

    def close(self) -> None:
        """Close the browser (killed if it does not exit within the time-out)."""
        with contextlib.suppress(BrowserError):
            self.call("Browser.close")
        deadline = time.monotonic() + self.timeout_s
        while os.waitpid(self.pid, os.WNOHANG) == (0, 0):
            if time.monotonic() > deadline:
                os.kill(self.pid, signal.SIGKILL)
                os.waitpid(self.pid, 0)
                break
            time.sleep(0.05)
        self._close_pipes()

    def _close_pipes(self) -> None:
        for fd in (self.commands, self.answers):
            with contextlib.suppress(OSError):
                os.close(fd)


STATE = ("!window.steamtwinLeft && document.body ? (document.body.dataset.ready || "
         "(document.querySelector('#status.bad') ? 'error' : '')) : ''")
"""What the page shows so far: its ``data-ready``, "error" for an error in its status line,
or "" while it (or the page left before it) is loading."""


def _shoot(browser: _DevTools, url: str, png: Path, wait_s: float) -> str:
    """Open ``url``, wait (at most ``wait_s``) until it is drawn or shows an error, write its
    screenshot to ``png`` and return its DOM."""
    browser.evaluate("window.steamtwinLeft = true")  # not in the next page's context
    opened = browser.call("Page.navigate", {"url": url}, browser.session)
    if opened.get("errorText"):
        raise BrowserError(f"{url} did not open: {opened['errorText']}")
    deadline = time.monotonic() + wait_s
    while time.monotonic() < deadline:
        try:  # a page that forwards (the fleet page of one unit) destroys its context once
            if browser.evaluate(STATE):
                break
        except BrowserError:
            pass
        time.sleep(0.1)
    dom = str(browser.evaluate("document.documentElement.outerHTML"))
    shot = browser.call("Page.captureScreenshot", {"format": "png"}, browser.session)
    png.write_bytes(base64.b64decode(shot["data"]))
    return dom


def screenshot_pages(base_url: str, unit: str, folder: str | Path,
                     pages: Sequence[DashboardPage] = DASHBOARD_PAGES, *,
                     chromium: str | Path | None = None, size: tuple[int, int] = (1366, 768),
                     wait_s: float = 20.0, timeout_s: float = 30.0) -> list[PageShot]:
    """A screenshot of each of ``pages`` of the service at ``base_url`` (e.g.
    ``http://127.0.0.1:8080``) for ``unit``, written as ``folder/dashboard-<name>.png`` at
    ``size`` (px), and whether each page drew its data (:func:`page_check`).

    One headless Chromium opens the pages in turn. ``chromium``: the executable (default
    :func:`find_chromium`); none found → ``[]``. ``wait_s``: the longest a page is given to
    draw (s); ``timeout_s``: the longest the browser may take to answer one command (s).
    Blocking: call it from a thread (``asyncio.to_thread``) when the service runs in the
    caller's event loop. A page (or a browser) that fails is reported (``rendered`` False),
    never raised.
    """
    executable = Path(chromium) if chromium is not None else find_chromium()
    if executable is None:
        return []
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    shots: list[PageShot] = []
    with tempfile.TemporaryDirectory(prefix="steamtwin-chromium-") as profile:
        start = time.perf_counter()
        try:
            browser = _DevTools(executable, profile, size, timeout_s)
        except BrowserError as error:
            return [PageShot(page, base_url.rstrip("/") + page.path.format(unit=unit), None,
                             False, str(error), time.perf_counter() - start) for page in pages]
        try:
            for page in pages:
                url = base_url.rstrip("/") + page.path.format(unit=unit)
                png = folder / f"dashboard-{page.name.lower()}.png"
                png.unlink(missing_ok=True)
                try:
                    rendered, detail = page_check(_shoot(browser, url, png, wait_s), page)
                except BrowserError as error:
                    rendered, detail = False, str(error)
                shots.append(PageShot(page, url, png if png.is_file() else None, rendered,
                                      detail, time.perf_counter() - start))
                start = time.perf_counter()
        finally:
            browser.close()
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
