"""``calibrate`` command on a small historian export of the virtual plant."""

from __future__ import annotations

import typer
from typer.testing import CliRunner

from steamtwin.cli.calibrate import calibrate
from steamtwin.dcs.plant import write_plant
from steamtwin.model.parameters import ModelParameters


def test_calibrate_command(plant_run, tmp_path):
    paths = write_plant(plant_run, tmp_path / "plant", file_format="csv")
    app = typer.Typer()
    app.command()(calibrate)
    app.command("other")(lambda: None)  # keep 'calibrate' a sub-command
    start, end = plant_run.measured.index[-300], plant_run.measured.index[-1]
    arguments = [
        "calibrate", "--data", str(paths["historian"]), "--tags", str(paths["tag_map"]),
        "--out", str(tmp_path / "params.json"), "--population", "6", "--generations", "2",
        "--window", f"{start.isoformat()}/{end.isoformat()}", "--workers", "1",
    ]
    result = CliRunner().invoke(app, arguments)
    assert result.exit_code == 0, result.output
    assert "RMSE before" in result.output
    fitted = ModelParameters.from_json(tmp_path / "params.json")
    assert (tmp_path / "params.history.csv").exists()
    assert (tmp_path / "params.checkpoint").exists()
    (tmp_path / "params.json").unlink()
    resumed = CliRunner().invoke(app, [*arguments, "--resume"])
    assert resumed.exit_code == 0, resumed.output
    assert ModelParameters.from_json(tmp_path / "params.json") == fitted
    other_seed = CliRunner().invoke(app, [*arguments, "--resume", "--seed", "9"])
    assert other_seed.exit_code == 2 and "other settings or data" in other_seed.output

    no_window = CliRunner().invoke(app, [
        "calibrate", "--data", str(paths["historian"]), "--tags", str(paths["tag_map"]),
        "--out", str(tmp_path / "p2.json"), "--generations", "2", "--population", "4",
    ])
    assert no_window.exit_code == 2
    assert "steady 2-h window" in no_window.output
