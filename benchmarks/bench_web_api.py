"""The HTTP API under load (issue 22, "What must hold": 200 concurrent clients polling at
1 Hz on this 2-core machine with p99 ≤ 250 ms, and the service still keeps up with the plant).

Two processes on loopback, as in the plant:

* the **service** (``--role service``, started by this script): a DuckDB historian prefilled
  with ``--history-h`` hours of one unit's 1-s samples (measured, twin, residual; 12 signals),
  then, on one asyncio loop, a writer that commits each wall-clock second's sample the way the
  live service does (``LiveHistorian.commit_block``) and the HTTP service
  (``web.server.http_companion``, uvicorn in the same loop). It reports how late each commit
  finished after its second began (the service keeps up while that stays well under 1 s)
  and its CPU time. The twin's model is left out: the live service spends ~1.4 ms of CPU per
  unit-sample on gate + FOM + ROM + residuals (docs/benchmarks.md, "Live twin pieces": 118 s
  of CPU for 86 400 samples), 0.14 % of a core at 1 Hz;
* the **clients** (this process): ``--clients`` asyncio tasks, each on its own kept-alive
  connection (as a browser), polling once a second at its own random phase what a Unit page
  polls — the last minute of a signal (raw), the active alarms, /health in turn — for
  ``--seconds``. Latency is from sending the request to having read the whole answer.

Prints the request count, errors, latency p50/p95/p99/max, the service's commit lateness
p99/max, both processes' CPU time and the machine load (``os.getloadavg``).

``--cache-s 0`` turns off the reuse of an identical poll's answer (``web.coalesce``).
``--streams K`` also opens K server-sent event streams (``/api/events``) and reports how long
after its second each new sample reached them (the second's start → the event read: the
writer's commit lateness, the feed's poll interval and the delivery).

Run: python benchmarks/bench_web_api.py [--clients 200] [--seconds 30] [--history-h 24]
     [--cache-s 0.2] [--streams 0]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.web.app import WebSettings

SIGNALS = ("main_steam_pressure", "main_steam_temperature", "main_steam_flow",
           "control_stage_pressure", "control_stage_temperature", "hp_exhaust_pressure",
           "hp_exhaust_temperature", "hp_inner_casing_temperature", "load")


def _frames(index: pd.DatetimeIndex, rng: np.random.Generator) -> dict[str, pd.DataFrame]:
    n = len(index)
    measured = pd.DataFrame({name: 500.0 + rng.normal(0.0, 1.0, n) for name in SIGNALS},
                            index=index)
    twin = measured[list(SIGNALS[3:8])] + 0.1
    twin["blade_leading_edge"] = 780.0
    residual = measured[list(SIGNALS[4:8])] - twin[list(SIGNALS[4:8])]
    return {"measured": measured, "twin": twin, "residual": residual}


async def _service(db: Path, port_file: Path, history_h: float, cache_s: float) -> None:
    from steamtwin.live.historian import LiveHistorian
    from steamtwin.web.app import WebSettings
    from steamtwin.web.server import HttpSettings, http_companion

    rng = np.random.default_rng(0)
    now = pd.Timestamp.now(tz="UTC").floor("s")
    start = now - pd.Timedelta(hours=history_h)
    historian = LiveHistorian(db)
    historian.open()
    hour = pd.Timedelta(hours=1)
    block_start = start
    while block_start < now:
        index = pd.date_range(block_start, min(block_start + hour, now), freq="1s",
                              inclusive="left", tz="UTC")
        historian.commit_block("unit1", _frames(index, rng))
        block_start += hour
    companion = http_companion(HttpSettings(port=0, web=WebSettings(cache_s=cache_s)),
                               on_bound=lambda _h, port: port_file.write_text(str(port)))
    done = asyncio.Event()
    loop = asyncio.get_running_loop()
    loop.add_signal_handler(signal.SIGTERM, done.set)
    server = asyncio.create_task(companion(historian, done))
    lateness = []
    cpu0 = time.process_time()
    while not done.is_set():
        second = pd.Timestamp.now(tz="UTC").floor("s")
        wake = (second + pd.Timedelta(seconds=1) - pd.Timestamp.now(tz="UTC")).total_seconds()
        try:
            await asyncio.wait_for(done.wait(), max(wake, 0.0))
            break
        except TimeoutError:
            pass
        tick = second + pd.Timedelta(seconds=1)
        last = historian.resume_time("unit1")
        index = pd.date_range(last + pd.Timedelta(seconds=1), tick, freq="1s", tz="UTC")
        historian.commit_block("unit1", _frames(index, rng))
        lateness.append((pd.Timestamp.now(tz="UTC") - tick).total_seconds())
    await server
    historian.close()
    late = np.array(lateness)
    print(json.dumps({"commits": len(late), "late_p50_s": float(np.percentile(late, 50)),
                      "late_p99_s": float(np.percentile(late, 99)),
                      "late_max_s": float(late.max()),
                      "cpu_s": time.process_time() - cpu0}))


async def _get(reader: asyncio.StreamReader, writer: asyncio.StreamWriter, target: str
               ) -> int:
    """One HTTP/1.1 GET on a kept-alive connection (RFC 9112): the status; the body is read
    whole (Content-Length framing, which the service's JSON answers use)."""
    writer.write(f"GET {target} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode())
    await writer.drain()
    head = await reader.readuntil(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    length = next(int(line.split(":", 1)[1]) for line in lines
                  if line.lower().startswith("content-length:"))
    await reader.readexactly(length)
    return int(lines[0].split(" ")[1])


async def _clients(port: int, clients: int, seconds: float, streams: int
                   ) -> dict[str, object]:
    """``clients`` browsers, each on its own kept-alive connection, polling once a second.
    A lean HTTP client on asyncio streams: httpx costs ~6 ms of CPU a request, which on this
    2-core machine would load it more than the service does."""
    latencies: list[float] = []
    errors: list[str] = []
    stop_at = time.perf_counter() + seconds

    async def poll(k: int) -> None:
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        await asyncio.sleep(random.random())  # each its own phase
        n = 0
        try:
            while time.perf_counter() < stop_at:
                tick = time.perf_counter()
                target = ("/api/units/unit1/series?signal=hp_exhaust_temperature&span_s=60",
                          "/api/alarms?active=true", "/health")[(k + n) % 3]
                try:
                    status = await _get(reader, writer, target)
                    if status != 200:
                        errors.append(f"{target}: {status}")
                except (OSError, asyncio.IncompleteReadError) as error:
                    errors.append(f"{target}: {type(error).__name__}")
                    writer.close()
                    reader, writer = await asyncio.open_connection("127.0.0.1", port)
                latencies.append(time.perf_counter() - tick)
                n += 1
                await asyncio.sleep(max(0.0, 1.0 - (time.perf_counter() - tick)))
        finally:
            writer.close()

    delays: list[float] = []

    async def listen() -> None:
        """One open event stream: how long after its second each sample arrives."""
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        writer.write(b"GET /api/events?unit=unit1 HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
        await writer.drain()
        try:
            while (remaining := stop_at - time.perf_counter()) > 0:
                try:
                    line = await asyncio.wait_for(reader.readline(), remaining)
                except TimeoutError:
                    break
                if line.startswith(b"id: "):  # the sample's time (chunk sizes never match)
                    sample = pd.Timestamp(line[4:].decode().strip())
                    delays.append((pd.Timestamp.now(tz="UTC") - sample).total_seconds())
        finally:
            writer.close()

    cpu0 = time.process_time()
    await asyncio.gather(*(poll(k) for k in range(clients)),
                         *(listen() for _ in range(streams)))
    cpu = time.process_time() - cpu0
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    writer.write(b"GET /health HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n")
    health = json.loads((await reader.read()).split(b"\r\n\r\n", 1)[1])
    writer.close()
    late = np.array(latencies) * 1000.0
    events = np.array(delays if delays else [np.nan]) * 1000.0
    return {"streams": streams, "events": len(delays),
            "event_delay_p50_ms": float(np.percentile(events, 50)),
            "event_delay_p95_ms": float(np.percentile(events, 95)),
            "event_delay_max_ms": float(np.max(events)),
            "requests": len(late), "errors": len(errors), "first_errors": errors[:3],
            "rate_per_s": len(late) / seconds,
            "p50_ms": float(np.percentile(late, 50)), "p95_ms": float(np.percentile(late, 95)),
            "p99_ms": float(np.percentile(late, 99)), "max_ms": float(late.max()),
            "client_cpu_s": cpu, "keeps_up": health["keeps_up"],
            "last_sample_age_s": health["units"]["unit1"]["age_s"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--role", choices=("clients", "service"), default="clients")
    parser.add_argument("--clients", type=int, default=200)
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--streams", type=int, default=0,
                        help="open server-sent event streams besides the pollers")
    parser.add_argument("--history-h", type=float, default=24.0)
    parser.add_argument("--cache-s", type=float, default=WebSettings().cache_s,
                        help="the service's answer reuse for identical polls (0: off)")
    parser.add_argument("--db", type=Path)
    parser.add_argument("--port-file", type=Path)
    args = parser.parse_args()
    if args.role == "service":
        asyncio.run(_service(args.db, args.port_file, args.history_h, args.cache_s))
        return
    with tempfile.TemporaryDirectory() as folder:
        port_file = Path(folder) / "port"
        started = time.perf_counter()
        service = subprocess.Popen(
            [sys.executable, __file__, "--role", "service", "--db", str(Path(folder) / "t.db"),
             "--port-file", str(port_file), "--history-h", str(args.history_h),
             "--cache-s", str(args.cache_s)],
            stdout=subprocess.PIPE, text=True)
        try:
            while not port_file.exists() or not port_file.read_text():
                if service.poll() is not None:
                    raise SystemExit("the service process ended before it listened")
                time.sleep(0.1)
            print(f"service up after {time.perf_counter() - started:.1f} s "
                  f"({args.history_h:g} h of history)")
            time.sleep(1.0)
            load_before = os.getloadavg()
            result = asyncio.run(_clients(int(port_file.read_text()), args.clients,
                                          args.seconds, args.streams))
            load_after = os.getloadavg()
        finally:
            service.send_signal(signal.SIGTERM)
            out, _ = service.communicate(timeout=30)
    print(json.dumps({**result, "service": json.loads(out.strip().splitlines()[-1]),
                      "load_before": load_before, "load_after": load_after}, indent=1))


if __name__ == "__main__":
    main()
