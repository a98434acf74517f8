"""Helpers of the Rotor page's tests: a historian holding what the live twin stores for a unit
with a rotor model — the measured load and the rotor's twin signals over two load cycles
(100 → 50 → 100 %, the groove root in compression while heating and tension while cooling) —
and a serve configuration naming the rotor (``rotor = "fit"``: the HTTP service needs only the
spec's rotor steel) with an allowable stress."""

from __future__ import annotations

import numpy as np
import pandas as pd

from steamtwin.dcs.plant import plant_tag_map
from steamtwin.dcs.tagmap import write_tag_map
from steamtwin.live.config import load_config
from steamtwin.live.historian import LiveHistorian
from steamtwin.spec import load_spec

START = pd.Timestamp("2026-03-01T00:00:00Z")
CYCLE_S = 3600
SECONDS = 2 * CYCLE_S
ALLOWABLE_MPA = 300


def rotor_frames(start_s: int, n: int) -> dict[str, pd.DataFrame]:
    """``n`` 1-s samples from ``start_s``: measured load (W), twin rotor signals (K, Pa)."""
    index = START + pd.to_timedelta(np.arange(start_s, start_s + n), unit="s")
    phase = 2.0 * np.pi * np.arange(start_s, start_s + n, dtype=float) / CYCLE_S
    rated = load_spec("reference").design.generator_power
    load = rated * (0.75 + 0.25 * np.cos(phase))
    swing = np.sin(phase)  # cooling (falling load): tension at the groove root
    twin = pd.DataFrame({
        "rotor_groove_stress": 40e6 + 180e6 * swing,
        "rotor_bore_stress": 60e6 - 50e6 * swing,
        "rotor_groove_temperature": 760.0 + 40.0 * np.cos(phase),
        "rotor_bore_temperature": 765.0 + 25.0 * np.cos(phase - 0.5),
        "rotor_mean_temperature": 762.0 + 30.0 * np.cos(phase - 0.3)}, index=index)
    return {"measured": pd.DataFrame({"load": load}, index=index), "twin": twin}


def fill_rotor(path) -> None:
    """Two load cycles of unit1 at 1 s, stored as the service stores its blocks."""
    with LiveHistorian(path) as historian:
        for start_s in range(0, SECONDS, 900):
            frames = rotor_frames(start_s, 900)
            flags = pd.DataFrame(None, index=frames["measured"].index, columns=["load"],
                                 dtype=object)
            historian.commit_block("unit1", frames, flags)


def write_rotor_config(folder, db, allowable: bool = True):
    """A serve configuration of unit1 on ``db`` with ``rotor = "fit"`` (and the allowable)."""
    write_tag_map(plant_tag_map(), folder / "tags.toml")
    (folder / "plant.csv").write_text("Timestamp\n")
    limit = f"rotor_allowable_mpa = {ALLOWABLE_MPA}\n" if allowable else ""
    config = folder / "unit.toml"
    config.write_text(f'database = "{db}"\n[[units]]\nname = "unit1"\ntags = "tags.toml"\n'
                      f'rotor = "fit"\n{limit}[units.source]\nkind = "replay"\n'
                      'path = "plant.csv"\n[[units]]\nname = "unit2"\ntags = "tags.toml"\n'
                      '[units.source]\nkind = "replay"\npath = "plant.csv"\n')
    return load_config(config)
