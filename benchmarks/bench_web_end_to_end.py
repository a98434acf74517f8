"""End to end: a value change at the plant's OPC UA server → drawn in the browser's Unit page
(issue 22, "What must hold": ≤ 1.5 s at p95 at 1 Hz; the Unit page "updates within a second").

* **plant**: a virtual-plant OPC UA server (``live.PlantServer``, 127.0.0.1, no security), in a
  thread of this process with its own event loop, publishes a plant run (``deep-peak-50``,
  seed 0) at 1 Hz with source timestamps on the wall clock; the wall time (``time.time``) at
  which every tag of a sample has been written is recorded;
* **service**: the real CLI, ``steamtwin serve --config … --http-port …`` in a process of its
  own (an OPC UA source, so provisional rows are on: ``live.runner``), reading that server;
* **browser**: Debian's headless chromium through Playwright opens ``/units/unit1`` as soon
  as the service has stored its first (provisional) sample, or with ``--after-final`` once it
  has stored its first final block (after the gate's 60-s look-ahead), and a
  hook on the first temperature chart's uPlot ``draw`` records the wall clock (``Date.now()``,
  the same clock) and the newest sample time drawn.

Latency of a sample = its first drawing − its write at the server: the OPC UA subscription,
the provisional rows' commit, the live feed's poll, the event stream and uPlot's drawing —
for the samples written after the hook was set (the page first draws the samples stored
before its event stream opened, sent with ``Last-Event-ID``; they are not counted).
Prints p50/p95/p99/max over ``--changes`` samples, the service's CPU time (``getrusage`` of the
waited child) and the load average.

Run: python benchmarks/bench_web_end_to_end.py [--changes 120]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import resource
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path

import numpy as np
import pandas as pd
from playwright.sync_api import sync_playwright

from bench_web_pages import ARGS, CHROMIUM, RECORD  # the browser and the draw hook
from steamtwin.dcs.plant import plant_tag_map, run_plant
from steamtwin.dcs.tagmap import write_tag_map
from steamtwin.live.plant_server import PlantServer, PlantServerSettings, plant_node_ids


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


class _Plant(threading.Thread):
    """The OPC UA server in a thread: publishes ``signals`` at 1 Hz from the next whole second
    after its first subscriber, its timestamps shifted onto the wall clock; ``written``: sample
    time (Unix ms) → wall time (s) when all its tags had been written."""

    def __init__(self, signals: pd.DataFrame, port: int) -> None:
        super().__init__(daemon=True)
        self.server = PlantServer(signals, plant_node_ids(plant_tag_map()),
                                  PlantServerSettings(port=port, speed=1.0))
        self.written: dict[float, float] = {}
        self.started = threading.Event()
        self.stop = threading.Event()

    def run(self) -> None:
        asyncio.run(self._main())

    async def _main(self) -> None:
        server = self.server
        await server.start()
        self.started.set()
        await server.wait_for_subscribers(server.signals.shape[1], timeout_s=120.0)
        start = pd.Timestamp(np.ceil(time.time()) + 1.0, unit="s", tz="UTC")
        server.signals = server.signals.set_axis(
            start + (server.signals.index - server.signals.index[0]))

        def record(_fraction: float, _message: str) -> None:
            stamp = server.signals.index[server.published - 1]
            self.written[stamp.timestamp() * 1e3] = time.time()

        server.progress = record
        await asyncio.sleep(max(0.0, start.timestamp() - time.time()))
        publishing = asyncio.create_task(server.publish())
        while not self.stop.is_set() and not publishing.done():
            await asyncio.sleep(0.2)
        publishing.cancel()
        await server.stop()


def _first_sample(url: str, final: bool, timeout_s: float = 300.0) -> None:
    """Wait until the service has stored its first sample: a provisional one (its signals are
    listed), or with ``final`` its first final block (/api/units' last_sample)."""
    deadline = time.monotonic() + timeout_s
    path = "/api/units" if final else "/api/units/unit1/signals"
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(f"{url}{path}", timeout=5) as answer:
                found = json.loads(answer.read())
                if found and (not final or found[0]["last_sample"]):
                    return
        except OSError:
            pass  # not listening yet
        time.sleep(1.0)
    raise SystemExit(f"no sample stored within {timeout_s:.0f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--changes", type=int, default=120, help="samples timed in the page")
    parser.add_argument("--after-final", action="store_true",
                        help="open the page after the first final block (default: as soon as "
                        "the first provisional sample is stored)")
    args = parser.parse_args()
    signals = run_plant("deep-peak-50", hours=0.15, random_state=0).measured
    plant = _Plant(signals, _free_port())
    plant.start()
    plant.started.wait(60)
    http_port = _free_port()
    url = f"http://127.0.0.1:{http_port}"
    with tempfile.TemporaryDirectory() as folder:
        base = Path(folder)
        write_tag_map(plant.server.tag_map, base / "tags.toml")
        (base / "service.toml").write_text(
            'database = "live.duckdb"\n[[units]]\nname = "unit1"\ntags = "tags.toml"\n'
            f'[units.source]\nkind = "opcua"\nendpoint = "{plant.server.endpoint}"\n'
            "allow_insecure = true\n", encoding="utf-8")
        service = subprocess.Popen(
            [str(Path(sys.executable).with_name("steamtwin")), "serve", "--config",
             str(base / "service.toml"), "--http-port", str(http_port), "--log-level",
             "warning"], stdout=subprocess.DEVNULL)
        try:
            _first_sample(url, args.after_final)
            with sync_playwright() as playwright:
                browser = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
                page = browser.new_page(viewport={"width": 1366, "height": 768})
                page.goto(f"{url}/units/unit1")
                page.wait_for_function("() => document.body.dataset.ready", timeout=60_000)
                page.evaluate(RECORD)
                watching = time.time()
                page.wait_for_timeout((args.changes + 3) * 1000.0)
                redraws = page.evaluate("window.redraws")
                browser.close()
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
        finally:
            service.send_signal(signal.SIGTERM)
            service.wait(timeout=60)
            plant.stop.set()
            plant.join(30)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    shown: dict[float, float] = {}
    for wall_ms, sample_ms in redraws:  # the first drawing of each sample
        shown.setdefault(sample_ms, wall_ms / 1e3)
    # changes made while the page watched (it also draws, at once, the samples stored before
    # it opened its event stream: Last-Event-ID; those are not a latency)
    latency = np.array([wall - plant.written[sample] for sample, wall in shown.items()
                        if plant.written.get(sample, 0.0) > watching])[: args.changes]
    p50, p95, p99 = np.percentile(latency, [50, 95, 99])
    print(json.dumps({
        "samples_timed": int(latency.size), "p50_s": round(p50, 3), "p95_s": round(p95, 3),
        "p99_s": round(p99, 3), "max_s": round(float(latency.max()), 3),
        "within_1s": int((latency <= 1.0).sum()),
        "service_cpu_s": round(after.ru_utime + after.ru_stime - before.ru_utime
                               - before.ru_stime, 1),
        "published": plant.server.published, "loadavg": [round(x, 2) for x in os.getloadavg()],
        "date": pd.Timestamp.now(tz="UTC").isoformat(timespec="seconds")}))


if __name__ == "__main__":
    main()
