"""Rotor ROM vs full FEM acceptance (issue 23 "What must hold"): temperature and groove stress
on a 5 %/min ramp 100 → 30 → 100 % and on the virtual plant's ``day``; ROM step and 24-h
record times; the FEM's 24-h transient at 1-s boundary conditions timed.

1. ``RotorModel(reference spec).fit()`` — mesh ``--size`` (m), training ramps at 2 and 8 %/min
   (10-s steps), FOM → steam side → full-order snapshots → POD–Galerkin ROM + strain DEIM.
2. Ramp: 300-s hold at 100 %, 5 %/min down to 30 %, 1-h hold, 5 %/min back, 1-h hold, at 1-s
   steps (``operating.ramp_profile``/``load_profile_inputs``; 5 %/min is not a training rate).
3. Day: ``dcs.plant.run_plant("day")``'s true boundary conditions (the canonical FOM inputs, as
   the plant had them, 86 400 1-s samples), the reference spec's steam side.
For each: the ROM batch run against the FEM (``RotorConduction.transient_frame``: properties
per element, lagged, the Dittus–Boelter cooling factor applied) — temperatures every step;
stresses by a full thermo-elastic solve (E, ν at every quadrature point) every
``--stress-every`` steps (a solve costs ~0.1 s, so every step of a day would take hours), and
by the stress operator (nodal thermal strain exact, E/(1−ν) at the mean) at the same steps to
separate the ROM's error from the operator's. Errors are max |ROM − FEM| over the compared steps,
the stress error as a fraction of the FEM's range of that quantity over the run.

Run: python benchmarks/bench_rotor_acceptance.py [--size 0.03] [--stress-every 10]
     [--day-stress-every 60] [--skip-day] [--skip-ramp] [--out bench-rotor-acceptance.json]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.dcs.plant import run_plant
from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.rotor.conduction import htc_column, steam_temperature_column
from steamtwin.rotor.model import LOCATIONS, RotorModel
from steamtwin.rotor.stress_points import COMPONENTS, StressState, equivalent_stress
from steamtwin.spec import load_spec

FOM_INPUTS = ("main_steam_pressure", "main_steam_temperature", "main_steam_flow",
              "hp_exhaust_pressure")
COMPARED = ("axial", "hoop", "von_mises", "equivalent")


class Clock:
    """Wall and CPU seconds of a block."""

    def __enter__(self) -> Clock:
        self.wall, self.cpu = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *_: object) -> None:
        self.wall = time.perf_counter() - self.wall
        self.cpu = time.process_time() - self.cpu


def stress_table(state: StressState, directions: np.ndarray) -> dict[str, np.ndarray]:
    """(samples, locations) arrays of the compared quantities; the equivalent stress along
    each location's direction (``RotorModel.equivalent_directions_``)."""
    equivalent = np.column_stack([
        equivalent_stress(StressState(*(getattr(state, c)[:, p] for c in COMPONENTS)),
                          directions[p]) for p in range(len(directions))])
    return {"axial": state.axial, "hoop": state.hoop, "von_mises": state.von_mises,
            "equivalent": equivalent}


def compare(model: RotorModel, steam: pd.DataFrame, every: int, label: str) -> dict:
    """ROM vs FEM over one steam-side record (module docstring)."""
    with Clock() as rom_clock:
        rom = model.simulate_steam(steam).frame
    first = steam.iloc[0]
    initial = model.conduction_.steady([first[htc_column(g)] for g in model.groups_],
                                       [first[steam_temperature_column(g)]
                                        for g in model.groups_])
    with Clock() as fem_clock:
        fem = model.conduction_.transient_frame(initial, steam, probes=model.critical_nodes_,
                                                snapshot_every=every)
    points = [model.critical_points[name] for name in LOCATIONS]
    with Clock() as solve_clock:
        solved = [model.elasticity_.stress(model.elasticity_.solve(field, model.speed_), points)
                  for field in fem.snapshots]
    full = StressState(*(np.array([getattr(s, c) for s in solved]) for c in COMPONENTS))
    operator = model.stress_operator_(fem.snapshots, model.speed_)
    rows = np.arange(0, len(steam), every)
    result = {"label": label, "samples": len(steam), "stress_rows": int(rows.size),
              "rom_wall_s": rom_clock.wall, "rom_cpu_s": rom_clock.cpu,
              "fem_wall_s": fem_clock.wall, "fem_cpu_s": fem_clock.cpu,
              "fem_ms_per_step_cpu": 1e3 * fem_clock.cpu / (len(steam) - 1),
              "stress_solves_wall_s": solve_clock.wall, "stress_solves_cpu_s": solve_clock.cpu}
    for name in LOCATIONS:
        error = np.abs(rom[f"{name}_temperature"].to_numpy() - fem.probes[name].to_numpy())
        result[f"{name}_temperature_error_k"] = float(error.max())
        result[f"{name}_temperature_range_k"] = float(np.ptp(fem.probes[name].to_numpy()))
    for reference_name, reference in (("full", full), ("operator", operator)):
        table = stress_table(reference, model.equivalent_directions_)
        for p, name in enumerate(LOCATIONS):
            for quantity in COMPARED:
                values = table[quantity][:, p]
                span = float(np.ptp(values))
                error = float(np.max(np.abs(rom[f"{name}_{quantity}"].to_numpy()[rows] - values)))
                key = f"{name}_{quantity}_vs_{reference_name}"
                result[key + "_error_mpa"] = error / 1e6
                result[key + "_range_mpa"] = span / 1e6
                result[key + "_error_of_range"] = error / span if span > 0 else float("nan")
    full_table = stress_table(full, model.equivalent_directions_)
    operator_table = stress_table(operator, model.equivalent_directions_)
    span = float(np.ptp(full_table["equivalent"][:, 0]))
    result["groove_operator_vs_full_equivalent_of_range"] = float(
        np.max(np.abs(operator_table["equivalent"][:, 0] - full_table["equivalent"][:, 0]))
        / span)
    # the equivalent's range vs ASME VIII-2 §5.5.3.2's: von Mises of the component differences
    # between the instants of its largest and smallest value (the FEM's full solves)
    for p, name in enumerate(LOCATIONS):
        values = full_table["equivalent"][:, p]
        high, low = int(np.argmax(values)), int(np.argmin(values))
        difference = StressState(*(getattr(full, c)[high, p] - getattr(full, c)[low, p]
                                   for c in COMPONENTS))
        result[f"{name}_equivalent_range_over_asme_range"] = float(
            (values[high] - values[low]) / difference.von_mises)
    return result


