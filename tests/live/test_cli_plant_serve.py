"""``steamtwin plant serve`` end to end in its own process: a real OPC UA endpoint a client
reads, the tag map it writes resolves, SIGTERM stops it cleanly (issue 21, item 3)."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from asyncua import Client
from ports import free_port

from steamtwin.dcs.tagmap import load_tag_map
from steamtwin.live.nodes import resolve_node_id

pytestmark = pytest.mark.slow  # 12 s of the full suite (2026-11-27): not in the quick loop


def _wait_for(process: subprocess.Popen, text: str, timeout: float) -> str:
    seen = ""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if not line and process.poll() is not None:
            break
        seen += line
        if text in line:
            return seen
    raise AssertionError(f"{text!r} not printed within {timeout} s; output: {seen}")


def test_plant_serve_publishes_resolvable_tags_and_stops_on_sigterm(tmp_path: Path):
    port = free_port()
    tags = tmp_path / "live-tags.toml"
    process = subprocess.Popen(
        [sys.executable, "-m", "steamtwin", "plant", "serve", "--scenario",
         "deep-peak-50", "--hours", "0.02", "--speed", "max", "--port", str(port),
         "--tags-out", str(tags)],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        env={**os.environ, "COLUMNS": "200"})
    try:
        _wait_for(process, "all ", timeout=240)  # every sample out, history kept
        tag_map = load_tag_map(tags)
        spec = tag_map.signals["control_stage_pressure"]

        async def read() -> tuple[float, int]:
            async with Client(url=f"opc.tcp://127.0.0.1:{port}/steamtwin/plant/",
                              timeout=10) as client:
                node = client.get_node(await resolve_node_id(client, spec.node_id))
                value = await node.read_value()
                history = await node.read_raw_history()
                return value, len(history)

        value, history = asyncio.run(read())
        assert 5.0 < value < 15.0  # MPa at ~50 % load on sliding pressure
        assert history == 1673  # every sample of the run, within --history-samples
        process.send_signal(signal.SIGTERM)
        out, _ = process.communicate(timeout=30)
        assert process.returncode == 0
        assert "stopped after 1673 samples" in out
    finally:
        if process.poll() is None:
            process.kill()
