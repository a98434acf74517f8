"""Blade geometry: parametric ground truth, scans, reconstruction, assembly and meshes.

The modules follow the chain (docs/architecture.md, "The geometry package by pipeline step"):
ground truth (:mod:`.pritchard`, :mod:`.row_sizing`, :mod:`.ip_rows`, :mod:`.profile`), scan
(:mod:`.scanner`, :mod:`.pointcloud`, :mod:`.mesh_io`), rigid motions (:mod:`.rigid`),
preprocessing (:mod:`.filters`, :mod:`.targets`, :mod:`.registration`, :mod:`.multiview`,
:mod:`.preprocess`), segmentation, surface fitting (:mod:`.reconstruct`), reports
(:mod:`.fidelity`, :mod:`.row_metrics`, :mod:`.reconstruction_report`), meshes
(:mod:`.volume_mesh`, :mod:`.meshing`) and the chain as a user runs it (:mod:`.workflow`).
Here: the blade, its volume mesh and their errors, and (imported on first use) the chain's
steps as a user runs them: :func:`scan_row`, :func:`preprocess_scan`, :func:`load_cloud`,
:func:`reconstruct_cloud`, :func:`write_blade_stl`, :func:`report_reconstruction`,
:func:`reconstruct_source`.
"""

from steamtwin.geometry.meshing import MeshQuality, blade_volume_mesh, mesh_quality
from steamtwin.geometry.pritchard import GeometryError
from steamtwin.geometry.profile import Blade, make_blade, row_design
from steamtwin.geometry.volume_mesh import (
    REGIONS,
    MeshError,
    VolumeMesh,
    read_volume_mesh,
    write_volume_mesh,
)
from steamtwin.lazy import lazy_exports

_WORKFLOW = ("scan_row", "preprocess_scan", "load_cloud", "reconstruct_cloud", "write_blade_stl",
             "report_reconstruction", "reconstruct_source")
_EXPORTS = dict.fromkeys(_WORKFLOW, "steamtwin.geometry.workflow")

__all__ = [
    *_WORKFLOW,
    "REGIONS",
    "Blade",
    "GeometryError",
    "MeshError",
    "MeshQuality",
    "VolumeMesh",
    "blade_volume_mesh",
    "make_blade",
    "mesh_quality",
    "read_volume_mesh",
    "row_design",
    "write_volume_mesh",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
