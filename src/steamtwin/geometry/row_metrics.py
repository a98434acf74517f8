"""Row metrics of any blade: chord, stagger, thickness, throat and edge radii from its surface.

Measured on sections z = const of a closed triangulation in the blade frame (m; x axial,
y tangential, z radius — the frame of :func:`~steamtwin.geometry.reconstruct.reconstruct_blade`)
at fractions of the span, with no nominal blade: chord, stagger (from the x axis) and maximum
thickness as :func:`~steamtwin.geometry.fidelity.section_metrics`; the throat only when the
pitch is known (a blade count N gives 2πr/N at each section); the leading- and trailing-edge
radii from a least-squares circle fitted to the edge region (:func:`edge_circle`).

Edge circle: around the section's most upstream (downstream) point along the chord line, arcs
of growing length are fitted by Kåsa's algebraic circle (Kåsa 1976, "A circle fitting procedure
and its error analysis", IEEE Trans. Instrum. Meas. IM-25:8); the edge is the longest arc
whose points all lie within ``max(0.2 % r, tolerance)`` of its circle — the sides that join the
edge tangentially leave the circle by t²/2r at an arc length t past the tangent point, so the
arc stops there —, and its circle is refined by geometric (orthogonal distance) least squares
(Gander, Golub & Strebel 1994, "Least-squares fitting of circles and ellipses", BIT 34:558).
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from steamtwin.geometry.fidelity import chord_line, section_metrics, truth_section
from steamtwin.geometry.mesh_sections import section_loops
from steamtwin.geometry.profile import Blade
from steamtwin.geometry.reconstruct import METRIC_SECTIONS

#: Span fractions of the measured sections (as the reconstruction report's hub, mid, tip).
SPAN_SECTIONS = (("hub", 0.05), ("mid", 0.5), ("tip", 0.95))
#: Allowed RMS deviation of edge points from their circle (m): above the STL's 1 µm chord sag
#: and the few µm a reconstructed edge wanders (bench_blade_io: 5 µm holds the arcs round the
#: leading edge of hp1 where 2 µm breaks them off).
EDGE_TOLERANCE = 5e-6
#: Relative allowance of the edge circle fit (share of the radius).
EDGE_RELATIVE = 2e-3
#: Points per chord when the section is resampled evenly by arc length for the edge fits.
EDGE_SAMPLES = 20_000
#: Deviation of the arc's end points from the circle, in RMS allowances, when the arc stops:
#: the tails t²/2r past the tangent points are a short part of an arc held to an RMS δ, so
#: their ends lie several δ off; 3 δ is the estimate trimmed (exact sections: radii within
#: 0.3 %, test_row_metrics).
OVERRUN = 3.0
#: Growth factor of the arcs tried round an edge.
ARC_GROWTH = 1.1


@dataclass(frozen=True)
class EdgeCircle:
    """A fitted edge circle: ``centre`` (2,; m), ``radius`` (m), ``rms`` of the points'
    distances from it (m) and the ``points`` fitted."""

    centre: np.ndarray
    radius: float
    rms: float
    points: int


@dataclass(frozen=True)
class RowSection:
    """Metrics of one section (m, rad): ``throat`` NaN without a pitch."""

    name: str
    radius: float
    chord: float
    stagger: float
    max_thickness: float
    throat: float
    pitch: float
    leading_edge: EdgeCircle
    trailing_edge: EdgeCircle

    def rows(self) -> list[dict[str, float | str]]:
        """Report rows in engineering units (mm, deg)."""
        values = {"chord": (self.chord * 1e3, "mm"),
                  "stagger": (math.degrees(self.stagger), "deg"),
                  "max_thickness": (self.max_thickness * 1e3, "mm"),
                  "throat": (self.throat * 1e3, "mm"),
                  "pitch": (self.pitch * 1e3, "mm"),
                  "le_radius": (self.leading_edge.radius * 1e3, "mm"),
                  "te_radius": (self.trailing_edge.radius * 1e3, "mm")}
        return [{"section": self.name, "radius_mm": self.radius * 1e3, "metric": name,
                 "unit": unit, "measured": value} for name, (value, unit) in values.items()]


def fit_circle(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Kåsa's algebraic circle (centre (2,), radius; m) through ``points`` (n ≥ 3, 2): the
    linear least-squares solution of x² + y² + D x + E y + F = 0."""
    points = np.asarray(points, dtype=np.float64)
    origin = points.mean(axis=0)
    p = points - origin  # centred for conditioning
    design = np.column_stack([p, np.ones(len(p))])
    solution, *_ = np.linalg.lstsq(design, -(p**2).sum(axis=1), rcond=None)
    centre = -0.5 * solution[:2]
    radius = math.sqrt(max(float(centre @ centre - solution[2]), 0.0))
    return centre + origin, radius


