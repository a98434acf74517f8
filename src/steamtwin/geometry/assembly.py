"""Assembly: blade rows, rotor and casing placed on the turbine centreline.

Turbine frame (m): x along the axis (downstream), y and z across it. A blade is built in its
own frame (x axial, y tangential, z radial) and wrapped onto the cylinders of its sections —
the tangential coordinate becomes the angle θ = y / r, so Pritchard's unrolled sections (and the
pitch 2πr/N) hold exactly on every radius — then copied N times around the axis.

The spec gives diameters, heights and blade counts but no axial positions: rows are stacked at a
pitch of 2.5 axial chords (a stator of equal axial width plus two axial gaps of 25 % of the
axial chord, the usual 0.2–0.3 of HP blading, Traupel 2001 §19), the IP section one metre
downstream of the HP section (a schematic single-flow arrangement). Rotor and casing are bodies
of revolution following the hub and tip radii (tip clearance 0.5 mm, casing wall 0.1 m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from steamtwin.geometry.profile import Blade, make_blade
from steamtwin.geometry.row_sizing import HP_ROWS, IP_ROWS
from steamtwin.progress import ProgressCallback
from steamtwin.spec import TurbineSpec

ROW_PITCH_PER_AXIAL_CHORD = 2.5
HP_IP_GAP = 1.0  # m
TIP_CLEARANCE = 0.5e-3  # m
CASING_WALL = 0.1  # m


@dataclass(frozen=True)
class Component:
    """A named triangle mesh in the turbine frame (m)."""

    name: str
    vertices: np.ndarray
    triangles: np.ndarray


def wrap_blade(vertices: np.ndarray) -> np.ndarray:
    """Blade-frame points (x, y tangential, z radial) onto cylinders about the turbine x axis."""
    theta = vertices[:, 1] / vertices[:, 2]
    return np.column_stack([vertices[:, 0], vertices[:, 2] * np.sin(theta),
                            vertices[:, 2] * np.cos(theta)])


def row_positions(spec: TurbineSpec, rows: tuple[str, ...] = HP_ROWS + IP_ROWS
                  ) -> dict[str, float]:
    """Axial position (m) of each row's leading-edge plane (see the module docstring)."""
    positions, x = {}, 0.0
    for index, row in enumerate(rows):
        blade = make_blade(spec, row)
        if row == IP_ROWS[0] and index > 0:
            x += HP_IP_GAP
        positions[row] = x
        x += ROW_PITCH_PER_AXIAL_CHORD * blade.profile.params.axial_chord
    return positions


def row_component(blade: Blade, x: float, spacing: float = 2e-3) -> Component:
    """All N blades of a row, wrapped and rotated about the axis, leading edge at ``x``."""
    vertices, triangles, _ = blade.surface_mesh(spacing)
    wrapped = wrap_blade(vertices) + np.array([x, 0.0, 0.0])
    count = blade.profile.params.blade_count
    all_vertices, all_triangles = [], []
    for k in range(count):
        angle = 2.0 * math.pi * k / count
        c, s = math.cos(angle), math.sin(angle)
        rotation = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        all_vertices.append(wrapped @ rotation.T)
        all_triangles.append(triangles + k * len(vertices))
    return Component(f"row_{blade.row}", np.concatenate(all_vertices),
                     np.concatenate(all_triangles))


def revolve(profile: np.ndarray, name: str, sections: int = 180) -> Component:
    """Closed body of revolution of an (n, 2) (x, r) outline (closed by the axis when its ends
    lie on it, else by repeating its first point), with outward normals."""
    import trimesh  # deferred: heavy import (~1-2 s), only the mesh steps pay it

    if profile[0, 1] > 0.0 or profile[-1, 1] > 0.0:
        profile = np.vstack([profile, profile[:1]])
    mesh = trimesh.creation.revolve(profile[:, ::-1], sections=sections)
    if mesh.volume < 0.0:
        mesh.invert()
    # trimesh revolves about its z axis with (r, z) input: turn z into the turbine x axis
    vertices = np.asarray(mesh.vertices)[:, [2, 0, 1]]
    return Component(name, vertices, np.asarray(mesh.faces, dtype=np.int64))


def build_assembly(spec: TurbineSpec, rows: tuple[str, ...] = HP_ROWS + IP_ROWS,
                   spacing: float = 2e-3,
                   progress: ProgressCallback | None = None) -> list[Component]:
    """Rows, rotor and casing of ``spec`` (``spacing``: blade triangulation spacing, m)."""
    positions = row_positions(spec, rows)
    components, hub, tip = [], [], []
    for k, row in enumerate(rows):
        blade = make_blade(spec, row)
        x0 = positions[row]
        x1 = x0 + ROW_PITCH_PER_AXIAL_CHORD * blade.profile.params.axial_chord
        components.append(row_component(blade, x0, spacing))
        hub += [(x0 - 0.75 * blade.profile.params.axial_chord, blade.design.hub_radius),
                (x1 - 0.75 * blade.profile.params.axial_chord, blade.design.hub_radius)]
        tip += [(x0 - 0.75 * blade.profile.params.axial_chord,
                 blade.design.tip_radius + TIP_CLEARANCE),
                (x1 - 0.75 * blade.profile.params.axial_chord,
                 blade.design.tip_radius + TIP_CLEARANCE)]
        if progress is not None:
            progress(0.9 * (k + 1) / len(rows), f"row {row} placed")
    hub, tip = np.array(hub), np.array(tip)
    # rotor: axis -> hub line -> axis; casing: inner line at the tips, outer wall 0.1 m out
    rotor = np.vstack([[hub[0, 0], 0.0], hub, [hub[-1, 0], 0.0]])
    outer = tip[:, 1].max() + CASING_WALL
    casing = np.vstack([tip, [tip[-1, 0], outer], [tip[0, 0], outer]])
    components.append(revolve(rotor, "rotor"))
    components.append(revolve(casing, "casing"))
    if progress is not None:
        progress(1.0, "rotor and casing revolved")
    return components


def write_assembly(components: list[Component], path: str | Path,
                   per_component: bool = True) -> list[Path]:
    """Write the whole assembly as one binary STL and, optionally, one STL per component
    (``<stem>_<name>.stl`` beside it)."""
    import trimesh  # deferred: heavy import (~1-2 s), only the mesh steps pay it

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    written = []
    if per_component:
        for component in components:
            part = path.with_name(f"{path.stem}_{component.name}.stl")
            trimesh.Trimesh(component.vertices, component.triangles,
                            process=False).export(part)
            written.append(part)
    offsets = np.cumsum([0] + [len(c.vertices) for c in components[:-1]])
    whole = trimesh.Trimesh(np.concatenate([c.vertices for c in components]),
                            np.concatenate([c.triangles + o
                                            for c, o in zip(components, offsets, strict=True)]),
                            process=False)
    whole.export(path)
    written.append(path)
    return written
