"""The ``steamtwin`` command: one sub-command per pipeline stage, plus ``demo``."""

from __future__ import annotations

import typer

from steamtwin.cli.calibrate import calibrate, calibrate_online
from steamtwin.cli.dcs import dcs_app
from steamtwin.cli.demo import demo
from steamtwin.cli.geometry import geometry_app
from steamtwin.cli.plant import plant
from steamtwin.cli.rom import rom_app
from steamtwin.cli.simulate import simulate
from steamtwin.cli.turbine import turbine_app
from steamtwin.cli.validate import validate

app = typer.Typer(
    name="steamtwin",
    help="Digital twin of a steam turbine in deep peak-shaving operation.\n\n"
    "Example: steamtwin demo --out demo-output",
    no_args_is_help=True,
    add_completion=False,
)
app.add_typer(turbine_app, name="turbine")
app.add_typer(dcs_app, name="dcs")
app.add_typer(geometry_app, name="geometry")
app.add_typer(rom_app, name="rom")
app.command()(simulate)
app.command()(plant)
app.command()(calibrate)
app.command("calibrate-online")(calibrate_online)
app.command()(validate)
app.command()(demo)
