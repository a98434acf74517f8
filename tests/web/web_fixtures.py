"""Helpers of the HTTP service's tests (imported by tests/web/conftest.py and the tests): a
historian filled by the live twin's own writer (:meth:`LiveHistorian.commit_block`, as the
service stores its blocks) and a serve configuration whose tag map gives the signals' tags and
instrument errors."""

from __future__ import annotations

import asyncio
import dataclasses
import threading
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.blade.mesh import block_mesh
from steamtwin.dcs.plant import plant_tag_map
from steamtwin.dcs.quality import Flag
from steamtwin.dcs.tagmap import write_tag_map
from steamtwin.live.config import load_config
from steamtwin.live.historian import Alarm, AlarmEnd, BlockEvents, LiveHistorian
from steamtwin.rom.estimator import PodRbfRom
from steamtwin.rom.romfile import BladeRom, probe_nodes, save_rom
from steamtwin.web.access import AccessPolicy, load_tokens
from steamtwin.web.app import WebSettings
from steamtwin.web.server import HttpSettings, http_companion

START = pd.Timestamp("2026-03-01T00:00:00Z")
HOURS = 2


def unit_block(start_s: int, n: int, seed: int = 0) -> tuple[dict[str, pd.DataFrame],
                                                             pd.DataFrame]:
    """``n`` 1-s samples from ``start_s`` s after :data:`START`: measured, twin, residual
    (SI) and the gate's flags."""
    index = START + pd.to_timedelta(np.arange(start_s, start_s + n), unit="s")
    rng = np.random.default_rng(seed + start_s)
    k = np.arange(start_s, start_s + n, dtype=float)
    twin_t = 600.0 + 5.0 * np.sin(2.0 * np.pi * k / 3600.0)
    measured = pd.DataFrame({"hp_exhaust_temperature": twin_t + rng.normal(0.0, 0.5, n),
                             "control_stage_pressure": 9.0e6 + 100.0 * k}, index=index)
    twin = pd.DataFrame({"hp_exhaust_temperature": twin_t,
                         "blade_leading_edge": 780.0 + 0.001 * k}, index=index)
    residual = measured[["hp_exhaust_temperature"]] - twin[["hp_exhaust_temperature"]]
    flags = pd.DataFrame(None, index=index, columns=measured.columns, dtype=object)
    return {"measured": measured, "twin": twin, "residual": residual}, flags


BLOCK_S = 600
"""Seconds per stored block (the service commits smaller ones; the rows are the same)."""


