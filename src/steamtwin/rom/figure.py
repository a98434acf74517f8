"""Figure 9 analogue: the ROM's blade field next to the FOM's, with the error map (PNG).

Three panels show the blade's surface nodes (suction side left out) seen from the pressure
side: axial position x (mm) against radius z (mm), leading edge left, root at the bottom. The
error panel uses a colour scale symmetric about zero (ROM − FOM).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt
import numpy as np

from steamtwin.blade.mesh import REGIONS, SolidMesh


def field_comparison_figure(mesh: SolidMesh, fom_field: np.ndarray, rom_field: np.ndarray,
                            path: str | Path, title: str = "") -> Path:
    """Write the FOM | ROM | error figure of nodal fields (K) to ``path`` (PNG)."""
    n = mesh.points.shape[0]
    fom = np.asarray(fom_field, dtype=float)
    rom = np.asarray(rom_field, dtype=float)
    if fom.shape != (n,) or rom.shape != (n,):
        raise ValueError(f"fields must have shape ({n},), got {fom.shape} and {rom.shape}")
    side = mesh.boundary_triangles[mesh.boundary_regions != REGIONS.index("suction_side")]
    nodes = np.unique(side)
    x = mesh.points[nodes, 0] * 1e3
    z = mesh.points[nodes, 2] * 1e3
    error = rom[nodes] - fom[nodes]
    low = min(fom[nodes].min(), rom[nodes].min()) - 273.15
    high = max(fom[nodes].max(), rom[nodes].max()) - 273.15
    limit = max(float(np.abs(error).max()), 1e-6)
    figure, axes = plt.subplots(1, 3, figsize=(13.0, 4.2), sharey=True,
                                constrained_layout=True)
    panels = (
        (fom[nodes] - 273.15, "FOM (FEM)", "inferno", low, high, "T [°C]"),
        (rom[nodes] - 273.15, "ROM (POD–RBF)", "inferno", low, high, "T [°C]"),
        (error, "ROM − FOM", "coolwarm", -limit, limit, "error [K]"),
    )
    for axis, (values, label, cmap, vmin, vmax, unit) in zip(axes, panels, strict=True):
        order = np.argsort(mesh.points[nodes, 1])  # draw the far side first
        image = axis.scatter(x[order], z[order], c=values[order], s=6, cmap=cmap, vmin=vmin,
                             vmax=vmax, linewidths=0)
        axis.set_title(label)
        axis.set_xlabel("axial position x [mm]")
        axis.set_aspect("equal")
        figure.colorbar(image, ax=axis, label=unit, shrink=0.85)
    axes[0].set_ylabel("radius z [mm]")
    max_error = float(np.abs(rom - fom).max())
    figure.suptitle(f"{title}  max |ROM − FOM| = {max_error:.3f} K".strip())
    path = Path(path)
    figure.savefig(path, dpi=150)
    plt.close(figure)
    return path
