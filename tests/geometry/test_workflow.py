"""The geometry chain as the CLI and the demo run it (geometry/workflow.py): scan folders, the
settings a scan carries, the progress protocol and the refusals."""

from __future__ import annotations

import json

import numpy as np
import pytest

from steamtwin.errors import GeometryAreaError
from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.preprocess_settings import PreprocessSettings
from steamtwin.geometry.workflow import (
    RowMismatchError,
    ScanFolderError,
    preprocess_scan,
    read_scan_folder,
    reconstruct_source,
    scan_row,
    scan_settings,
)


def test_a_folder_without_manifest_is_named(tmp_path):
    with pytest.raises(ScanFolderError, match=r"scan\.json: no scan manifest"):
        read_scan_folder(tmp_path)
    (tmp_path / "scan.json").write_text(json.dumps({"row": "hp1"}), encoding="utf-8")
    with pytest.raises(ScanFolderError, match="no key 'views'"):
        read_scan_folder(tmp_path)
    assert issubclass(ScanFolderError, GeometryAreaError) and issubclass(ScanFolderError,
                                                                         ValueError)


def test_scan_settings_take_the_recorded_sphere_radius():
    assert scan_settings({}).sphere_radius == PreprocessSettings().sphere_radius
    assert scan_settings({"sphere_radius": None}).sphere_radius is None
    settings = scan_settings({"sphere_radius": 0.012}, target_points=5000)
    assert settings.sphere_radius == 0.012 and settings.target_points == 5000


def test_row_mismatch_names_the_row_and_the_fit():
    error = RowMismatchError("hp3", 0.205)
    assert isinstance(error, ReconstructionError) and isinstance(error, ValueError)
    assert "row hp3's nominal blade" in str(error) and "205 mm" in str(error)


def test_a_row_needs_its_spec(tmp_path):
    with pytest.raises(ValueError, match="needs the turbine spec"):
        reconstruct_source(tmp_path / "cloud.ply", tmp_path / "b.stl", row="hp1")
    with pytest.raises(ValueError, match="stl_frame must be"):
        reconstruct_source(tmp_path / "cloud.ply", tmp_path / "b.stl", stl_frame="cad")


def test_scan_and_preprocess_report_progress(reference_spec, tmp_path):
    """Both steps call progress(fraction, message): fractions rise to 1, messages are text; the
    in-memory scan and its folder give the same fused cloud (the folder keeps float64)."""
    calls = []
    scanned = scan_row(reference_spec, "hp1", tmp_path, points=4000, views=4, spheres=0,
                       random_state=5, progress=lambda f, m: calls.append((f, m)))
    assert [f for f, _ in calls] == [0.25, 0.5, 0.75, 1.0]
    assert all(isinstance(m, str) and m for _, m in calls)
    assert json.loads((tmp_path / "scan.json").read_text())["sphere_radius"] is None
    calls.clear()
    from_folder = preprocess_scan(tmp_path, target_points=1000,
                                  progress=lambda f, m: calls.append((f, m)))
    fractions = [f for f, _ in calls]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    assert any(m.startswith("register: ") for _, m in calls)
    in_memory = preprocess_scan(scanned.scan, target_points=1000)
    assert from_folder.row == in_memory.row == "hp1"
    assert np.array_equal(from_folder.cloud, in_memory.cloud)