def fill(path) -> None:
    """2 h of unit1 (at 00:30:00 a spike put in the data and flagged, a stuck flag on the
    pressure, an alarm raised and a parameter swap; at 00:40 that alarm ends, a degradation
    alarm stays active and the flow coefficient moves again) and 10 min of unit2."""
    with LiveHistorian(path) as historian:
        for block in range(HOURS * 3600 // BLOCK_S):
            start_s = BLOCK_S * block
            frames, flags = unit_block(start_s, BLOCK_S)
            index = frames["measured"].index
            events = None
            if start_s == 1800:
                frames["measured"].iloc[0, 0] = 700.0
                flags.iloc[0, 0] = str(int(Flag.SPIKE | Flag.OUT_OF_RANGE))
                flags.iloc[1, 1] = str(int(Flag.STUCK))
                events = BlockEvents(
                    alarms=(Alarm("unit1", "sensor_fault", index[0], "hp_exhaust_temperature",
                                  evidence={"statistic": 9.1, "threshold": 5.0}),
                            AlarmEnd("sensor_fault", "hp_exhaust_temperature", index[10]),
                            Alarm("unit1", "degradation", index[15], None,
                                  evidence={"statistic": 12.0})),
                    parameters=((index[0], {"flow_coefficient": 0.99,
                                            "friction_coefficient": 1.0}, "scheduled"),
                                (index[15], {"flow_coefficient": 0.98}, "degradation",
                                 {"flow_coefficient": (0.965, 0.995)})))
            historian.commit_block("unit1", frames, flags, events=events)
        frames, flags = unit_block(0, 600, seed=7)
        historian.commit_block("unit2", frames, flags)


def write_serve_config(folder, db):
    """A serve configuration of unit1 and unit2 on ``db`` in ``folder`` (a replay source that
    is never run), with a tag map giving the exhaust temperature an instrument σ of 1.5 K."""
    tag_map = plant_tag_map()
    signals = dict(tag_map.signals)
    signals["hp_exhaust_temperature"] = dataclasses.replace(
        signals["hp_exhaust_temperature"], noise_si=1.5)
    write_tag_map(dataclasses.replace(tag_map, signals=signals), folder / "tags.toml")
    (folder / "plant.csv").write_text("Timestamp\n")
    units = "".join(f'[[units]]\nname = "{name}"\ntags = "tags.toml"\n[units.source]\n'
                    'kind = "replay"\npath = "plant.csv"\n' for name in ("unit1", "unit2"))
    config = folder / "unit.toml"
    config.write_text(f'database = "{db}"\n{units}')
    return load_config(config)


ROM_INPUTS = ("control_stage_pressure", "hp_exhaust_temperature")
"""The test ROM's inputs: two signals :func:`fill` measures."""


def write_rom(path) -> None:
    """A small blade ROM on :data:`ROM_INPUTS` (a field linear in them, on a block 'blade'
    with the six regions' probes) at ``path``."""
    mesh = block_mesh(np.linspace(0, 0.02, 4), np.linspace(0, 0.01, 3), np.linspace(0, 0.05, 6))
    rng = np.random.default_rng(0)
    conditions = np.column_stack([rng.uniform(8.9e6, 9.8e6, 12), rng.uniform(590.0, 710.0, 12)])
    scaled = (conditions - [8.9e6, 590.0]) / [0.9e6, 120.0]
    fields = 700.0 + scaled @ (50.0 * rng.uniform(0.5, 1.0, size=(2, mesh.points.shape[0])))
    rom = PodRbfRom(energy=0.9999).fit(fields, conditions, input_names=ROM_INPUTS)
    save_rom(BladeRom(rom, mesh, probe_nodes(mesh),
                      pd.DataFrame(conditions, columns=list(ROM_INPUTS))), path)


READ, ACK = "r" * 40, "a" * 40
"""The tokens of :class:`ServedSite`: read-only and allowed to acknowledge alarms."""


class ServedSite:
    """The HTTP companion on loopback (any free port: :attr:`url`) in a thread of its own, on
    :func:`fill`'s historian with :func:`write_rom`'s ROM for unit1, with the tokens
    :data:`READ` and :data:`ACK` unless not ``tokens``; the test thread writes the
    historian (:meth:`commit`)."""

    def __init__(self, folder: Path, tokens: bool = True) -> None:
        db = folder / "twin.duckdb"
        fill(db)
        write_rom(folder / "rom.npz")
        config = write_serve_config(folder, db).source
        config.write_text(config.read_text().replace('name = "unit1"\n',
                                                     'name = "unit1"\nrom = "rom.npz"\n'))
        access = AccessPolicy()
        if tokens:
            token_file = folder / "tokens.toml"
            token_file.write_text(
                f'[[tokens]]\nname = "viewer"\nrole = "read"\ntoken = "{READ}"\n'
                f'[[tokens]]\nname = "shift-lead"\nrole = "ack"\ntoken = "{ACK}"\n')
            access = load_tokens(token_file)
        bound: dict[str, int] = {}
        self.companion = http_companion(
            HttpSettings(port=0, access=access, web=WebSettings(poll_s=0.1)),
            load_config(config), on_bound=lambda _host, port: bound.update(port=port))
        self.url = f"http://127.0.0.1:{bound['port']}"
        self.historian = LiveHistorian(db)
        self.historian.open()
        self.next_s = 7200
        self.loop = asyncio.new_event_loop()
        self.done = asyncio.Event()
        self.thread = threading.Thread(target=self.loop.run_until_complete,
                                       args=(self.companion(self.historian, self.done),))
        self.thread.start()

    def commit(self, n: int = 1, events: BlockEvents | None = None) -> pd.Timestamp:
        """``n`` new 1-s samples of unit1 (with ``events``), stored as the service stores
        them; the last time."""
        frames, flags = unit_block(self.next_s, n)
        self.historian.commit_block("unit1", frames, flags, events=events)
        self.next_s += n
        return frames["measured"].index[-1]

    def close(self) -> None:
        self.loop.call_soon_threadsafe(self.done.set)
        self.thread.join(10.0)
        self.historian.close()
