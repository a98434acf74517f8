"""Scanned throat areas into the turbine spec: the flow capacities of the reconstructed rows.

``steamtwin geometry reconstruct … --report BASE`` writes ``BASE.json`` with the row's throat
area N·∫o(r)dr of the measured and of the design blade (``throat_area``, from the throats at
hub, mid-span and tip; :func:`~steamtwin.geometry.reconstruction_report.row_throat_area`).
The Stodola constant of a stage scales with its throat area (Cooke 1985), so the ratio measured
/ design of rotor row hpK multiplies ``stages[K−1].flow_capacity`` (:func:`update_spec_from_scans`).
The control-stage rotor hp1 sets no flow in the model (the nozzle groups do,
:data:`~steamtwin.geometry.uncertainty.CONTROL_STAGE_ROTOR`) and IP rows are not in the HP
model: both are listed as not applied. The spec TOML text is edited line by line, so its
comments and layout stay; every changed line names the row, the report file and the ratio.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from steamtwin.errors import GeometryAreaError
from steamtwin.geometry.fidelity import section_pitch, section_throat, truth_section
from steamtwin.geometry.pritchard import GeometryError
from steamtwin.geometry.profile import make_blade
from steamtwin.geometry.row_sizing import HP_ROWS, ROWS
from steamtwin.geometry.uncertainty import CONTROL_STAGE_ROTOR, throat_area
from steamtwin.spec import TurbineSpec, parse_spec

#: Plausible measured / design throat-area ratios: a scan of the right blade at the right scale
#: differs from the design by a few per cent at most (±0.05 mm on a 5–13 mm throat is < 1 %;
#: erosion and deposits a few per cent); outside, the report is of another blade or unit.
PLAUSIBLE_RATIO = (0.8, 1.2)
#: Relative agreement required between the report's design throat area and the spec's blade.
DESIGN_AREA_TOLERANCE = 0.005


class ScanUpdateError(GeometryAreaError):
    """A reconstruction report that cannot go into the spec; the message names the file."""


@dataclass(frozen=True)
class ScannedRow:
    """One row's reconstruction report: ``ratio`` = measured / design throat area (–)."""

    row: str
    path: Path
    ratio: float
    design_area: float  # m²
    radii: tuple[float, ...]  # m, where the throats were measured


@dataclass(frozen=True)
class SpecUpdate:
    """The updated spec text and what went into it.

    ``applied``: (row, 1-based stage, report file, ratio, old and new flow capacity in m²);
    ``not_applied``: row → reason (control-stage rotor, IP row); ``missing``: the spec's
    pressure-stage rows with no report in the folder.
    """

    toml: str
    applied: tuple[tuple[str, int, Path, float, float, float], ...]
    not_applied: dict[str, str]
    missing: tuple[str, ...]


