"""Scanned throat areas into the spec: the reconstruction report's throat area, the flow
capacity of the row's own stage, and the refusals (file and row named)."""

from __future__ import annotations

import dataclasses
import json
from importlib.resources import files

import numpy as np
import pytest

from steamtwin.geometry.fidelity import section_pitch, section_throat, truth_section
from steamtwin.geometry.into_spec import (
    ScanUpdateError,
    read_scan_reports,
    update_spec_from_scans,
)
from steamtwin.geometry.profile import make_blade
from steamtwin.geometry.reconstruction_report import (
    reconstruction_fidelity,
    row_throat_area,
    write_reconstruction_report,
)
from steamtwin.spec import parse_spec

pytestmark = pytest.mark.slow  # 15 s of the full suite (2026-11-27): not in the quick loop

REFERENCE_TEXT = (files("steamtwin.spec") / "data" / "reference.toml").read_text(
    encoding="utf-8")


@pytest.fixture(scope="module")
def exact_report(reference_spec):
    """The report reconstruct writes, for a 0.5 mm triangulation of the exact hp13 blade as
    the "measured" one."""
    blade = make_blade(reference_spec, "hp13")
    vertices, triangles, _ = blade.surface_mesh(0.5e-3, span_count=20)
    return blade, reconstruction_fidelity(blade, vertices, triangles, samples=2000)


def write_report(folder, blade, report, ratio: float, name: str | None = None):
    """``report`` with the measured throats set to ``ratio`` × the design ones, written as
    reconstruct writes it (a real 25k-point reconstruct of hp13 takes ~35 s and fails on the
    sparse trailing edge, so the tests use the exact surface and a synthetic ratio)."""
    area = report.extra["throat_area"]
    radii = np.array(area["radii_mm"]) * 1e-3
    design = np.array([section_throat(truth_section(blade, r), section_pitch(blade, r))
                       for r in radii])
    extra = {**report.extra, "throat_area": row_throat_area(blade, radii, design,
                                                            ratio * design)}
    path = folder / (name or f"{blade.row}-reconstruction")
    json_path, _ = write_reconstruction_report(dataclasses.replace(report, extra=extra), path)
    return json_path


def test_reconstruction_report_carries_the_row_throat_area(exact_report, tmp_path) -> None:
    blade, report = exact_report
    area = report.extra["throat_area"]
    # the exact blade measured against itself: the same throat area (0.5 mm chords: 1.2e-4)
    assert area["ratio"] == pytest.approx(1.0, abs=5e-4)
    throats = [section_throat(truth_section(blade, r * 1e-3),
                              section_pitch(blade, r * 1e-3)) for r in area["radii_mm"]]
    count, span = blade.profile.params.blade_count, blade.design.span
    assert count * min(throats) * span < area["design_mm2"] * 1e-6 < count * max(throats) * span
    json_path, csv_path = write_reconstruction_report(report, tmp_path / "r")
    assert json.loads(json_path.read_text())["throat_area"]["ratio"] == area["ratio"]
    assert "throat_area,mm2," in csv_path.read_text()


def test_update_scales_only_the_rows_own_stage(exact_report, reference_spec, tmp_path) -> None:
    blade, report = exact_report
    path = write_report(tmp_path, blade, report, 1.01)
    (tmp_path / "scan.json").write_text(json.dumps({"row": "hp13"}))  # not a report: skipped
    result = update_spec_from_scans(REFERENCE_TEXT, reference_spec, tmp_path, "unit.toml")
    updated = parse_spec(result.toml)
    old = reference_spec.stages[11].flow_capacity
    assert updated.stages[11].flow_capacity == pytest.approx(1.01 * old, rel=2e-6)
    assert updated.stages[:11] == reference_spec.stages[:11]
    assert result.applied[0][:4] == ("hp13", 12, path, pytest.approx(1.01))
    assert result.missing == tuple(f"hp{k}" for k in range(2, 13))
    changed = [line for line in result.toml.splitlines()
               if line not in REFERENCE_TEXT.splitlines()]
    assert len(changed) == 1
    assert f"# hp13: {path.name}, throat-area ratio 1.01000 (was 0.1155 m^2)" in changed[0]


def test_control_stage_rotor_and_ip_rows_are_listed_not_applied(exact_report, reference_spec,
                                                                 tmp_path) -> None:
    blade, report = exact_report
    path = write_report(tmp_path, blade, report, 1.0)
    document = json.loads(path.read_text())
    for row in ("hp1", "ip4"):
        (tmp_path / f"{row}.json").write_text(json.dumps({**document, "row": row}))
    result = update_spec_from_scans(REFERENCE_TEXT, reference_spec, tmp_path)
    assert "control-stage rotor" in result.not_applied["hp1"]
    assert "IP row" in result.not_applied["ip4"]
    assert [a[0] for a in result.applied] == ["hp13"]


@pytest.mark.parametrize("ratio", [0.75, 1.25])
def test_implausible_ratio_is_refused_naming_row_and_file(exact_report, tmp_path,
                                                          ratio) -> None:
    blade, report = exact_report
    path = write_report(tmp_path, blade, report, ratio)
    with pytest.raises(ScanUpdateError, match=rf"{path}: row hp13: throat_area.ratio .*0.8–1.2"):
        read_scan_reports(tmp_path)


def test_refusals(exact_report, reference_spec, tmp_path) -> None:
    blade, report = exact_report
    path = write_report(tmp_path, blade, report, 1.0)
    document = json.loads(path.read_text())
    # another design blade: the report's design throat area is not this spec's
    other = {**document, "throat_area": {**document["throat_area"],
                                         "design_mm2": document["throat_area"]["design_mm2"]
                                         * 1.1}}
    path.write_text(json.dumps(other))
    with pytest.raises(ScanUpdateError, match=rf"{path}: row hp13: measured against a design"):
        update_spec_from_scans(REFERENCE_TEXT, reference_spec, tmp_path, "unit.toml")
    # written before reconstruct reported the throat area
    path.write_text(json.dumps({k: v for k, v in document.items() if k != "throat_area"}))
    with pytest.raises(ScanUpdateError, match=rf"{path}: row hp13: the report has no"):
        read_scan_reports(tmp_path)
    # two reports of one row
    path.write_text(json.dumps(document))
    (tmp_path / "again.json").write_text(json.dumps(document))
    with pytest.raises(ScanUpdateError, match="row hp13 has two reconstruction reports"):
        read_scan_reports(tmp_path)
    with pytest.raises(ScanUpdateError, match="not a folder"):
        read_scan_reports(tmp_path / "missing")
    # a spec whose stages are not [[stages]] tables cannot be edited in place
    (tmp_path / "again.json").unlink()
    with pytest.raises(ScanUpdateError, match=r"unit.toml: the pressure stages must be written"):
        update_spec_from_scans(REFERENCE_TEXT.replace("flow_capacity =", "flow_capacity="
                                                      ).replace("[[stages]]", "[[stage]]"),
                               reference_spec, tmp_path, "unit.toml")
