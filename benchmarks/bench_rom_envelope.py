"""Benchmark of the ROM's snapshot envelope (issue 18, item 4): coverage and accuracy.

Run: python benchmarks/bench_rom_envelope.py [--workers 2] — prints, on the default
control-stage blade mesh with 32 snapshots:

1. the reference with the calibrated flow coefficient 0.953 of the issue: how many conditions of
   the design before the envelope the model refuses (per layout), and what ``rom build``
   replaces now;
2. the share of the virtual plant's samples (``steamtwin plant --scenario day``, read through
   the quality gate) that the ROM flags ``rom_out_of_domain`` and ``rom_extrapolated``, overall
   and per hold (30/50/75/100 % demand), for the design before the envelope, the envelope
   without data and the envelope with ``--data``; the same for the spec derived and fitted from
   the example kit (``steamtwin turbine derive example-600mw`` + ``fit``) — a spec that does not
   describe how the virtual plant runs, the case of a unit's own design-data spec;
3. ROM error on held-out conditions across each envelope (uniform in every level's box, the
   operating line at 30/50/75/100 %, and for the reference 12 of the plant's own states incl.
   the 30 % hold): max abs (K) and relative to the field range, overall and within 2 % of
   30 % load.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.dcs.history import load_history
from steamtwin.dcs.plant import run_plant, write_plant
from steamtwin.geometry.meshing import blade_volume_mesh
from steamtwin.model.design_fit import fit_design, fitted_spec_toml
from steamtwin.model.fom import FullOrderModel, InputError
from steamtwin.model.operating import hp_exhaust_pressure, operating_point
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.rom.build import build_rom, rom_envelope
from steamtwin.rom.envelope import feasible_conditions
from steamtwin.rom.estimator import ExtrapolationWarning, PodRbfRom
from steamtwin.rom.features import ControlStageFeatures
from steamtwin.rom.reconstruction import FLAG_EXTRAPOLATED, FLAG_OUT_OF_DOMAIN, predict_series
from steamtwin.rom.romfile import BladeRom, probe_nodes
from steamtwin.rom.snapshots import ROM_INPUTS, design_conditions, generate_snapshots
from steamtwin.rom.validation import rom_errors
from steamtwin.spec import derive_spec, load_heat_balance, load_spec

CALIBRATED = ModelParameters(flow_coefficient=0.953)
HOLDS = (0.3, 0.5, 0.75, 1.0)


def build_before(spec, mesh, params, workers):
    """The ROM as ``rom build`` made it before the envelope: the fixed design, no repair."""
    conditions = design_conditions(spec, 32)
    snaps = generate_snapshots(spec, mesh, conditions, params, max_workers=workers)
    rom = PodRbfRom(energy=0.992, projection_tolerance=0.1, input_scaling="range",
                    features=ControlStageFeatures(spec, params)).fit(
        snaps.fields, snaps.rom_inputs(), input_names=ROM_INPUTS,
        sensors=snaps.sensors.to_numpy(dtype=float), sensor_names=tuple(snaps.sensors.columns))
    return BladeRom(rom=rom, mesh=snaps.mesh, probes=probe_nodes(snaps.mesh),
                    conditions=snaps.conditions, provenance={})


def flag_shares(bundle, data, demand) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        table = predict_series(bundle, data).sensors
    parts = [f"all {table[FLAG_OUT_OF_DOMAIN].mean():.1%} / {table[FLAG_EXTRAPOLATED].mean():.1%}"]
    for hold in HOLDS:
        mine = (demand - hold).abs().to_numpy() < 1e-9
        parts.append(f"{hold:.0%} {table[FLAG_OUT_OF_DOMAIN][mine].mean():.1%} / "
                     f"{table[FLAG_EXTRAPOLATED][mine].mean():.1%}")
    return "; ".join(parts)


def held_out_conditions(spec, envelope, params, rng, plant_states=None) -> pd.DataFrame:
    """3 uniform points in every level's box, the line at HOLDS, optional plant states."""
    rows = []
    for box in envelope.levels:
        point = {k: float(v) for k, v in operating_point(spec, box.load).items()}
        for _ in range(3):
            flow = point["main_steam_flow"] * rng.uniform(*box.flow_factor)
            load = flow / spec.design.main_steam_flow
            rows.append({"load_level": box.load, "load_fraction": load,
                         "main_steam_pressure": point["main_steam_pressure"]
                         * rng.uniform(*box.pressure_factor),
                         "main_steam_temperature": point["main_steam_temperature"]
                         + rng.uniform(*box.temperature_offset),
                         "main_steam_flow": flow,
                         "hp_exhaust_pressure": float(hp_exhaust_pressure(spec, flow, load))})
    for load in HOLDS:
        rows.append({"load_level": load, "load_fraction": load,
                     **{k: float(v) for k, v in operating_point(spec, load).items()}})
    table = pd.DataFrame(rows)
    if plant_states is not None:
        table = pd.concat([table, plant_states], ignore_index=True)
    return feasible_conditions(spec, table, params)[0]


