"""What the ``steamtwin geometry`` commands share: the one-line error exit and the turbine spec."""

from __future__ import annotations

from pathlib import Path
from typing import NoReturn

import typer

from steamtwin.cli.paths import prepare_output_file


def fail(message: str) -> NoReturn:
    """Print ``error: message`` and exit with code 2 (bad input)."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def load_turbine(turbine: str):  # returns a steamtwin.spec.TurbineSpec
    """The spec of a built-in turbine name or a spec TOML path, or a clear error exit."""
    from steamtwin.spec import SpecError, load_spec

    try:
        return load_spec(turbine)
    except (SpecError, OSError, ValueError) as error:
        fail(f"cannot load turbine {turbine!r}: {error}")


def point_cloud_out(path: Path) -> Path:
    """``--out`` of a point cloud: a known format, a writable file."""
    from steamtwin.geometry.pointcloud import SUFFIXES

    if path.suffix.lower() not in SUFFIXES:
        fail(f"--out {path}: unknown point-cloud format {path.suffix!r}; use "
             f"{', '.join(SUFFIXES)}")
    return prepare_output_file(path, "--out")
