"""End to end (issue 22 on issue 21): ``run_service`` with the HTTP companion — a replayed
virtual-plant unit processed by the real live twin while the API, on the same loop and the
same DuckDB database, answers with the samples it is storing; both stop together."""

from __future__ import annotations

import asyncio

import httpx
import pandas as pd
import pytest

from steamtwin.dcs.plant import run_plant, write_plant
from steamtwin.live.config import load_config
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.runner import run_service
from steamtwin.web.server import HttpSettings, http_companion


async def _serve_and_poll(settings) -> tuple[dict, list[int]]:
    bound: dict[str, int] = {}
    companion = http_companion(HttpSettings(port=0), settings,
                               on_bound=lambda _host, port: bound.update(port=port))
    service = asyncio.create_task(run_service(settings, companions=[companion]))
    counts: list[int] = []
    async with httpx.AsyncClient(base_url=f"http://127.0.0.1:{bound['port']}",
                                 timeout=5.0) as client:
        while not service.done():
            try:
                answer = await client.get("/api/units/unit1/series",
                                          params={"signal": "hp_exhaust_temperature",
                                                  "source": "twin", "span_s": 3600})
                if answer.status_code == 200:
                    counts.append(answer.json()["count"])
            except httpx.TransportError:
                pass  # not listening yet, or already stopped
            await asyncio.sleep(0.1)
    return await service, counts


pytestmark = pytest.mark.slow  # ~7 s: the virtual plant's warm-up and the model (CI runs it)

SAMPLES = 300
"""Samples replayed: 1.5 s at ``speed = 100``."""


def test_the_api_reads_what_the_live_service_stores(tmp_path):
    run = run_plant("deep-peak-50", hours=0.01, random_state=6)
    paths = write_plant(run, tmp_path, file_format="parquet")
    historian = pd.read_parquet(paths["historian"])
    historian.iloc[:SAMPLES].to_parquet(paths["historian"])
    config = tmp_path / "unit.toml"
    config.write_text(f'database = "twin.duckdb"\n[[units]]\nname = "unit1"\n'
                      f'tags = "{paths["tag_map"]}"\nblock_samples = 20\n[units.source]\n'
                      f'kind = "replay"\npath = "{paths["historian"]}"\nspeed = 100\n')
    summaries, counts = asyncio.run(_serve_and_poll(load_config(config)))
    assert summaries["unit1"].samples == SAMPLES
    assert counts, "the API never answered while the service ran"
    # answered while storing: the counts only grow, and at least one answer came between the
    # first stored block and the last (the first answers may come before anything is stored)
    assert counts == sorted(counts) and any(0 < count < SAMPLES for count in counts)
    with LiveHistorian(tmp_path / "twin.duckdb") as historian:  # closed cleanly, reopens
        assert historian.resume_time("unit1") == run.measured.index[SAMPLES - 1]