def report_errors(label, bundle, held) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        summary = rom_errors(bundle.rom, held.fields, held.rom_inputs()).summary()
    low = (held.conditions["load_fraction"] - 0.3).abs() < 0.02
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        low_error = rom_errors(bundle.rom, held.fields[low.to_numpy()],
                               held.rom_inputs()[low.to_numpy()]).summary()
    print(f"   {label}: {len(held.fields)} held-out, max abs {summary['max_total']:.3f} K, "
          f"max relative {summary['max_relative_total']:.2%} (field range "
          f"{bundle.rom.field_range_:.2f} K); at 30 % ({int(low.sum())}): max abs "
          f"{low_error['max_total']:.3f} K, {low_error['max_relative_total']:.2%}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    workers = args.workers
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}")
    reference = load_spec("reference")
    model = FullOrderModel(reference)
    mesh = blade_volume_mesh(reference, "hp1")
    print(f"blade mesh {mesh.points.shape[0]} nodes")

    print("\n1. reference, flow coefficient 0.953 (the issue's calibrated value)")
    for layout in ("lhs", "corners", "bands"):
        refused = []
        for seed in range(5):
            plan = design_conditions(reference, 32, random_state=seed, layout=layout)
            bad = 0
            for i in range(len(plan)):
                try:
                    model.simulate_detailed(plan.iloc[[i]][list(INPUT_SIGNALS)], CALIBRATED,
                                            stages=False)
                except InputError:
                    bad += 1
            refused.append(bad)
        print(f"   design before the envelope, {layout}, seeds 0-4: conditions refused "
              f"{refused} (any > 0 failed the build)")
    start = time.perf_counter()
    calibrated, _ = build_rom(reference, mesh, CALIBRATED, max_workers=workers,
                              layout="corners", parameter_intervals={
                                  "flow_coefficient": (0.94, 0.97)})
    envelope = calibrated.provenance["envelope"]
    print(f"   now (corners, interval 0.94-0.97): built in {time.perf_counter() - start:.0f} s, "
          f"{envelope['replaced']} replacement(s); valve points "
          f"{[round(v, 3) for v in envelope['valve_points']]}")

    print("\n2. virtual plant, scenario day (24 h), samples flagged out-of-domain / "
          "extrapolated")
    folder = Path(tempfile.mkdtemp(prefix="bench-rom-envelope-"))
    run = run_plant("day", random_state=1)
    paths = write_plant(run, folder)
    history = load_history(paths["historian"], paths["tag_map"], required=list(ROM_INPUTS),
                           accept_errors=True)
    data = history.data
    demand = run.true_inputs["load_demand"].reindex(data.index, method="nearest")
    print(f"   {len(data)} samples after the quality gate")
    kit = load_heat_balance("example-600mw")
    text = derive_spec(kit).toml
    derived = load_spec_text(text, folder / "derived.toml")
    fitted = load_spec_text(fitted_spec_toml(text, fit_design(derived, kit).part_load),
                            folder / "fitted.toml")
    rng = np.random.default_rng(3)
    demand_all = run.true_inputs["load_demand"].to_numpy()
    steady = run.true_inputs[np.any(np.abs(demand_all[:, None] - np.array(HOLDS)) < 1e-9,
                                    axis=1)]
    plant_states = steady.iloc[rng.choice(len(steady), 12, replace=False)]
    plant_states = plant_states[list(INPUT_SIGNALS)].reset_index(drop=True).assign(
        load_level=lambda t: t["main_steam_flow"] / reference.design.main_steam_flow,
        load_fraction=lambda t: t["main_steam_flow"] / reference.design.main_steam_flow)
    for label, spec, params in (("reference", reference, ModelParameters()),
                                ("example kit, derived + fitted", fitted, ModelParameters())):
        print(f"   {label}:")
        start = time.perf_counter()
        before = build_before(spec, mesh, params, workers)
        print(f"     before the envelope ({time.perf_counter() - start:.0f} s): "
              f"{flag_shares(before, data, demand)}")
        start = time.perf_counter()
        plain, _ = build_rom(spec, mesh, params, max_workers=workers)
        print(f"     envelope, no data ({time.perf_counter() - start:.0f} s): "
              f"{flag_shares(plain, data, demand)}")
        start = time.perf_counter()
        observed, _ = build_rom(spec, mesh, params, max_workers=workers, observed=data)
        print(f"     envelope + --data ({time.perf_counter() - start:.0f} s): "
              f"{flag_shares(observed, data, demand)}; levels "
              f"{[round(b['load'], 3) for b in observed.provenance['envelope']['levels']]}, "
              f"{observed.provenance['envelope']['observed_anchors']} anchor snapshot(s)")
        print("   3. held-out errors")
        states = plant_states if spec is reference else None
        held_plain = generate_snapshots(spec, mesh, held_out_conditions(
            spec, rom_envelope(spec, params), params, rng, states), params,
            max_workers=workers)
        report_errors("envelope, no data, its own envelope", plain, held_plain)
        report_errors("before the envelope, same points", before, held_plain)
        held_data = generate_snapshots(spec, mesh, held_out_conditions(
            spec, rom_envelope(spec, params, observed=data), params, rng, states), params,
            max_workers=workers)
        report_errors("envelope + --data, its own envelope", observed, held_data)


def load_spec_text(text: str, path: Path):
    path.write_text(text, encoding="utf-8")
    return load_spec(path)


if __name__ == "__main__":
    main()
