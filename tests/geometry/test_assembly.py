"""Assembly on the centreline: radii, blade counts, volumes, files."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from steamtwin.geometry.assembly import build_assembly, row_positions, write_assembly


def test_rows_sit_at_their_radii_with_their_blade_counts(reference_spec, hp1_blade,
                                                         tmp_path) -> None:
    components = build_assembly(reference_spec, rows=("hp1",), spacing=3e-3)
    names = [c.name for c in components]
    assert names == ["row_hp1", "rotor", "casing"]
    row = components[0]
    radius = np.hypot(row.vertices[:, 1], row.vertices[:, 2])
    assert radius.min() == pytest.approx(hp1_blade.design.hub_radius, abs=1e-9)
    assert radius.max() == pytest.approx(hp1_blade.design.tip_radius, abs=1e-9)
    mesh = trimesh.Trimesh(row.vertices, row.triangles, process=False)
    assert mesh.is_watertight
    assert len(mesh.split(only_watertight=True)) == hp1_blade.profile.params.blade_count
    # wrapping onto the cylinders keeps the volume to the blade's curvature (y/r ≲ 0.05)
    volume = hp1_blade.profile.params.blade_count * hp1_blade.volume
    assert mesh.volume == pytest.approx(volume, rel=5e-3)
    for component in components[1:]:
        part = trimesh.Trimesh(component.vertices, component.triangles, process=False)
        assert part.is_watertight and part.volume > 0.0
    rotor = components[1]
    assert np.hypot(rotor.vertices[:, 1], rotor.vertices[:, 2]).max() == pytest.approx(
        hp1_blade.design.hub_radius, rel=1e-3)
    paths = write_assembly(components, tmp_path / "assembly.stl")
    assert {p.name for p in paths} == {"assembly.stl", "assembly_row_hp1.stl",
                                       "assembly_rotor.stl", "assembly_casing.stl"}


def test_rows_are_ordered_downstream(reference_spec) -> None:
    positions = row_positions(reference_spec)
    x = np.array(list(positions.values()))
    assert np.all(np.diff(x) > 0.0)
    assert positions["ip1"] - positions["hp13"] > 1.0
