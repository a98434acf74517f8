"""The dashboard in a real browser (issue 22, "What must hold": the Unit page with 24 h of
history loads in ≤ 2 s; a new value is visible in the browser ≤ 1.5 s (p95) at 1 Hz).

The service is :mod:`bench_web_api`'s (``--role service``: a historian prefilled with
``--history-h`` hours of one unit's 1-s samples, a writer committing each wall-clock second's
sample as the live service does, and the HTTP companion in the same loop), started as a
process of its own; this script drives Debian's headless chromium with Playwright:

* **load**: ``--loads`` times, a fresh browser context (cold cache: the charting library too)
  opens ``/units/unit1`` and waits until the page has drawn every chart (its
  ``data-ready``); then once more in the same context (warm cache);
* **live**: for ``--seconds``, every redraw of the page's first chart records the wall clock
  and the time of its newest sample; the latency is from that sample's second (when the
  writer commits it) to its redraw — the writer's commit, the feed's poll, the event stream
  and the browser's drawing.

Prints the page load times, the latency p50/p95/max, the service's CPU time and the machine
load. The OPC UA hop (plant server → the service's subscription) is not in this path.

Run: python benchmarks/bench_web_pages.py [--history-h 24] [--loads 3] [--seconds 30]
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from playwright.sync_api import sync_playwright

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking",
        "--disable-component-update", "--disable-sync", "--no-first-run"]
RECORD = """() => { const chart = document.querySelector('#temperatures .chart')._uplot;
    window.redraws = [];
    chart.hooks.draw = [...(chart.hooks.draw || []), (u) => window.redraws.push([Date.now(),
        u.data[0].at(-1) * 1e3])]; }"""


def _load(context, url: str) -> tuple[float, float]:
    """Seconds from navigation to every chart drawn, and to the first API request (the
    HTML, style sheets and scripts loaded and plotly.js evaluated)."""
    page = context.new_page()
    started = time.perf_counter()
    page.goto(url)
    page.wait_for_function("() => document.body.dataset.ready", timeout=60_000)
    ready = time.perf_counter() - started
    first_api_ms = page.evaluate("""() => Math.min(...performance.getEntriesByType('resource')
        .filter((e) => e.name.includes('/api/')).map((e) => e.startTime))""")
    page.close()
    return round(ready, 2), round(first_api_ms / 1e3, 2)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--history-h", type=float, default=24.0)
    parser.add_argument("--loads", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=30.0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        port_file = Path(folder) / "port"
        service = subprocess.Popen(
            [sys.executable, str(Path(__file__).with_name("bench_web_api.py")), "--role",
             "service", "--db", str(Path(folder) / "t.db"), "--port-file", str(port_file),
             "--history-h", str(args.history_h)], stdout=subprocess.PIPE, text=True)
        try:
            while not port_file.exists() or not port_file.read_text():
                if service.poll() is not None:
                    raise SystemExit("the service ended before listening")
                time.sleep(0.2)
            url = f"http://127.0.0.1:{port_file.read_text()}/units/unit1"
            time.sleep(2.0)  # the first commits after the prefill
            with sync_playwright() as playwright:
                browser = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
                cold, warm = [], []  # (ready, first API request) s
                for _ in range(args.loads):
                    context = browser.new_context(viewport={"width": 1366, "height": 768})
                    cold.append(_load(context, url))
                    warm.append(_load(context, url))
                    context.close()
                page = browser.new_page(viewport={"width": 1366, "height": 768})
                page.goto(url)
                page.wait_for_function("() => document.body.dataset.ready", timeout=60_000)
                page.evaluate(RECORD)
                page.wait_for_timeout(args.seconds * 1000.0)
                redraws = np.array(page.evaluate("window.redraws"), dtype=float)
                browser.close()
        finally:
            service.send_signal(signal.SIGTERM)
            out, _ = service.communicate(timeout=60)
    shown = {}
    for wall_ms, sample_ms in redraws:  # the first redraw showing each sample
        shown.setdefault(sample_ms, wall_ms)
    latency = np.array([wall - sample for sample, wall in shown.items()]) / 1e3
    print(json.dumps({
        "load_cold_s": cold, "load_warm_s": warm,
        "samples_seen": len(latency), "latency_p50_s": float(np.percentile(latency, 50)),
        "latency_p95_s": float(np.percentile(latency, 95)),
        "latency_max_s": float(latency.max()), "service": json.loads(out.strip().splitlines()[-1]),
        "loadavg": os.getloadavg()}))


if __name__ == "__main__":
    main()