def read_scan_reports(folder: str | Path) -> dict[str, ScannedRow]:
    """The reconstruction reports (``*.json`` written by ``geometry reconstruct --report``)
    in ``folder``, by row. Other JSON files (scan manifests, preprocessing reports) are
    skipped; a reconstruction report without the throat area, with a ratio outside
    :data:`PLAUSIBLE_RATIO`, or a second report of the same row raises
    :class:`ScanUpdateError` naming the file(s)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ScanUpdateError(f"--scans {folder}: not a folder")
    rows: dict[str, ScannedRow] = {}
    for path in sorted(folder.glob("*.json")):
        try:
            document = json.loads(path.read_text(encoding="utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as error:
            raise ScanUpdateError(f"{path}: not a JSON file ({error})") from None
        if not (isinstance(document, dict) and "deviation_mm" in document
                and "metrics" in document):
            continue  # not a reconstruction report
        row = document.get("row")
        if row not in ROWS:
            raise ScanUpdateError(f"{path}: 'row' is {row!r}, not a blade row "
                                  f"({ROWS[0]}…{ROWS[-1]})")
        area = document.get("throat_area")
        if not isinstance(area, dict) or not {"ratio", "design_mm2", "radii_mm"} <= set(area):
            raise ScanUpdateError(
                f"{path}: row {row}: the report has no 'throat_area' (ratio, design_mm2, "
                "radii_mm); it was written before reconstruct reported it: run "
                "'steamtwin geometry reconstruct … --report' again")
        ratio = float(area["ratio"])
        low, high = PLAUSIBLE_RATIO
        if not low <= ratio <= high:
            raise ScanUpdateError(
                f"{path}: row {row}: throat_area.ratio {ratio:.4g} (measured / design) lies "
                f"outside the plausible {low}–{high}: another blade, another unit or a scan "
                "in the wrong unit?")
        if row in rows:
            raise ScanUpdateError(f"row {row} has two reconstruction reports: {rows[row].path} "
                                  f"and {path}; keep one in the folder")
        rows[row] = ScannedRow(row=row, path=path, ratio=ratio,
                               design_area=float(area["design_mm2"]) * 1e-6,
                               radii=tuple(float(r) * 1e-3 for r in area["radii_mm"]))
    return rows


def design_throat_area(spec: TurbineSpec, row: str, radii: tuple[float, ...]) -> float:
    """Throat area N·∫o(r)dr (m²) of the spec's design blade of ``row`` from its exact throats
    at ``radii`` (m), as the reconstruction report measures it."""
    blade = make_blade(spec, row)
    radii_array = np.asarray(radii, dtype=np.float64)
    throats = np.array([section_throat(truth_section(blade, float(r)),
                                       section_pitch(blade, float(r))) for r in radii_array])
    return throat_area(blade, radii_array, throats)


def update_spec_from_scans(text: str, spec: TurbineSpec, folder: str | Path,
                           source: str = "<spec>") -> SpecUpdate:
    """``text`` (the TOML of ``spec``, read from ``source``) with the flow capacity of every
    pressure stage whose rotor row has a reconstruction report in ``folder`` multiplied by
    the row's measured / design throat-area ratio.

    Raises :class:`ScanUpdateError` naming the file and row for a report refused by
    :func:`read_scan_reports`, a report measured against another design blade (its design
    throat area more than :data:`DESIGN_AREA_TOLERANCE` off this spec's), a row beyond the
    spec's stages, or a spec whose stages are not ``[[stages]]`` tables with one
    ``flow_capacity = …`` line each.
    """
    scanned = read_scan_reports(folder)
    lines = text.splitlines(keepends=True)
    capacity_lines = _flow_capacity_lines(lines, len(spec.stages), source)
    applied, not_applied = [], {}
    for row, scan in scanned.items():
        if row == HP_ROWS[0]:
            not_applied[row] = CONTROL_STAGE_ROTOR
            continue
        if row not in HP_ROWS:
            not_applied[row] = "not applied: an IP row, not in the HP model"
            continue
        stage = HP_ROWS.index(row)
        if stage > len(spec.stages):
            raise ScanUpdateError(f"{scan.path}: row {row} is the rotor of pressure stage "
                                  f"{stage}, but {source} has {len(spec.stages)} stages")
        try:
            design = design_throat_area(spec, row, scan.radii)
        except GeometryError as error:
            raise ScanUpdateError(f"{scan.path}: row {row}: {error}") from None
        if abs(scan.design_area / design - 1.0) > DESIGN_AREA_TOLERANCE:
            raise ScanUpdateError(
                f"{scan.path}: row {row}: measured against a design throat area of "
                f"{scan.design_area * 1e6:.1f} mm², but the blade of {source} has "
                f"{design * 1e6:.1f} mm²: reconstruct with --turbine {source}")
        old = spec.stages[stage - 1].flow_capacity
        new = old * scan.ratio
        index = capacity_lines[stage - 1]
        indent = re.match(r"\s*", lines[index]).group(0)
        ending = "\n" if lines[index].endswith("\n") else ""
        lines[index] = (f'{indent}flow_capacity = "{new:.6g} m^2"  # {row}: {scan.path.name}, '
                        f"throat-area ratio {scan.ratio:.5f} (was {old:.6g} m^2){ending}")
        applied.append((row, stage, scan.path, scan.ratio, old, new))
    updated = "".join(lines)
    check = parse_spec(updated, source)
    for _, stage, path, _, _, new in applied:
        if not np.isclose(check.stages[stage - 1].flow_capacity, new, rtol=1e-5):
            raise ScanUpdateError(f"{source}: stages[{stage}].flow_capacity did not take the "
                                  f"value from {path}")
    missing = tuple(row for row in HP_ROWS[1:len(spec.stages) + 1] if row not in scanned)
    return SpecUpdate(toml=updated, applied=tuple(sorted(applied, key=lambda a: a[1])),
                      not_applied=not_applied, missing=missing)


def _flow_capacity_lines(lines: list[str], stages: int, source: str) -> list[int]:
    """0-based line index of each ``[[stages]]`` table's ``flow_capacity`` key."""
    found: list[int | None] = []
    in_stage = False
    for number, line in enumerate(lines):
        stripped = line.strip()
        if stripped.startswith("["):
            in_stage = re.match(r"\[\[\s*stages\s*\]\]", stripped) is not None
            if in_stage:
                found.append(None)
        elif in_stage and re.match(r"flow_capacity\s*=", stripped):
            found[-1] = number
    if len(found) != stages or any(index is None for index in found):
        raise ScanUpdateError(
            f"{source}: the pressure stages must be written as {stages} [[stages]] tables "
            "with one 'flow_capacity = …' line each to be updated in place")
    return found
