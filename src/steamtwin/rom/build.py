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
from collections.abc import Mapping
from importlib import metadata
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.blade.mesh import checked_mesh
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters
from steamtwin.progress import ProgressCallback
from steamtwin.rom.envelope import (
    OperatingEnvelope,
    feasible_conditions,
    observed_anchors,
    operating_envelope,
)
from steamtwin.rom.estimator import PodRbfRom
from steamtwin.rom.features import ControlStageFeatures
from steamtwin.rom.provenance import parameters_source, spec_provenance
from steamtwin.rom.reconstruction import MAX_EXTRAPOLATION
from steamtwin.rom.romfile import BladeRom, probe_nodes
from steamtwin.rom.snapshots import (
    FLOW_VARIATION,
    LOAD_LEVELS,
    MAXIMUM_FLOW_FRACTION,
    PRESSURE_VARIATION,
    ROM_INPUTS,
    TEMPERATURE_VARIATION,
    SnapshotSet,
    design_conditions,
    generate_snapshots,
)
from steamtwin.spec import TurbineSpec


def rom_envelope(spec: TurbineSpec, params: ModelParameters | None = None, *,
                 parameter_intervals: Mapping[str, tuple[float, float]] | None = None,
                 observed: pd.DataFrame | None = None, params_source: str | None = None,
                 model: FullOrderModel | None = None) -> OperatingEnvelope:
    """The envelope :func:`build_rom` plans its snapshots in: the design's load levels and
    variations (:mod:`steamtwin.rom.snapshots`), widened as in
    :func:`~steamtwin.rom.envelope.operating_envelope`."""
    return operating_envelope(
        spec, params, loads=LOAD_LEVELS, pressure_variation=PRESSURE_VARIATION,
        temperature_variation=TEMPERATURE_VARIATION, flow_variation=FLOW_VARIATION,
        maximum_flow_fraction=MAXIMUM_FLOW_FRACTION, parameter_intervals=parameter_intervals,
        observed=observed, params_source=params_source, model=model)


def build_rom(spec: TurbineSpec, mesh: object, params: ModelParameters | None = None, *,
              n_snapshots: int = 32, energy: float = 0.992,
              kernel: str = "thin_plate_spline", max_workers: int | None = None,
              scheduler: str | None = None, random_state: int = 0,
              layout: str = "lhs",
              progress: ProgressCallback | None = None,
              projection_tolerance: float | None = 0.1, physics_features: bool = True,
              spec_toml: str | None = None, params_file: str | Path | None = None,
              parameter_intervals: Mapping[str, tuple[float, float]] | None = None,
              observed: pd.DataFrame | None = None
              ) -> tuple[BladeRom, SnapshotSet]:
    """Envelope → design of experiments → feasible conditions → snapshots (parallel) → fitted
    ROM with provenance.

    ``projection_tolerance`` (K, None = energy only) and ``physics_features`` (RBF on
    (p0, T0, p1, T_cs, e) with range scaling; False: on (p0, T0, p1) with sensitivity scaling)
    as in the module docstring. The ROM records ``spec`` (name and content hash) with its TOML
    text ``spec_toml`` (default: the built-in's text when ``spec`` is a built-in turbine) and
    ``params`` with the file they were read from, ``params_file``
    (:mod:`steamtwin.rom.provenance`), which errors name too.
    ``parameter_intervals`` (name → (low, high)) and ``observed`` (historian signals, SI, with
    the ROM's inputs) widen the envelope (:func:`steamtwin.rom.envelope.operating_envelope`).
    Observed samples outside the planned snapshots get anchor snapshots
    (:func:`~steamtwin.rom.envelope.observed_anchors`, up to 4 per load band, on top of
    ``n_snapshots``). Conditions the model cannot run are replaced and counted (provenance
    ``envelope.replaced``); :class:`~steamtwin.rom.envelope.EnvelopeError` when the
    operating line itself cannot be run.
    """
    spec_record, spec_text = spec_provenance(spec, spec_toml)
    params = params or ModelParameters()
    mesh = checked_mesh(mesh)
    params_source = str(params_file) if params_file is not None else None
    model = FullOrderModel(spec)
    envelope = rom_envelope(spec, params, parameter_intervals=parameter_intervals,
                            observed=observed, params_source=params_source, model=model)
    planned = design_conditions(spec, n_snapshots, random_state=random_state, layout=layout,
                                envelope=envelope)
    conditions, replaced = feasible_conditions(spec, planned, params,
                                               params_source=params_source, model=model)
    anchors = observed_anchors(spec, envelope, conditions, params, model=model)
    if len(anchors):
        anchors, moved = feasible_conditions(spec, anchors, params,
                                             params_source=params_source, model=model)
        replaced = pd.concat([replaced, moved.assign(row=moved["row"] + len(conditions))],
                             ignore_index=True)
        conditions = pd.concat([conditions, anchors], ignore_index=True)
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
        "design": {"n_snapshots": n_snapshots, "seed": random_state, "layout": layout,
                   "load_levels": sorted({float(v) for v in conditions["load_level"]})},
        "envelope": {**envelope.describe(), "replaced": len(replaced),
                     "observed_anchors": len(anchors),
                     "replacements": [{"row": int(r.row), "reason": r.reason,
                                       "flow_before_kg_s": r.flow_before,
                                       "flow_after_kg_s": r.flow_after}
                                      for r in replaced.itertuples()],
                     "observed": _observed_coverage(rom, observed)},
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


def _observed_coverage(rom: PodRbfRom, observed: pd.DataFrame | None) -> dict[str, float] | None:
    """How many observed samples (finite ROM inputs) lie outside the snapshots' hull, and
    farther than the predict limit (:data:`~steamtwin.rom.reconstruction.MAX_EXTRAPOLATION`)."""
    if observed is None:
        return None
    inputs = observed[list(ROM_INPUTS)].apply(pd.to_numeric, errors="coerce").to_numpy(
        dtype=float)
    inputs = inputs[np.all(np.isfinite(inputs), axis=1)]
    if inputs.shape[0] == 0:
        return {"samples": 0}
    distance = rom.extrapolation_distance(inputs)
    return {"samples": int(inputs.shape[0]),
            "outside_hull": int(np.sum(distance > 0.0)),
            "beyond_limit": int(np.sum(distance > MAX_EXTRAPOLATION)),
            "max_distance": float(distance.max())}
