"""Rotor conduction FEM (issue 23, item 1): mesh size and cost per 1-s step, so that the 24-h
FEM reference run at 1-s boundary conditions the issue asks for is known to be feasible.

The reference spec's ``[rotor]`` section meshed at ``--size`` (m, far from the groove; groove
radius / 6 at it), steam-side conditions from the full-order model (``rotor.steam_side``,
default parameters) on a 5 %/min ramp 100 → 30 % load, a hold and back, then the implicit-Euler
transient (``RotorConduction.transient``) at 1-s steps. The htc changes every step, so every
step assembles and factorises anew: the per-step figure is the full cost. Material: a CrMoV
steel whose k and c vary linearly with temperature (magnitudes of ASME II-D Table TCD, Group C),
standing in for the life helper's 30CrMoNiV5-11 tables. Prints nodes, elements, seconds per
step (wall and CPU), the extrapolated 24-h time, and the groove-root − bore temperature
difference's extremes.

Run: python benchmarks/bench_rotor_conduction.py [--size 0.03] [--hours 1.0]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import numpy as np

from steamtwin.model.fom import FullOrderModel
from steamtwin.model.operating import load_profile_inputs
from steamtwin.rotor.conduction import RotorConduction
from steamtwin.rotor.geometry import critical_nodes, rotor_geometry, rotor_mesh
from steamtwin.rotor.steam_side import steam_side
from steamtwin.spec import load_spec


@dataclass(frozen=True)
class LinearCrMoV:
    """k = 38 − 0.01·(T − 293 K) W/(m·K), c = 450 + 0.35·(T − 293 K) J/(kg·K), ρ = 7850."""

    name: str = "linear CrMoV"

    def density(self) -> float:
        return 7850.0

    def specific_heat(self, temperature):
        return 450.0 + 0.35 * (np.asarray(temperature) - 293.15)

    def conductivity(self, temperature):
        return 38.0 - 0.01 * (np.asarray(temperature) - 293.15)

    def youngs_modulus(self, temperature):
        return np.full(np.shape(temperature), 2.1e11)

    def poisson_ratio(self, temperature):
        return np.full(np.shape(temperature), 0.3)

    def thermal_strain(self, temperature):
        return 1.25e-5 * (np.asarray(temperature) - 293.15)


def ramp(hours: float) -> np.ndarray:
    """Load fraction at 1-s samples: 100 %, down at 5 %/min to 30 %, hold, back up, hold."""
    seconds = int(hours * 3600)
    t = np.arange(seconds + 1.0)
    down = np.clip(1.0 - 0.05 / 60.0 * (t - 300.0), 0.3, 1.0)
    up = np.clip(0.3 + 0.05 / 60.0 * (t - seconds / 2.0), 0.3, 1.0)
    return np.where(t < seconds / 2.0, down, up)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=float, default=0.03)
    parser.add_argument("--hours", type=float, default=1.0)
    arguments = parser.parse_args()
    spec = load_spec("reference")
    geometry = rotor_geometry(spec)
    started = time.perf_counter()
    mesh = rotor_mesh(geometry, arguments.size)
    print(f"mesh: {mesh.p.shape[1]} nodes, {mesh.t.shape[1]} triangles "
          f"({time.perf_counter() - started:.2f} s)")
    inputs = load_profile_inputs(spec, ramp(arguments.hours))
    fom = FullOrderModel(spec)
    _ = fom.design_
    started, cpu = time.perf_counter(), time.process_time()
    frame = steam_side(fom, inputs, groups=list(geometry.groups))
    print(f"steam side over {len(frame)} samples: {time.perf_counter() - started:.2f} s wall, "
          f"{time.process_time() - cpu:.2f} s CPU")
    conduction = RotorConduction(mesh, LinearCrMoV(), geometry.groups)
    first = frame.iloc[0]
    initial = conduction.steady([first[f"htc:{g}"] for g in geometry.groups],
                                [first[f"steam_temperature:{g}"] for g in geometry.groups])
    probes = critical_nodes(mesh, geometry)
    started, cpu = time.perf_counter(), time.process_time()
    run = conduction.transient_frame(initial, frame, probes=probes)
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu
    steps = len(frame) - 1
    print(f"transient: {steps} steps, {1e3 * wall / steps:.2f} ms/step wall, "
          f"{1e3 * cpu / steps:.2f} ms/step CPU -> 24 h at 1 s: {86400 * wall / steps / 60:.1f} "
          f"min wall, {86400 * cpu / steps / 60:.1f} min CPU")
    difference = run.probes["groove_root"] - run.probes["bore"]
    supplied = run.heat_in[1:] * np.diff(run.times)
    balance = np.max(np.abs(supplied - run.stored[1:])) / np.abs(supplied).max()
    print(f"groove root − axis: {difference.min():+.1f} … {difference.max():+.1f} K; "
          f"energy balance (implicit Euler, 1-s steps): max |Q_in − ΔE| / max |Q_in| = "
          f"{balance:.1e}")


if __name__ == "__main__":
    main()
