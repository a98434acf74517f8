"""Benchmark of the blade POD–RBF ROM: build, errors, online speed, DMD, Figure 9.

Run: python benchmarks/bench_rom.py [--out DIR] [--workers 2] — prints

1. the build on the default control-stage blade mesh (32 snapshots, local process pool) at the
   defaults of ``steamtwin rom build`` (energy 0.992 + projection tolerance 0.1 K, RBF on the
   governing stage's physics features);
2. held-out and leave-one-out errors (projection, interpolation, total; max abs K and relative
   to the field range, see docs/rom.md) of that default ROM against the acceptance criterion,
   then of the plain RBF on (p0, T0, p1) at energy 0.992 and 0.99999 for comparison;
3. one reconstruction at N = 200k nodes, r = 10 modes (a ROM with the physics features fitted
   to synthetic 200k-node snapshots: the cost depends on the shapes only);
4. sensor and blade-probe predictions for a 7 200-sample (2 h at 1 s) DCS series;
5. the POD–RBF ROM against DMD on a 5 %/min ramp 100 → 50 % load between 10-min holds;
6. the Figure 9 analogue (worst held-out condition) as a PNG in --out.
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

from steamtwin.geometry.meshing import blade_volume_mesh
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.operating import load_profile_inputs, operating_point, ramp_profile
from steamtwin.rom.build import build_rom
from steamtwin.rom.dmd import compare_rom_and_dmd, ramp_transient
from steamtwin.rom.estimator import ExtrapolationWarning, PodRbfRom
from steamtwin.rom.figure import field_comparison_figure
from steamtwin.rom.reconstruction import predict_series
from steamtwin.rom.romfile import load_rom, save_rom
from steamtwin.rom.snapshots import ROM_INPUTS, generate_snapshots
from steamtwin.rom.validation import leave_one_out, rom_errors
from steamtwin.spec import load_spec


def held_out_conditions(spec, n_random: int, seed: int) -> pd.DataFrame:
    """Random loads in [0.3, 1] plus the four levels, inside the design's variation box."""
    rng = np.random.default_rng(seed)
    rows = []
    for load in [*rng.uniform(0.3, 1.0, n_random), 0.3, 0.5, 0.75, 1.0]:
        point = operating_point(spec, load)
        flow = float(point["main_steam_flow"]) * min(rng.uniform(0.97, 1.03), 1.0 / load)
        rows.append({
            "load_fraction": load,
            "main_steam_pressure": float(point["main_steam_pressure"]) * rng.uniform(0.96, 1.04),
            "main_steam_temperature": float(point["main_steam_temperature"])
            + rng.uniform(-8.0, 8.0),
            "main_steam_flow": flow,
            "hp_exhaust_pressure": spec.design.hp_exhaust_pressure * flow
            / spec.design.main_steam_flow,
        })
    return pd.DataFrame(rows)


