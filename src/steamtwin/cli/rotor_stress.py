"""``steamtwin rotor stress``: the HP rotor's stress and life over historian records, as a report.

Parsing, one library call — :func:`steamtwin.rotor.report.rotor_stress` over the histories
:func:`~steamtwin.calibration.histories.load_histories` read (the quality gate of
``calibrate``) — and printing.
"""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console

from steamtwin.calibration.histories import load_histories
from steamtwin.cli.calibrate_output import print_quality, progress_bar
from steamtwin.cli.paths import OutputPathError, prepare_output_folder
from steamtwin.dcs.history import OVERRIDE_OPTION, DataQualityError
from steamtwin.model.parameters import ModelParameters, ParameterError
from steamtwin.rotor.geometry import rotor_geometry
from steamtwin.rotor.report import checked_allowable, rotor_stress
from steamtwin.spec import SpecError, load_spec
from steamtwin.units import parse_quantity

__all__ = ["stress"]


def stress(
    data: list[Path] = typer.Option(
        ..., help="Historian export: CSV or Parquet, wide or long; repeat for records that "
        "follow each other (the rotor's state carries over a gap of up to a minute)."),
    tags: list[Path] = typer.Option(
        ..., help="Tag map (TOML): one for every --data, or one per --data in the same order."),
    report: Path = typer.Option(..., help="Folder for report.html, rotor_stress.parquet/.csv, "
                                "rotor_cycles.csv, rotor_life.json and the figures."),
    turbine: str = typer.Option("reference", help="'reference' or a turbine spec TOML with a "
                                "\\[rotor] section."),
    params: Path | None = typer.Option(
        None, help="Parameter JSON of the twin (from 'steamtwin calibrate'): its heat-transfer "
        "multiplier sets the rotor's steam-side htc. Default: empirical (1, 1, 1)."),
    allowable: str | None = typer.Option(
        None, help="Allowable peak von Mises stress at the groove root, with its unit (e.g. "
        "'450 MPa'). Default: 3 S_m = R_m at the groove's hottest temperature (ASME III "
        "NB-3222.2)."),
    mesh_size: float | None = typer.Option(
        None, min=1e-3, help="Element size of the rotor mesh far from the groove (m); "
        "default: the rotor model's."),
    accept_quality_errors: bool = typer.Option(
        False, OVERRIDE_OPTION, help="Go on despite error-level data-quality findings; the bad "
        "samples stay excluded (the inputs held at their last good value)."),
) -> None:
    """Thermal and centrifugal stress of the HP rotor and the life it consumed over a record.

    Reads and cleans the historian export(s) with their tag map, fits the rotor model to the
    turbine (mesh, FEM, transient ROM on the unit's own ramps), runs the ROM over the record,
    counts rainflow cycles at the heat-relief groove and sums fatigue (Manson–Coffin–Basquin,
    Neuber, Miner) and creep (Larson–Miller) damage per ramp and per day. Writes the time
    series, the cycles, the life (JSON) and report.html with stress vs time and the allowable,
    metal and steam temperatures, the rainflow matrix and the life per ramp; prints the peak
    stress and the life consumed.

    Example: steamtwin rotor stress --data plant-data/historian.parquet --tags plant-data/tags.toml --params params.json --report rotor-report
    """  # noqa: E501
    console = Console(stderr=True)
    try:
        allowable_pa = (None if allowable is None else checked_allowable(
            parse_quantity(allowable, "Pa", "--allowable"), "--allowable"))
        prepare_output_folder(report, "--report")
        spec = load_spec(turbine)
        rotor_geometry(spec)  # a spec without [rotor] is refused before the data are read
        parameters = None if params is None else ModelParameters.from_json(params)
        histories = load_histories(data, tags, accept_errors=accept_quality_errors)
        print_quality(histories, console)
        with progress_bar(console, "fitting the rotor model") as progress:
            result = rotor_stress(
                histories, spec, report, params=parameters, allowable_pa=allowable_pa,
                mesh_size=mesh_size, progress=progress,
                settings={"data": [str(p) for p in data], "tag maps": [str(p) for p in tags],
                          "turbine": turbine, "params": str(params) if params else "empirical"})
    except DataQualityError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=1) from None
    except (SpecError, ParameterError, OutputPathError, ValueError, OSError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    summary = result.life.summary()
    peak = float(result.frame["groove_von_mises"].max())
    typer.echo(f"{len(result.frame)} samples; peak von Mises at the groove "
               f"{peak / 1e6:.0f} MPa, allowable {result.allowable_pa / 1e6:.0f} MPa "
               f"({result.allowable_source}): "
               + ("within" if peak <= result.allowable_pa else "EXCEEDED"))
    typer.echo(f"life consumed: fatigue {summary['fatigue_damage']:.3g}, creep "
               f"{summary['creep_damage']:.3g} over {len(result.life.per_day)} day(s), "
               f"{len(result.life.per_ramp)} ramp(s)")
    typer.echo(f"wrote {result.files['report.html']} (+ "
               + ", ".join(name for name in result.files if name != "report.html") + ")")
