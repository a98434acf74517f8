"""``steamtwin turbine update SPEC --scans DIR --out UPDATED``: flow capacities from the
throat areas of reconstructed rows; refusals as exit code 2 naming file and row."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from steamtwin.cli.main import app
from steamtwin.geometry.into_spec import design_throat_area
from steamtwin.spec import load_spec

runner = CliRunner()


def write_report(folder, spec, row: str, ratio: float):
    """A reconstruction report's fields the update reads (the JSON of 'geometry reconstruct
    --report'), the throat area set from a synthetic ratio against the spec's design blade."""
    radii_mm = [438.2, 511.6, 585.0]  # hp13: 5 %, 50 %, 95 % of the span
    design = design_throat_area(spec, row, tuple(r * 1e-3 for r in radii_mm))
    path = folder / f"{row}-reconstruction.json"
    path.write_text(json.dumps({"row": row, "deviation_mm": {}, "metrics": [],
                                "throat_area": {"design_mm2": design * 1e6,
                                                "measured_mm2": ratio * design * 1e6,
                                                "ratio": ratio, "radii_mm": radii_mm}}))
    return path


def test_update_writes_the_scaled_spec(reference_spec, tmp_path) -> None:
    scans = tmp_path / "scans"
    scans.mkdir()
    path = write_report(scans, reference_spec, "hp13", 0.99)
    out = tmp_path / "updated.toml"
    result = runner.invoke(app, ["turbine", "update", "reference", "--scans", str(scans),
                                 "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert f"hp13: stages[12].flow_capacity 0.1155 → 0.114345 m² (throat-area ratio 0.99000, " \
           f"{path})" in result.output
    assert "no report for: hp2, hp3" in result.output
    capacity = load_spec(out).stages[11].flow_capacity
    assert abs(capacity / (0.99 * reference_spec.stages[11].flow_capacity) - 1.0) < 1e-5
    assert f"# hp13: {path.name}, throat-area ratio 0.99000" in out.read_text()


def test_update_refuses_an_implausible_ratio(reference_spec, tmp_path) -> None:
    path = write_report(tmp_path, reference_spec, "hp13", 1.3)
    out = tmp_path / "out" / "updated.toml"
    result = runner.invoke(app, ["turbine", "update", "reference", "--scans", str(tmp_path),
                                 "--out", str(out)])
    assert result.exit_code == 2
    assert f"error: {path}: row hp13: throat_area.ratio 1.3" in result.output
    assert not out.exists()


def test_update_checks_the_output_path_first(tmp_path) -> None:
    result = runner.invoke(app, ["turbine", "update", str(tmp_path / "missing.toml"),
                                 "--scans", str(tmp_path), "--out", str(tmp_path)])
    assert result.exit_code == 2 and "is a folder" in result.output
