"""Fixtures of the ROM tests: a coarse control-stage blade and a small snapshot set on it."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.geometry.meshing import blade_volume_mesh
from steamtwin.model.operating import operating_point
from steamtwin.rom.snapshots import SnapshotSet, design_conditions, generate_snapshots


@pytest.fixture(scope="session")
def coarse_blade(reference_spec):
    return blade_volume_mesh(reference_spec, "hp1", element_size=0.006)


@pytest.fixture(scope="session")
def blade_snapshots(reference_spec, reference_model, coarse_blade) -> SnapshotSet:
    conditions = design_conditions(reference_spec, 16, random_state=0)
    return generate_snapshots(reference_spec, coarse_blade, conditions, max_workers=1)


def conditions_at(spec, loads, rng: np.random.Generator) -> pd.DataFrame:
    """Conditions at ``loads``: pressure ±2 %, temperature ±5 K, flow ±2 % (random, ``rng``)."""
    rows = []
    for load in loads:
        point = operating_point(spec, load)
        flow = float(point["main_steam_flow"]) * min(rng.uniform(0.98, 1.02), 1.0 / load)
        rows.append({
            "load_fraction": load,
            "main_steam_pressure": float(point["main_steam_pressure"]) * rng.uniform(0.98, 1.02),
            "main_steam_temperature": float(point["main_steam_temperature"])
            + rng.uniform(-5.0, 5.0),
            "main_steam_flow": flow,
            "hp_exhaust_pressure": spec.design.hp_exhaust_pressure * flow
            / spec.design.main_steam_flow,
        })
    return pd.DataFrame(rows)


def random_conditions(spec, n: int, seed: int) -> pd.DataFrame:
    """Conditions inside the design's envelope at random loads (held out from the design)."""
    rng = np.random.default_rng(seed)
    return conditions_at(spec, rng.uniform(0.3, 1.0, n), rng)


@pytest.fixture(scope="session")
def held_out_conditions():
    """:func:`conditions_at`, for test modules (they cannot import this conftest)."""
    return conditions_at


@pytest.fixture(scope="session")
def held_out_snapshots(reference_spec, reference_model, coarse_blade) -> SnapshotSet:
    return generate_snapshots(reference_spec, coarse_blade,
                              random_conditions(reference_spec, 6, seed=3), max_workers=1)