def refine_circle(points: np.ndarray, centre: np.ndarray, radius: float
                  ) -> tuple[np.ndarray, float]:
    """Geometric least-squares circle (Gander, Golub & Strebel 1994) from a start circle."""
    def residual(c: np.ndarray) -> np.ndarray:
        return np.linalg.norm(points - c[:2], axis=1) - c[2]

    result = least_squares(residual, np.append(centre, radius), method="lm", xtol=1e-15,
                           ftol=1e-15)
    return result.x[:2], float(result.x[2])


def _resample(polygon: np.ndarray, count: int) -> np.ndarray:
    """``count`` points evenly spaced by arc length round a closed polyline."""
    closed = np.vstack([polygon, polygon[:1]])
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    t = np.linspace(0.0, arc[-1], count, endpoint=False)
    return np.column_stack([np.interp(t, arc, closed[:, 0]), np.interp(t, arc, closed[:, 1])])


def edge_circle(polygon: np.ndarray, end: str, tolerance: float = EDGE_TOLERANCE
                ) -> EdgeCircle:
    """Circle of the leading (``end="leading"``) or trailing edge of a closed section polyline
    (n, 2; m): the longest arc round the end that a circle fits within an RMS of
    ``max(0.2 % r, tolerance)`` (m), refined by geometric least squares (module docstring)."""
    if end not in ("leading", "trailing"):
        raise ValueError(f"end must be 'leading' or 'trailing' (got {end!r})")
    polygon = np.asarray(polygon, dtype=np.float64)
    lead, trail, _ = chord_line(polygon)
    direction = (trail - lead) / np.linalg.norm(trail - lead)
    chord = float(np.ptp(polygon @ direction))
    dense = _resample(polygon, EDGE_SAMPLES * max(1, math.ceil(
        np.sum(np.linalg.norm(np.diff(polygon, axis=0), axis=1)) / (2.0 * chord))))
    n = len(dense)
    along = dense @ direction
    tip = int(np.argmin(along) if end == "leading" else np.argmax(along))
    def fits(first: int, last: int) -> bool:
        chosen = dense[np.arange(first, last + 1) % n]
        centre, radius = fit_circle(chosen)
        error = np.abs(np.linalg.norm(chosen - centre, axis=1) - radius)
        return bool(np.sqrt(np.mean(error**2)) <= max(EDGE_RELATIVE * radius, tolerance))

    # grow each end of the arc on its own (the end point along the chord need not be the
    # middle of the edge circle's arc on a cambered section) while the circle still fits
    first, last = tip - 3, tip + 3
    if not fits(first, last):
        raise ValueError(f"no circular {end} edge: even the shortest arc round the end "
                         f"deviates more than {tolerance * 1e3:.3g} mm (RMS) from a circle")
    grown = True
    while grown and last - first < n // 2:
        grown = False
        step = max(1, int((last - first) * (ARC_GROWTH - 1.0)))
        if fits(first - step, last):
            first, grown = first - step, True
        if fits(first, last + step):
            last, grown = last + step, True
    best = dense[np.arange(first, last + 1) % n]
    # the arc runs on past each tangent point until a side leaves the circle by the allowance
    # δ, an arc length √(2 r δ) (a tangent leaves by t²/2r): drop that much from both ends
    _, radius = fit_circle(best)
    allowance = max(EDGE_RELATIVE * radius, tolerance)
    spacing = float(np.linalg.norm(dense[1] - dense[0]))
    trim = int(math.sqrt(2.0 * radius * OVERRUN * allowance) / spacing)
    if len(best) - 2 * trim >= 5:
        best = best[trim:len(best) - trim]
    centre, radius = refine_circle(best, *fit_circle(best))
    rms = float(np.sqrt(np.mean((np.linalg.norm(best - centre, axis=1) - radius) ** 2)))
    return EdgeCircle(centre=centre, radius=radius, rms=rms, points=len(best))


