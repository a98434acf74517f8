"""``steamtwin geometry``: virtual blade scans, scan preprocessing, surface reconstruction and
blade meshes — each command parses its options, makes one call into
:mod:`steamtwin.geometry.workflow` and prints the result."""

from __future__ import annotations

import typer

from steamtwin.cli.geometry_mesh import assemble, mesh, uncertainty
from steamtwin.cli.geometry_reconstruct import reconstruct
from steamtwin.cli.geometry_scan import preprocess, scan

geometry_app = typer.Typer(
    help="Blade geometry: virtual scans, scan preprocessing, reconstruction, simulation meshes.",
    no_args_is_help=True,
)

for command in (scan, preprocess, reconstruct, mesh, assemble, uncertainty):
    geometry_app.command()(command)
