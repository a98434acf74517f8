"""``steamtwin geometry`` commands end to end on small inputs."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from steamtwin.cli.geometry import geometry_app
from steamtwin.geometry.pointcloud import write_point_cloud
from steamtwin.geometry.volume_mesh import read_volume_mesh

pytestmark = pytest.mark.slow  # 20 s of the full suite (2026-11-27): not in the quick loop

runner = CliRunner()


@pytest.mark.parametrize("command", ["scan", "preprocess", "mesh", "assemble", "uncertainty"])
def test_help_has_an_example(command: str) -> None:
    result = runner.invoke(geometry_app, [command, "--help"])
    assert result.exit_code == 0 and "Example:" in result.output


def test_scan_then_preprocess(tmp_path) -> None:
    scan_dir = tmp_path / "scan"
    result = runner.invoke(geometry_app, ["scan", "--row", "hp2", "--points", "24000", "--views",
                                          "6", "--seed", "1", "--out", str(scan_dir)])
    assert result.exit_code == 0, result.output
    assert len(list(scan_dir.glob("view_*.ply"))) == 6
    result = runner.invoke(geometry_app, ["preprocess", str(scan_dir), "--out",
                                          str(tmp_path / "fused.ply"), "--target-points",
                                          "12000", "--report", str(tmp_path / "report")])
    assert result.exit_code == 0, result.output
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["row"] == "hp2"
    assert report["deviation_mm"]["mean"] < 0.2  # mean is dominated by inliers on the blade
    assert report["steps"]["downsampled_points"] == pytest.approx(12000, rel=0.05)


def test_mesh_writes_a_readable_mesh(tmp_path) -> None:
    out = tmp_path / "blade.vtu"
    result = runner.invoke(geometry_app, ["mesh", "--row", "hp1", "--element-size", "3",
                                          "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "min dihedral angle" in result.output
    assert len(read_volume_mesh(out).tetrahedra) > 0


def test_bad_input_gives_clear_errors(tmp_path) -> None:
    result = runner.invoke(geometry_app, ["scan", "--row", "lp1", "--out", str(tmp_path)])
    assert result.exit_code == 2 and "unknown blade row 'lp1'" in result.output
    result = runner.invoke(geometry_app, ["preprocess", str(tmp_path / "nothing"), "--out",
                                          str(tmp_path / "x.ply")])
    assert result.exit_code == 2 and "no scan manifest" in result.output


def test_assemble_and_uncertainty(tmp_path) -> None:
    out = tmp_path / "assembly.stl"
    result = runner.invoke(geometry_app, ["assemble", "--rows", "hp1", "--spacing", "4",
                                          "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert out.is_file() and (tmp_path / "assembly_rotor.stl").is_file()
    result = runner.invoke(geometry_app, ["assemble", "--rows", "hp1,zz9", "--out", str(out)])
    assert result.exit_code == 2 and "zz9" in result.output
    json_path = tmp_path / "u.json"
    result = runner.invoke(geometry_app, ["uncertainty", "--row", "hp13", "--samples", "2",
                                          "--out", str(json_path)])
    assert result.exit_code == 0, result.output
    document = json.loads(json_path.read_text())
    assert document["samples"] == 2
    assert "largest deviation" in result.output
    assert (0.5 * document["hp_exhaust_temperature_spread_K"] - 1e-12
            <= document["hp_exhaust_temperature_max_deviation_K"])
    assert document["stage"] == 12 and "stage 12's flow capacity alone" in result.output
    result = runner.invoke(geometry_app, ["uncertainty", "--samples", "2"])
    assert result.exit_code == 0 and "not propagated: hp1 is the control-stage rotor" in (
        result.output)
    result = runner.invoke(geometry_app, ["uncertainty", "--row", "ip2", "--samples", "2"])
    assert result.exit_code == 2 and "not in the HP model" in result.output


def test_preprocess_refuses_a_truncated_view(tmp_path) -> None:
    """Issue 16: a cut-off view used to be read with zeros or garbage and fused (exit 0)."""
    points = np.random.default_rng(2).normal(scale=0.02, size=(500, 3))
    for k in range(2):
        write_point_cloud(points, tmp_path / f"view_{k:02d}.ply")
    view = tmp_path / "view_01.ply"
    view.write_bytes(view.read_bytes()[:-2405])
    (tmp_path / "scan.json").write_text(json.dumps(
        {"row": "hp1", "views": ["view_00.ply", "view_01.ply"], "sphere_radius": None}))
    result = runner.invoke(geometry_app, ["preprocess", str(tmp_path), "--out",
                                          str(tmp_path / "fused.ply")])
    assert result.exit_code != 0 and isinstance(result.exception, SystemExit)
    assert "view_01.ply: element 'vertex' promises 500 points" in result.output
    assert "399 complete points): the file is truncated" in result.output
    assert not (tmp_path / "fused.ply").exists()
