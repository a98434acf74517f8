"""Reports of a reconstruction: its fidelity against the exact blade (deviation, row metrics at
hub, mid and tip, the row's throat area), the report files (JSON + CSV) and the deviation map
(PNG)."""

from __future__ import annotations

import csv
from pathlib import Path

import matplotlib
import numpy as np

from steamtwin.geometry.fidelity import (
    FidelityReport,
    blade_distance,
    section_metrics,
    section_pitch,
    surface_deviation,
    surface_samples,
    truth_section,
    write_report,
)
from steamtwin.geometry.mesh_sections import section_loops
from steamtwin.geometry.profile import Blade
from steamtwin.geometry.reconstruct import METRIC_SECTIONS, Reconstruction
from steamtwin.geometry.uncertainty import throat_area


def reconstruction_fidelity(blade: Blade, vertices: np.ndarray, triangles: np.ndarray,
                            samples: int = 100_000,
                            random_state: np.random.Generator | int | None = 0,
                            extra: dict | None = None) -> FidelityReport:
    """Deviation of a reconstructed surface from the exact blade and its row metrics.

    The deviation is measured at ``samples`` points spread uniformly over the reconstructed
    triangles (and back from as many on the exact surface for the Hausdorff distance); row
    metrics of the sections at :data:`METRIC_SECTIONS` against the exact sections there — the
    report's ``truth``/``measured`` are the mid-span ones, all three are in ``extra``.
    """
    rng = np.random.default_rng(random_state)
    points = surface_samples(vertices, triangles, samples, rng)
    deviation = surface_deviation(blade, points, vertices, triangles, samples=samples,
                                   random_state=rng)
    sections = {}
    for name, fraction in METRIC_SECTIONS:
        radius = blade.design.hub_radius + fraction * blade.design.span
        pitch = section_pitch(blade, radius)
        truth = section_metrics(truth_section(blade, radius), pitch)
        measured = section_metrics(section_loops(vertices, triangles, radius)[0][0], pitch)
        sections[name] = (radius, truth, measured)
    _, truth, measured = sections["mid"]
    report = FidelityReport(blade.row, deviation, truth, measured, dict(extra or {}))
    report.extra["throat_area"] = row_throat_area(
        blade, np.array([radius for radius, _, _ in sections.values()]),
        np.array([t.throat for _, t, _ in sections.values()]),
        np.array([m.throat for _, _, m in sections.values()]))
    report.extra["sections"] = [
        {"section": name, "radius_mm": radius * 1e3,
         "metrics": FidelityReport(blade.row, deviation, t, m, {}).metric_rows()}
        for name, (radius, t, m) in sections.items()]
    return report


def row_throat_area(blade: Blade, radii: np.ndarray, design: np.ndarray, measured: np.ndarray
                    ) -> dict[str, float | list[float]]:
    """The row's throat area N·∫o(r)dr of the design blade and of the measured one, from the
    throats (m) at ``radii`` (m), and their ratio — the multiplier of the stage's flow capacity
    (:func:`~steamtwin.geometry.uncertainty.throat_area`); report units mm²."""
    design_area = throat_area(blade, radii, design)
    measured_area = throat_area(blade, radii, measured)
    return {"design_mm2": design_area * 1e6, "measured_mm2": measured_area * 1e6,
            "ratio": measured_area / design_area,
            "radii_mm": [float(r) * 1e3 for r in radii]}


def write_reconstruction_report(report: FidelityReport, path: str | Path) -> tuple[Path, Path]:
    """:func:`~steamtwin.geometry.fidelity.write_report`, with the hub and tip metrics added to
    the CSV as ``<metric>@hub`` / ``<metric>@tip`` rows and, when the report has it, the row's
    throat area (:func:`row_throat_area`) as a ``throat_area`` row in mm²."""
    json_path, csv_path = write_report(report, path)
    with csv_path.open("a", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=["metric", "unit", "truth", "measured",
                                                    "error"])
        for section in report.extra.get("sections", []):
            if section["section"] == "mid":
                continue
            for row in section["metrics"]:
                writer.writerow({**row, "metric": f"{row['metric']}@{section['section']}"})
        if "throat_area" in report.extra:
            area = report.extra["throat_area"]
            writer.writerow({"metric": "throat_area", "unit": "mm2",
                             "truth": area["design_mm2"], "measured": area["measured_mm2"],
                             "error": area["measured_mm2"] - area["design_mm2"]})
    return json_path, csv_path