def row_section(polygon: np.ndarray, name: str = "section", radius: float = float("nan"),
                pitch: float | None = None) -> RowSection:
    """All metrics of one section polyline (n, 2; m) in the blade frame; the throat only with
    a ``pitch`` (m)."""
    metrics = section_metrics(polygon, pitch)
    return RowSection(name=name, radius=radius, chord=metrics.chord, stagger=metrics.stagger,
                      max_thickness=metrics.max_thickness, throat=metrics.throat,
                      pitch=float("nan") if pitch is None else pitch,
                      leading_edge=edge_circle(polygon, "leading"),
                      trailing_edge=edge_circle(polygon, "trailing"))


def blade_row_metrics(vertices: np.ndarray, triangles: np.ndarray,
                      blade_count: int | None = None, pitch: float | None = None,
                      sections: tuple[tuple[str, float], ...] = SPAN_SECTIONS
                      ) -> list[RowSection]:
    """Metrics of a closed blade triangulation (m, blade frame) at ``sections`` (name, span
    fraction between the lowest and highest vertex). The throat needs the pitch: a fixed
    ``pitch`` (m) or ``blade_count`` N (pitch 2πz/N at radius z); with neither it is NaN."""
    if blade_count is not None and pitch is not None:
        raise ValueError("give blade_count or pitch, not both")
    if blade_count is not None and blade_count < 1:
        raise ValueError(f"blade_count must be a positive count (got {blade_count})")
    if pitch is not None and not pitch > 0.0:
        raise ValueError(f"pitch must be positive, m (got {pitch})")
    low, high = float(vertices[:, 2].min()), float(vertices[:, 2].max())
    result = []
    for name, fraction in sections:
        z = low + fraction * (high - low)
        at = 2.0 * math.pi * z / blade_count if blade_count is not None else pitch
        polygon = section_loops(vertices, triangles, z)[0][0]
        result.append(row_section(polygon, name, z, at))
    return result


# --- reports -------------------------------------------------------------------------------------

#: Columns of the report CSV (as :func:`~steamtwin.geometry.fidelity.write_report`'s).
CSV_FIELDS = ["metric", "unit", "truth", "measured", "error"]


def design_edge_rows(blade: Blade, vertices: np.ndarray, triangles: np.ndarray
                     ) -> list[dict[str, float | str]]:
    """Leading- and trailing-edge radii (mm) of a reconstructed triangulation (m, blade frame)
    against the exact sections of ``blade``, at the reconstruction report's sections
    (``<metric>@<section>`` rows: truth, measured, error)."""
    rows = []
    for name, fraction in METRIC_SECTIONS:
        radius = blade.design.hub_radius + fraction * blade.design.span
        truth = truth_section(blade, radius)
        measured = section_loops(vertices, triangles, radius)[0][0]
        for metric, end in (("le_radius", "leading"), ("te_radius", "trailing")):
            t = edge_circle(truth, end).radius * 1e3
            m = edge_circle(measured, end).radius * 1e3
            rows.append({"metric": f"{metric}@{name}", "unit": "mm", "truth": t,
                         "measured": m, "error": m - t})
    return rows


def write_row_metrics(sections: list[RowSection], path: str | Path, extra: dict | None = None
                      ) -> tuple[Path, Path]:
    """Write the metrics of a blade without a nominal row as ``<path>.json`` (``row_metrics``
    per section, plus ``extra``) and ``<path>.csv`` (``<metric>@<section>`` rows, measured
    only; mm, deg)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    json_path, csv_path = path.with_suffix(".json"), path.with_suffix(".csv")
    document = {"row": None, "row_metrics": [
        {"section": s.name, "radius_mm": s.radius * 1e3,
         "metrics": {r["metric"]: r["measured"] for r in s.rows()}} for s in sections],
        **(extra or {})}
    json_path.write_text(json.dumps(document, indent=2, default=float), encoding="utf-8")
    with csv_path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=CSV_FIELDS)
        writer.writeheader()
        for section in sections:
            for row in section.rows():
                writer.writerow({"metric": f"{row['metric']}@{section.name}",
                                 "unit": row["unit"], "truth": "",
                                 "measured": row["measured"], "error": ""})
    return json_path, csv_path


def append_report_rows(json_path: Path, csv_path: Path, key: str,
                       rows: list[dict[str, float | str]]) -> None:
    """Add ``rows`` (``CSV_FIELDS``) to a written report: under ``key`` in the JSON and at the
    end of the CSV."""
    document = json.loads(json_path.read_text(encoding="utf-8"))
    document[key] = rows
    json_path.write_text(json.dumps(document, indent=2, default=float), encoding="utf-8")
    with csv_path.open("a", newline="", encoding="utf-8") as handle:
        csv.DictWriter(handle, fieldnames=CSV_FIELDS).writerows(rows)
