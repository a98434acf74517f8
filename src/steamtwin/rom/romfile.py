"""The ROM file: one self-describing ``.npz`` (no pickles) with modes, map, mesh and sensors.

Arrays (SI units): ``modes`` (r, N), ``mean`` (N,), ``singular_values``, ``coefficients``
(m, r), ``centres`` (m, k) scaled RBF inputs of the snapshots, ``input_points`` (m, d) their
scaled conditions, ``sensor_values`` (m, s), ``input_min``/``input_span``/``input_weights``
(d,), ``feature_names``/``feature_min``/``feature_span``/``feature_weights`` (k,) of the RBF
inputs, the physics-feature table (``feature_pressure_nodes``, ``feature_temperature_nodes``,
``feature_flow_ratio_nodes``, ``feature_table``; empty without features, see
:mod:`steamtwin.rom.features`), ``snapshot_conditions`` (m, c) with
``condition_names``, the mesh (``points``, ``tetrahedra``, ``boundary_triangles``,
``boundary_regions``, ``region_names``), the sensor layout (``sensor_names`` steam-path signals,
``probe_names``/``probe_nodes`` blade nodes), the RBF settings, ``format_version``,
``provenance`` (a JSON string; its ``spec`` and ``model_parameters`` say which turbine and
parameters the ROM was built from, :mod:`steamtwin.rom.provenance`) and ``spec_toml`` (the
spec's TOML text, "" when not known). :func:`load_rom` reads with ``allow_pickle=False`` and
checks every key, dtype, shape and the version before building the model. Format 2 files
(before ``spec_toml`` and the spec record) are still read; they carry no spec to check.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from steamtwin.blade.mesh import REGIONS, MeshError, SolidMesh, checked_mesh
from steamtwin.errors import RomError
from steamtwin.rom.estimator import PodRbfRom, text_array
from steamtwin.rom.features import FEATURE_NAMES

FORMAT = "steamtwin-pod-rbf-rom"
FORMAT_VERSION = 3  # 2: physics features, input_points, projection_tolerance; 3: spec_toml
READABLE_VERSIONS = (2, 3)


class RomFileError(RomError):
    """A ROM file is unreadable, corrupt, of another version or inconsistent."""


@dataclass
class BladeRom:
    """A fitted :class:`PodRbfRom` with its mesh, sensor layout and provenance.

    ``probes`` maps blade probe names to node indices; ``conditions`` holds the snapshots'
    conditions (SI), ``provenance`` how the ROM was made (JSON-serialisable) and ``spec_toml``
    the TOML text of the turbine it was built from ("" when not known).
    """

    rom: PodRbfRom
    mesh: SolidMesh
    probes: dict[str, int]
    conditions: pd.DataFrame
    provenance: dict[str, Any] = field(default_factory=dict)
    spec_toml: str = ""

    @property
    def sensor_names(self) -> tuple[str, ...]:
        """Steam-path sensors the ROM predicts (canonical names, SI)."""
        return self.rom.sensor_names_


def probe_nodes(mesh: SolidMesh) -> dict[str, int]:
    """Virtual blade thermocouples: per region, the boundary node nearest its area centroid."""
    probes = {}
    points = mesh.points
    for index, name in enumerate(REGIONS):
        triangles = mesh.boundary_triangles[mesh.boundary_regions == index]
        if triangles.size == 0:
            continue
        corners = points[triangles]
        area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
                                             corners[:, 2] - corners[:, 0]), axis=1)
        centroid = (area[:, None] * corners.mean(axis=1)).sum(axis=0) / area.sum()
        nodes = np.unique(triangles)
        probes[f"blade_{name}"] = int(nodes[np.argmin(np.linalg.norm(points[nodes] - centroid,
                                                                     axis=1))])
    return probes


def save_rom(bundle: BladeRom, path: str | Path) -> Path:
    """Write ``bundle`` to ``path`` (``.npz``, compressed); returns the path written."""
    rom = bundle.rom
    path = Path(path)
    conditions = bundle.conditions.select_dtypes("number")
    arrays = {
        "format": np.array(FORMAT),
        "format_version": np.array(FORMAT_VERSION, dtype=np.int64),
        **rom.get_state(),
        "points": bundle.mesh.points, "tetrahedra": bundle.mesh.tetrahedra,
        "boundary_triangles": bundle.mesh.boundary_triangles,
        "boundary_regions": bundle.mesh.boundary_regions,
        "region_names": text_array(REGIONS),
        "probe_names": text_array(list(bundle.probes)),
        "probe_nodes": np.array(list(bundle.probes.values()), dtype=np.int64),
        "snapshot_conditions": conditions.to_numpy(dtype=float),
        "condition_names": text_array(list(conditions.columns)),
        "provenance": np.array(json.dumps(bundle.provenance, sort_keys=True, default=str)),
        "spec_toml": np.array(bundle.spec_toml, dtype=np.str_),
    }
    with path.open("wb") as handle:
        np.savez_compressed(handle, **arrays)
    return path


_REQUIRED = {
    # name: (kind, ndim)   kind "f" float, "i" integer, "U" text
    "format": ("U", 0), "format_version": ("i", 0), "modes": ("f", 2), "mean": ("f", 1),
    "singular_values": ("f", 1), "coefficients": ("f", 2), "centres": ("f", 2),
    "sensor_values": ("f", 2), "sensor_names": ("U", 1), "input_names": ("U", 1),
    "input_min": ("f", 1), "input_span": ("f", 1), "input_weights": ("f", 1), "energy": ("f", 0),
    "energy_captured": ("f", 0), "field_range": ("f", 0), "kernel": ("U", 0),
    "smoothing": ("f", 0), "degree": ("i", 0), "epsilon": ("f", 0), "input_scaling": ("U", 0),
    "points": ("f", 2), "tetrahedra": ("i", 2), "boundary_triangles": ("i", 2),
    "boundary_regions": ("i", 1), "region_names": ("U", 1), "probe_names": ("U", 1),
    "probe_nodes": ("i", 1), "snapshot_conditions": ("f", 2), "condition_names": ("U", 1),
    "provenance": ("U", 0), "projection_tolerance": ("f", 0), "input_points": ("f", 2),
    "feature_names": ("U", 1), "feature_min": ("f", 1), "feature_span": ("f", 1),
    "feature_weights": ("f", 1), "feature_pressure_nodes": ("f", 1),
    "feature_temperature_nodes": ("f", 1), "feature_flow_ratio_nodes": ("f", 1),
    "feature_table": ("f", 4),
}


def _read_arrays(path: Path) -> dict[str, np.ndarray]:
    try:
        with np.load(path, allow_pickle=False) as archive:
            arrays = {name: archive[name] for name in archive.files}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as error:
        raise RomFileError(f"{path}: not a readable ROM file ({error})") from None
    if "format" not in arrays or arrays["format"].dtype.kind != "U" or str(
            arrays["format"]) != FORMAT:
        raise RomFileError(f"{path}: not a steamtwin ROM file (no format tag {FORMAT!r})")
    version = arrays.get("format_version")
    if version is None or version.dtype.kind not in "iu" or int(
            version) not in READABLE_VERSIONS:
        raise RomFileError(f"{path}: ROM format version {version!r} is not supported (this "
                           f"steamtwin reads versions {READABLE_VERSIONS}); rebuild the ROM")
    required = dict(_REQUIRED)
    if int(version) >= 3:
        required["spec_toml"] = ("U", 0)
    for name, (kind, ndim) in required.items():
        if name not in arrays:
            raise RomFileError(f"{path}: missing array {name!r}")
        array = arrays[name]
        kinds = {"f": "f", "i": "iu", "U": "U"}[kind]
        if array.dtype.kind not in kinds or array.ndim != ndim:
            raise RomFileError(f"{path}: array {name!r} has dtype {array.dtype} and {array.ndim} "
                               f"dimension(s), expected kind {kind!r} with {ndim}")
    return arrays


def _check_shapes(path: Path, a: dict[str, np.ndarray]) -> None:
    r, n = a["modes"].shape
    m, k = a["centres"].shape
    d = a["input_names"].size
    expected = {
        "mean": (n,), "coefficients": (m, r), "sensor_values": (m, a["sensor_names"].size),
        "input_min": (d,), "input_span": (d,), "input_weights": (d,), "input_points": (m, d),
        "feature_names": (k,), "feature_min": (k,), "feature_span": (k,),
        "feature_weights": (k,),
        "points": (n, 3), "probe_nodes": (a["probe_names"].size,),
        "snapshot_conditions": (m, a["condition_names"].size),
        "boundary_regions": (a["boundary_triangles"].shape[0],),
    }
    for name, shape in expected.items():
        if a[name].shape != shape:
            raise RomFileError(f"{path}: array {name!r} has shape {a[name].shape}, expected "
                               f"{shape} (modes {a['modes'].shape}, centres {(m, k)}, "
                               f"{d} inputs)")
    if a["singular_values"].size < r:
        raise RomFileError(f"{path}: fewer singular values than modes")
    if tuple(a["region_names"]) != REGIONS:
        raise RomFileError(f"{path}: region names {tuple(a['region_names'])} differ from "
                           f"{REGIONS}")
    if a["probe_nodes"].size and (a["probe_nodes"].min() < 0 or a["probe_nodes"].max() >= n):
        raise RomFileError(f"{path}: probe_nodes index nodes outside the mesh")
    numeric = ("modes", "mean", "coefficients", "centres", "sensor_values", "input_min",
               "input_span", "input_weights", "points", "input_points", "feature_min",
               "feature_span", "feature_weights", "feature_pressure_nodes",
               "feature_temperature_nodes", "feature_flow_ratio_nodes", "feature_table")
    for name in numeric:
        if not np.all(np.isfinite(a[name])):
            raise RomFileError(f"{path}: array {name!r} holds NaN or infinite values")
    if np.any(a["input_span"] <= 0) or np.any(a["input_weights"] <= 0) or np.any(
            a["feature_span"] <= 0) or np.any(a["feature_weights"] <= 0):
        raise RomFileError(f"{path}: input/feature spans and weights must be positive")
    if a["feature_table"].size == 0:
        same = {"feature_names": "input_names", "feature_min": "input_min",
                "feature_span": "input_span", "feature_weights": "input_weights",
                "centres": "input_points"}
        for name, twin in same.items():
            if a[name].shape != a[twin].shape or not np.array_equal(a[name], a[twin]):
                raise RomFileError(f"{path}: without a feature table {name!r} must equal "
                                   f"{twin!r}")
    elif tuple(a["feature_names"]) != FEATURE_NAMES:
        raise RomFileError(f"{path}: feature names {tuple(a['feature_names'])} differ from "
                           f"{FEATURE_NAMES}")
    gram = a["modes"] @ a["modes"].T
    if not np.allclose(gram, np.eye(r), atol=1e-6):
        raise RomFileError(f"{path}: the modes are not orthonormal (corrupt data)")


def load_rom(path: str | Path) -> BladeRom:
    """Read and validate a ROM file; raises :class:`RomFileError` saying what is wrong."""
    path = Path(path)
    a = _read_arrays(path)
    _check_shapes(path, a)
    try:
        provenance = json.loads(str(a["provenance"]))
    except json.JSONDecodeError as error:
        raise RomFileError(f"{path}: provenance is not valid JSON ({error})") from None
    try:
        rom = PodRbfRom.from_state(a)
        mesh = checked_mesh(SolidMesh(a["points"], a["tetrahedra"], a["boundary_triangles"],
                                      a["boundary_regions"]))
    except (ValueError, MeshError, np.linalg.LinAlgError) as error:
        raise RomFileError(f"{path}: inconsistent ROM data ({error})") from None
    conditions = pd.DataFrame(a["snapshot_conditions"], columns=list(a["condition_names"]))
    probes = {str(k): int(v) for k, v in zip(a["probe_names"], a["probe_nodes"], strict=True)}
    spec_toml = str(a["spec_toml"]) if "spec_toml" in a else ""
    return BladeRom(rom=rom, mesh=mesh, probes=probes, conditions=conditions,
                    provenance=provenance, spec_toml=spec_toml)