def write_deviation_map(reconstruction: Reconstruction, path: str | Path,
                        blade: Blade | None = None) -> Path:
    """PNG of the side unrolled (arc length round the mid-span section from the trailing edge ×
    radius, mm): the fit residual of every side point and, with the exact ``blade``, the
    distance of the reconstructed surface from it; colours in mm, patch boundaries marked."""
    matplotlib.use("Agg")  # before pyplot: no display needed (and none on a server)
    import matplotlib.pyplot as plt  # deferred: pyplot loads a GUI backend machinery (~0.5 s)

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    surface = reconstruction.surface
    fine = np.linspace(0.0, 1.0, 4001)
    curve = surface(fine, 0.5 * (surface.z_knots[0] + surface.z_knots[-1]))
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(curve, axis=0), axis=1))])

    def unrolled(s: np.ndarray) -> np.ndarray:
        return np.interp(s, fine, arc) * 1e3

    panels = 2 if blade is not None else 1
    figure, axes = plt.subplots(panels, 1, figsize=(11, 3.6 * panels), squeeze=False)
    chosen = ~np.isnan(reconstruction.parameters) & reconstruction.inliers
    residual = reconstruction.residuals[chosen] * 1e3
    limit = float(np.percentile(np.abs(residual), 99.0))
    image = axes[0, 0].scatter(unrolled(reconstruction.parameters[chosen]),
                               reconstruction.points[chosen, 2] * 1e3, c=residual, s=1.0,
                               cmap="coolwarm", vmin=-limit, vmax=limit, rasterized=True)
    figure.colorbar(image, ax=axes[0, 0], label="fit residual (mm, + outside)")
    axes[0, 0].set_title("side points: distance from the fitted B-spline surface")
    if blade is not None:
        columns = reconstruction.ring_parameters
        rings = reconstruction.vertices.reshape(-1, len(columns), 3)
        deviation = blade_distance(blade, rings.reshape(-1, 3)).reshape(rings.shape[:2]) * 1e3
        image = axes[1, 0].pcolormesh(np.broadcast_to(unrolled(columns), deviation.shape),
                                      rings[:, :, 2] * 1e3, deviation, shading="gouraud",
                                      cmap="viridis", vmin=0.0,
                                      vmax=float(np.percentile(deviation, 99.5)),
                                      rasterized=True)
        figure.colorbar(image, ax=axes[1, 0], label="deviation (mm)")
        axes[1, 0].set_title(f"reconstructed surface: distance from the exact blade "
                             f"{blade.row}")
    starts = sorted((value, key.split("|")[1]) for key, value in
                    reconstruction.boundaries.items())
    for ax in axes[:, 0]:
        for k, (value, name) in enumerate(starts):
            end = starts[k + 1][0] if k + 1 < len(starts) else starts[0][0] + 1.0
            ax.axvline(float(unrolled(np.array([value]))[0]), color="k", lw=0.5, ls="--")
            middle = float(unrolled(np.array([np.mod(0.5 * (value + end), 1.0)]))[0])
            ax.annotate(name.replace("_", " "), (middle, 1.0), ha="center", va="bottom",
                        xycoords=("data", "axes fraction"), fontsize=7)
        ax.set_xlim(0.0, arc[-1] * 1e3)
        ax.set_xlabel("arc length from the trailing edge, anticlockwise (mm)")
        ax.set_ylabel("radius z (mm)")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path