def print_errors(label: str, summary: dict[str, float]) -> None:
    print(f"   {label}: max abs total {summary['max_total']:.3f} K (projection "
          f"{summary['max_projection']:.3f} K, interpolation {summary['max_interpolation']:.3f} "
          f"K); relative total max {summary['max_relative_total']:.2%}, mean "
          f"{summary['mean_relative_total']:.2%}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="bench-rom-"))
    out.mkdir(parents=True, exist_ok=True)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}")
    spec = load_spec("reference")
    model = FullOrderModel(spec)
    _ = model.design_
    mesh = blade_volume_mesh(spec, "hp1")

    print("\n1. build (32 snapshots, default mesh, defaults of steamtwin rom build)")
    start = time.perf_counter()
    bundle, snapshots = build_rom(spec, mesh, n_snapshots=32, max_workers=args.workers)
    build_s = time.perf_counter() - start
    rom = bundle.rom
    path = save_rom(bundle, out / "rom.npz")
    start = time.perf_counter()
    load_rom(path)
    load_s = time.perf_counter() - start
    print(f"   {mesh.points.shape[0]} nodes; build {build_s:.1f} s with {args.workers} "
          f"workers; file {path.stat().st_size / 1e6:.1f} MB, load {load_s:.2f} s")
    print(f"   field range over the snapshots {rom.field_range_:.2f} K; singular values "
          f"{np.array2string(rom.singular_values_[:6], precision=3)}")
    print(f"   modes {rom.n_modes_} (energy {rom.energy} → captured {rom.energy_captured_:.7f}, "
          f"projection tolerance {rom.projection_tolerance} K); RBF inputs "
          f"{', '.join(rom.feature_names_)}")
    features = rom.features_
    start = time.perf_counter()
    type(features)(spec).fit(snapshots.rom_inputs())
    print(f"   feature table {features.table_.shape[:3]} nodes: fit "
          f"{time.perf_counter() - start:.2f} s")

    print("\n2. errors")
    held = generate_snapshots(spec, mesh, held_out_conditions(spec, 24, seed=11),
                              max_workers=args.workers)
    x, c = snapshots.fields, snapshots.rom_inputs()
    report = rom_errors(rom, held.fields, held.rom_inputs())
    summary = report.summary()
    print_errors(f"DEFAULTS held-out ({len(held.fields)} conditions)", summary)
    print_errors("DEFAULTS leave-one-out (32)", leave_one_out(rom, x, c).summary())
    passed = summary["max_total"] <= 2.0 and summary["max_relative_total"] <= 0.01
    print(f"   criterion (≤ 2 K and ≤ 1 % of {rom.field_range_:.2f} K = "
          f"{0.01 * rom.field_range_:.3f} K): {'met' if passed else 'NOT met'}")
    worst = int(report.table["total"].idxmax())
    in_hull = report.table["extrapolation_distance"] == 0
    print(f"   held-out inside the snapshots' hull: {int(in_hull.sum())} of {len(in_hull)}; "
          f"their max abs total {report.table.loc[in_hull, 'total'].max():.3f} K")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        sensors = rom.predict_sensors(held.rom_inputs())
    column = list(rom.sensor_names_).index("control_stage_temperature")
    print(f"   control_stage_temperature sensor, held-out max abs "
          f"{np.abs(sensors[:, column] - held.sensors['control_stage_temperature']).max():.3f} K")
    print("   plain RBF on (p0, T0, p1), for comparison:")
    for energy in (0.992, 0.99999):
        model_e = PodRbfRom(energy=energy).fit(x, c, ROM_INPUTS)
        print(f"   energy {energy}: {model_e.n_modes_} mode(s), captured "
              f"{model_e.energy_captured_:.7f}")
        report = rom_errors(model_e, held.fields, held.rom_inputs())
        print_errors(f"held-out ({len(held.fields)} conditions)", report.summary())
        print_errors("leave-one-out (32)", leave_one_out(model_e, x, c).summary())

    print("\n3. one reconstruction, N = 200k, r = 10")
    rng = np.random.default_rng(0)
    n_nodes = 200_000
    modes, _ = np.linalg.qr(rng.standard_normal((n_nodes, 10)))
    synthetic = 750.0 + (rng.standard_normal((32, 10)) * np.logspace(2, -2, 10)) @ modes.T
    big = PodRbfRom(energy=1.0, max_modes=10, input_scaling="range",
                    features=features).fit(synthetic, c)
    query = c.mean(axis=0)
    big.predict(query)
    times = []
    for _ in range(500):
        start = time.perf_counter()
        big.predict(query)
        times.append(time.perf_counter() - start)
    print(f"   predict (features + RBF map + extrapolation check + reconstruction), r = "
          f"{big.n_modes_}: "
          f"median {np.median(times) * 1e3:.3f} ms, 90th percentile "
          f"{np.percentile(times, 90) * 1e3:.3f} ms")

    print("\n4. sensor predictions for a 7 200-sample series")
    load = ramp_profile(1.0, 0.3, 0.05, 600.0, 7200 - 600 - 840 - 1.0)
    inputs = load_profile_inputs(spec, load)
    signals = inputs.join(model.simulate(inputs)[["control_stage_pressure"]])
    times = []
    for _ in range(7):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ExtrapolationWarning)
            start = time.perf_counter()
            series = predict_series(bundle, signals)
            times.append(time.perf_counter() - start)
    print(f"   {len(series.sensors)} samples, {series.sensors.shape[1]} columns: median "
          f"{np.median(times) * 1e3:.1f} ms; extrapolated samples "
          f"{int(series.sensors['rom_extrapolated'].sum())}")

    print("\n5. POD-RBF vs DMD, 5 %/min ramp 100 → 50 % between 10-min holds (10-s steps)")
    start = time.perf_counter()
    transient = ramp_transient(spec, mesh, start_load=1.0, end_load=0.5, rate=0.05,
                               hold_s=600.0, step_s=10.0)
    print(f"   transient FOM + FEM: {transient.fields.shape[0]} steps in "
          f"{time.perf_counter() - start:.1f} s")
    summary = compare_rom_and_dmd(transient, rom).summary
    print(f"   POD-RBF defaults ({rom.n_modes_} modes, physics features):")
    print(summary.to_string(float_format=lambda v: f"{v:.4f}"))
    for energy in (0.992, 0.99999):
        model_e = PodRbfRom(energy=energy).fit(x, c, ROM_INPUTS)
        summary = compare_rom_and_dmd(transient, model_e).summary
        print(f"   POD-RBF plain (p0, T0, p1), energy {energy} ({model_e.n_modes_} modes):")
        print(summary.to_string(float_format=lambda v: f"{v:.4f}"))

    print("\n6. Figure 9 analogue")
    rom_field = rom.predict(held.rom_inputs()[worst])
    figure = field_comparison_figure(mesh, held.fields[worst], rom_field, out / "figure9.png",
                                     f"held-out load {held.conditions['load_fraction'][worst]:.0%}")
    print(f"   wrote {figure} (worst held-out condition of the default ROM)")


if __name__ == "__main__":
    main()
