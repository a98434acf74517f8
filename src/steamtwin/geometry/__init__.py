"""Blade geometry: parametric ground truth, scans, reconstruction, assembly and meshes.

- :mod:`~steamtwin.geometry.profile`: Pritchard blade sections, rows sized from the spec, blades.
- :mod:`~steamtwin.geometry.volume_mesh`: the tetrahedral :class:`VolumeMesh` and its files.
- :mod:`~steamtwin.geometry.meshing`: gmsh/HXT blade meshes and their quality.

Submodules with heavy dependencies (open3d) are not imported here.
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

__all__ = [
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