def timings(model: RotorModel, steam: pd.DataFrame) -> dict:
    """Streaming step cost (ROM alone and the model's step with its frame row) and the
    24-h batch."""
    rom = model.rom_
    htc = np.ascontiguousarray(steam[[htc_column(g) for g in model.groups_]].to_numpy())
    temperature = np.ascontiguousarray(
        steam[[steam_temperature_column(g) for g in model.groups_]].to_numpy())
    state = rom.initial_state(htc[0], temperature[0])
    calls = min(20000, len(steam) - 1)
    rom.step(state, htc[1], temperature[1], 1.0)  # compile
    with Clock() as rom_step:
        for i in range(1, calls + 1):
            state = rom.step(state, htc[i], temperature[i], 1.0)
    rotor_state = model.initial_state(steam)
    records = steam.iloc[1:2001].to_dict("records")
    with Clock() as model_step:
        for row in records:
            rotor_state, _ = model.step(rotor_state, row, 1.0)
    batch = []
    for _ in range(3):
        with Clock() as clock:
            model.simulate_steam(steam)
        batch.append((clock.wall, clock.cpu))
    return {"rom_step_us_wall": 1e6 * rom_step.wall / calls,
            "rom_step_us_cpu": 1e6 * rom_step.cpu / calls,
            "model_step_us_wall": 1e6 * model_step.wall / len(records),
            "model_step_us_cpu": 1e6 * model_step.cpu / len(records),
            "batch_24h_wall_s": [w for w, _ in batch], "batch_24h_cpu_s": [c for _, c in batch]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=float, default=0.03)
    parser.add_argument("--stress-every", type=int, default=10)
    parser.add_argument("--day-stress-every", type=int, default=60)
    parser.add_argument("--skip-day", action="store_true")
    parser.add_argument("--skip-ramp", action="store_true")
    parser.add_argument("--out", type=Path, default=Path("bench-rotor-acceptance.json"))
    arguments = parser.parse_args()
    spec = load_spec("reference")
    report: dict[str, object] = {"load_average_start": os.getloadavg()}
    with Clock() as fit:
        model = RotorModel(spec, mesh_size=arguments.size).fit()
    report["fit"] = {"wall_s": fit.wall, "cpu_s": fit.cpu, "nodes": int(model.mesh_.p.shape[1]),
                     "modes": int(model.rom_.n_modes_),
                     "strain_nodes": int(model.strain_nodes_.size),
                     "reference_temperatures_k": model.reference_temperatures_.tolist()}
    print(json.dumps(report["fit"]))
    load = np.concatenate([ramp_profile(1.0, 0.3, 0.05, 300.0, 3600.0),
                           ramp_profile(0.3, 1.0, 0.05, 0.0, 3600.0)[1:]])
    ramp_steam = model.steam_side(load_profile_inputs(spec, load))
    if not arguments.skip_ramp:
        report["ramp"] = compare(model, ramp_steam, arguments.stress_every, "5 %/min ramp")
        print(json.dumps(report["ramp"]))
    if not arguments.skip_day:
        with Clock() as plant:
            day = run_plant("day", random_state=0)
        inputs = day.true_inputs[list(FOM_INPUTS)]
        with Clock() as side:
            day_steam = model.steam_side(inputs)
        report["day_inputs"] = {"plant_wall_s": plant.wall, "steam_side_wall_s": side.wall,
                                "steam_side_cpu_s": side.cpu}
        report["day_timings"] = timings(model, day_steam)
        print(json.dumps(report["day_timings"]))
        report["day"] = compare(model, day_steam, arguments.day_stress_every, "plant day")
        print(json.dumps(report["day"]))
    report["load_average_end"] = os.getloadavg()
    arguments.out.write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
