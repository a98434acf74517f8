"""From a turbine and its blade mesh to a ROM: design, snapshots, POD + RBF, provenance.

Defaults (docs/rom.md): POD energy 0.992 plus modes until no snapshot's projection error exceeds
``projection_tolerance`` = 0.1 K (a fifth of the 1 % accuracy budget: the energy threshold alone
keeps one mode on the reference blade, 2.5 K projection error), and the RBF on the governing
stage's physics features (:class:`~steamtwin.rom.features.ControlStageFeatures`, tabulated with
the FOM at the snapshots' parameters), each scaled to [0, 1] over the snapshots.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import platform
from collections.abc import Callable
from importlib import metadata
from pathlib import Path

from steamtwin.blade.mesh import checked_mesh
from steamtwin.model.parameters import ModelParameters
from steamtwin.rom.estimator import PodRbfRom
from steamtwin.rom.features import ControlStageFeatures
from steamtwin.rom.provenance import parameters_source, spec_provenance
from steamtwin.rom.romfile import BladeRom, probe_nodes
from steamtwin.rom.snapshots import (
    ROM_INPUTS,
    SnapshotSet,
    design_conditions,
    generate_snapshots,
)
from steamtwin.spec import TurbineSpec


def build_rom(spec: TurbineSpec, mesh: object, params: ModelParameters | None = None, *,
              n_snapshots: int = 32, energy: float = 0.992,
              kernel: str = "thin_plate_spline", max_workers: int | None = None,
              scheduler: str | None = None, seed: int = 0, layout: str = "lhs",
              progress: Callable[[float], None] | None = None,
              projection_tolerance: float | None = 0.1, physics_features: bool = True,
              spec_toml: str | None = None, params_file: str | Path | None = None
              ) -> tuple[BladeRom, SnapshotSet]:
    """Design of experiments → snapshots (parallel) → fitted ROM with provenance.

    ``projection_tolerance`` (K, None = energy only) and ``physics_features`` (RBF on
    (p0, T0, p1, T_cs, e) with range scaling; False: on (p0, T0, p1) with sensitivity scaling)
    as in the module docstring. The ROM records ``spec`` (name and content hash) with its TOML
    text ``spec_toml`` (default: the built-in's text when ``spec`` is a built-in turbine) and
    ``params`` with the file they were read from, ``params_file``
    (:mod:`steamtwin.rom.provenance`).
    """
    spec_record, spec_text = spec_provenance(spec, spec_toml)
    params = params or ModelParameters()
    mesh = checked_mesh(mesh)
    conditions = design_conditions(spec, n_snapshots, seed=seed, layout=layout)
    snapshots = generate_snapshots(spec, mesh, conditions, params, max_workers=max_workers,
                                   scheduler=scheduler, progress=progress)
    sensor_names = tuple(snapshots.sensors.columns)
    features = ControlStageFeatures(spec, params) if physics_features else None
    rom = PodRbfRom(energy=energy, kernel=kernel, projection_tolerance=projection_tolerance,
                    features=features,
                    input_scaling="range" if physics_features else "sensitivity").fit(
        snapshots.fields, snapshots.rom_inputs(ROM_INPUTS), input_names=ROM_INPUTS,
        sensors=snapshots.sensors.to_numpy(dtype=float), sensor_names=sensor_names)
    try:
        version = metadata.version("steamtwin")
    except metadata.PackageNotFoundError:
        version = "unknown"
    provenance = {
        "created_utc": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
        "steamtwin_version": version,
        "python": platform.python_version(),
        "turbine": spec.name,
        "turbine_description": spec.description,
        "spec": spec_record,
        "parameters_source": parameters_source(params_file),
        "blade_row": "control stage rotor (hp1)",
        "model_parameters": dataclasses.asdict(params),
        "design": {"n_snapshots": n_snapshots, "seed": seed, "layout": layout,
                   "load_levels": sorted({float(v) for v in conditions["load_level"]})},
        "mesh": {"nodes": int(mesh.points.shape[0]), "tetrahedra": int(mesh.tetrahedra.shape[0])},
        "pod": {"energy_threshold": energy, "projection_tolerance_K": projection_tolerance,
                "modes": rom.n_modes_, "energy_captured": rom.energy_captured_},
        "rbf": {"kernel": kernel, "inputs": list(ROM_INPUTS),
                "features": features.describe() if features is not None else None,
                "input_scaling": rom.input_scaling},
        "units": "SI (K, Pa, kg/s, W)",
    }
    bundle = BladeRom(rom=rom, mesh=mesh, probes=probe_nodes(mesh),
                      conditions=snapshots.conditions, provenance=provenance,
                      spec_toml=spec_text)
    return bundle, snapshots
