"""Figure 9 analogue: the ROM's blade field next to the FOM's, with the error map (PNG).

Three panels show the blade's pressure-side surface seen from the pressure side: axial
position x (mm) against radius z (mm), leading edge left, root at the bottom. The field is drawn
as a surface — the mesh's own boundary triangles of that side, coloured by linear interpolation
of the nodal values across each triangle (Gouraud shading: the P1 finite-element field the
solver computed, Zienkiewicz, Taylor & Zhu, *The Finite Element Method*, 7th ed., §2.4) — not
as scattered nodes. The error panel uses a colour scale symmetric about zero (ROM − FOM).
Drawn on a bare :class:`matplotlib.figure.Figure` (Agg canvas, no pyplot state).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.tri import Triangulation

from steamtwin.blade.mesh import REGIONS, SolidMesh

__all__ = ["field_comparison_figure", "field_figure", "surface_triangulation"]

SURFACE_REGION = "pressure_side"
"""The boundary region the figure shows (its triangles project one-to-one onto x–z)."""


def surface_triangulation(mesh: SolidMesh, region: str = SURFACE_REGION
                          ) -> tuple[Triangulation, np.ndarray]:
    """The boundary triangles of ``region`` projected onto the x–z plane (mm), and the mesh
    node index of each triangulation vertex (so a nodal field ``f`` is drawn as ``f[nodes]``).

    The triangles are the mesh's own connectivity (``boundary_triangles`` whose
    ``boundary_regions`` is the region), renumbered onto the region's nodes.
    """
    if region not in REGIONS:
        raise ValueError(f"region {region!r} is not one of {list(REGIONS)}")
    triangles = np.asarray(mesh.boundary_triangles)[
        np.asarray(mesh.boundary_regions) == REGIONS.index(region)]
    if triangles.size == 0:
        raise ValueError(f"the mesh has no boundary triangle in region {region!r}")
    nodes, local = np.unique(triangles, return_inverse=True)
    points = np.asarray(mesh.points)[nodes] * 1e3
    return Triangulation(points[:, 0], points[:, 2], local.reshape(triangles.shape)), nodes


def field_figure(mesh: SolidMesh, fom_field: np.ndarray, rom_field: np.ndarray,
                 title: str = "") -> Figure:
    """The FOM | ROM | ROM − FOM figure of nodal fields (K) on the pressure-side surface,
    temperatures shown in °C, the error in K."""
    n = mesh.points.shape[0]
    fom = np.asarray(fom_field, dtype=float)
    rom = np.asarray(rom_field, dtype=float)
    if fom.shape != (n,) or rom.shape != (n,):
        raise ValueError(f"fields must have shape ({n},), got {fom.shape} and {rom.shape}")
    triangulation, nodes = surface_triangulation(mesh)
    error = rom[nodes] - fom[nodes]
    low = min(fom[nodes].min(), rom[nodes].min()) - 273.15
    high = max(fom[nodes].max(), rom[nodes].max()) - 273.15
    limit = max(float(np.abs(error).max()), 1e-6)
    figure = Figure(figsize=(13.0, 4.2), layout="constrained")
    axes = figure.subplots(1, 3, sharey=True)
    panels = (
        (fom[nodes] - 273.15, "FOM (FEM)", "inferno", low, high, "T [°C]"),
        (rom[nodes] - 273.15, "ROM (POD–RBF)", "inferno", low, high, "T [°C]"),
        (error, "ROM − FOM", "coolwarm", -limit, limit, "error [K]"),
    )
    for axis, (values, label, cmap, vmin, vmax, unit) in zip(axes, panels, strict=True):
        image = axis.tripcolor(triangulation, values, shading="gouraud", cmap=cmap,
                               vmin=vmin, vmax=vmax)
        axis.set_title(label)
        axis.set_xlabel("axial position x [mm]")
        axis.set_aspect("equal")
        figure.colorbar(image, ax=axis, label=unit, shrink=0.85)
    axes[0].set_ylabel("radius z [mm]")
    max_error = float(np.abs(rom - fom).max())
    figure.suptitle(f"{title}  max |ROM − FOM| = {max_error:.3f} K (pressure side)".strip())
    return figure


def field_comparison_figure(mesh: SolidMesh, fom_field: np.ndarray, rom_field: np.ndarray,
                            path: str | Path, title: str = "") -> Path:
    """Write :func:`field_figure` of nodal fields (K) to ``path`` (PNG, 150 dpi)."""
    path = Path(path)
    field_figure(mesh, fom_field, rom_field, title).savefig(path, dpi=150)
    return path
