"""``calibrate`` command on a small historian export of the virtual plant."""

from __future__ import annotations

import pandas as pd
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


def test_calibrate_surrogate_with_report(plant_run, tmp_path):
    paths = write_plant(plant_run, tmp_path / "plant", file_format="csv")
    app = typer.Typer()
    app.command()(calibrate)
    app.command("other")(lambda: None)
    start, end = plant_run.measured.index[-600], plant_run.measured.index[-1]
    result = CliRunner().invoke(app, [
        "calibrate", "--data", str(paths["historian"]), "--tags", str(paths["tag_map"]),
        "--out", str(tmp_path / "params.json"), "--surrogate", "--max-evaluations", "40",
        "--window", f"{start.isoformat()}/{end.isoformat()}", "--workers", "1",
        "--report", str(tmp_path / "report"),
    ])
    assert result.exit_code == 0, result.output
    assert "evaluations: 40" in result.output or "evaluations: 3" in result.output
    assert "not identifiable" in result.output  # a 10-min hold cannot see heat transfer
    table6 = pd.read_csv(tmp_path / "report" / "table6_rmse.csv", index_col="condition")
    assert table6["rmse_calibrated_K"].iloc[0] <= table6["rmse_empirical_K"].iloc[0]
    assert (tmp_path / "report" / "figure8_temperatures.png").stat().st_size > 10_000
    assert (tmp_path / "report" / "identifiability.csv").exists()
    both = CliRunner().invoke(app, [
        "calibrate", "--data", str(paths["historian"]), "--tags", str(paths["tag_map"]),
        "--out", str(tmp_path / "p.json"), "--surrogate", "--resume"])
    assert both.exit_code == 2 and "surrogate mode has no checkpoint" in both.output


def test_calibrate_online_command(plant_run, tmp_path):
    from steamtwin.cli.main import app

    paths = write_plant(plant_run, tmp_path / "plant")
    result = CliRunner().invoke(app, [
        "calibrate-online", "--data", str(paths["historian"]), "--tags", str(paths["tag_map"]),
        "--out", str(tmp_path / "online"), "--window-minutes", "10", "--every-minutes", "10",
        "--population", "4", "--generations", "1", "--first-generations", "2",
    ])
    assert result.exit_code == 0, result.output
    trajectory = pd.read_csv(tmp_path / "online" / "trajectory.csv")
    hours = (plant_run.measured.index[-1] - plant_run.measured.index[0]).total_seconds() / 3600
    assert len(trajectory) == int(hours * 6)
    live = ModelParameters.from_json(tmp_path / "online" / "params.json")
    last = trajectory.iloc[-1]
    assert live.flow_coefficient == last["flow_coefficient"]
    assert (tmp_path / "online" / "trajectory.png").stat().st_size > 10_000
