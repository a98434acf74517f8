"""What ``steamtwin geometry reconstruct`` prints: the source as a cloud, the blade frame, the
reconstruction, the CAD export and the reports (from a
:class:`~steamtwin.geometry.workflow.ReconstructionRun`)."""

from __future__ import annotations

import math
from pathlib import Path

import typer


def _vector(v) -> str:
    return "(" + ", ".join(f"{c:+.5f}" for c in v) + ")"


def echo_frame(found) -> None:  # found: steamtwin.geometry.frame.BladeFrame
    """Print a blade frame from the data: axes, transformation, the rule behind each choice."""
    typer.echo(f"blade frame from the data: span axis (hub → tip) {_vector(found.span_axis)}, "
               f"chord (leading → trailing edge) {_vector(found.chord_direction)}, span "
               f"{found.span * 1e3:.3f} mm")
    for name, rule in found.rules.items():
        typer.echo(f"  {name}: {rule}")
    typer.echo("  scan → blade: rotation " + ", ".join(_vector(r) for r in found.rotation)
               + f", translation {_vector(found.translation * 1e3)} mm")
    if found.hub_tip_ambiguous:
        typer.echo("  hub and tip AMBIGUOUS: the data cannot tell them apart; check, or give "
                   "--hub-end")
    if found.edges_ambiguous:
        typer.echo("  leading and trailing edge AMBIGUOUS: the section's ends are alike")


def echo_reconstruction(run, source: Path) -> None:  # run: workflow.ReconstructionRun
    """Print what :func:`~steamtwin.geometry.workflow.reconstruct_source` did."""
    loaded, result = run.loaded, run.result
    if loaded.fused is not None:
        typer.echo(f"fused {sum(loaded.fused.report.input_points)} points of "
                   f"{len(loaded.fused.report.input_points)} views into {len(loaded.cloud)} "
                   "points")
    if loaded.sampling is not None:
        s = loaded.sampling
        typer.echo(f"sampled {s.samples} points over the {s.triangles} triangles of {source} "
                   f"({s.area * 1e6:.1f} mm², {s.degenerate} degenerate left out, "
                   f"{s.vertices_added} vertices added)")
    for note in result.notes:
        typer.echo(note)
    if result.fit_rms is not None:
        typer.echo(f"best fit to the nominal blade {result.row}: RMS "
                   f"{result.fit_rms * 1e3:.4f} mm")
    if result.frame is not None:
        echo_frame(result.frame)
    summary = result.reconstruction.summary()
    counts = ", ".join(f"{k} {v}" for k, v in summary["patch_points"].items())
    typer.echo(f"wrote {run.stl}: {summary['triangles']} triangles, watertight, volume "
               f"{summary['volume_cm3']:.4f} cm³")
    typer.echo(f"  points per patch: {counts}; left out by the fit: "
               f"{summary['trimmed_by_fit']}")
    typer.echo(f"  side fit: RMS {summary['side_fit_rms_mm']:.4f} mm, max "
               f"{summary['side_fit_max_mm']:.4f} mm, {summary['breakpoints']} knots round "
               "the profile")
    if run.cad is not None:
        shape = "a solid" if run.cad.solid else "surfaces only (the kernel did not close them)"
        typer.echo(f"  CAD: {', '.join(str(p) for p in run.cad.paths)}: {shape}, "
                   f"{run.cad.faces} faces, {run.cad.control_points[0]}×"
                   f"{run.cad.control_points[1]} control points (mm, blade frame)")
    if run.report is not None:
        _echo_report(run.report)


def _echo_report(files) -> None:  # files: workflow.ReconstructionReport
    if files.fidelity is not None:
        d = files.fidelity.deviation
        typer.echo(f"  deviation from the nominal blade: mean {d.mean * 1e3:.4f} mm, RMS "
                   f"{d.rms * 1e3:.4f} mm, max {d.max * 1e3:.4f} mm, Hausdorff "
                   f"{d.hausdorff * 1e3:.4f} mm")
        throat = files.fidelity.extra["throat_area"]
        typer.echo(f"  throat area N·∫o dr: {throat['measured_mm2']:.1f} mm² against the "
                   f"design blade's {throat['design_mm2']:.1f} mm² (ratio "
                   f"{throat['ratio']:.5f})")
        for section in files.fidelity.extra["sections"]:
            errors = ", ".join(f"{m['metric']} {m['error']:+.4f} {m['unit']}"
                               for m in section["metrics"])
            typer.echo(f"  {section['section']} ({section['radius_mm']:.1f} mm): {errors}")
    for section in files.sections or []:
        values = ", ".join(f"{r['metric']} {r['measured']:.4f} {r['unit']}"
                           for r in section.rows() if math.isfinite(r["measured"]))
        typer.echo(f"  {section.name} ({section.radius * 1e3:.1f} mm): {values}")
    typer.echo(f"  reports {files.json}, {files.csv}, {files.png}")
