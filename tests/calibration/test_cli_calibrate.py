"""``calibrate`` command on a small historian export of the virtual plant."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
import typer
from typer.testing import CliRunner

from steamtwin.cli.calibrate import calibrate
from steamtwin.dcs.plant import write_plant
from steamtwin.model.parameters import ModelParameters

pytestmark = pytest.mark.slow  # 8 s of the full suite (2026-11-27): not in the quick loop


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
        "--no-ramps",
    ])
    assert no_window.exit_code == 2
    assert "historian.csv: no steady window of at least 60 min" in no_window.output


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
        "--report", str(tmp_path / "report"), "--sensor-bias",
    ])
    assert result.exit_code == 0, result.output
    assert "evaluations: 40" in result.output or "evaluations: 3" in result.output
    assert "not identifiable" in result.output  # a 10-min hold cannot see heat transfer
    table6 = pd.read_csv(tmp_path / "report" / "table6_rmse.csv", index_col="condition")
    assert table6["rmse_calibrated_K"].iloc[0] <= table6["rmse_empirical_K"].iloc[0]
    # with the thermocouples' offsets estimated, Table 6 also scores the twin as delivered:
    # offsets shrunk from the windows' mean residuals can only lower the RMSE there
    assert table6["rmse_delivered_K"].iloc[0] <= table6["rmse_calibrated_K"].iloc[0]
    assert "delivered_over_instrument" in table6.columns  # NaN: this tag map gives no σ
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


def test_joint_calibration_over_two_files(plant_run, tmp_path):
    first = write_plant(plant_run, tmp_path / "a", file_format="csv")
    second = write_plant(plant_run, tmp_path / "b", file_format="csv")
    text = second["tag_map"].read_text()
    for name in ("control_stage_temperature", "hp_exhaust_temperature",
                 "hp_inner_casing_temperature"):  # the second file's map states its noise
        text = text.replace(f"[signals.{name}]\n", f"[signals.{name}]\nnoise = 0.4\n")
    second["tag_map"].write_text(text)
    app = typer.Typer()
    app.command()(calibrate)
    app.command("other")(lambda: None)
    common = ["--out", str(tmp_path / "params.json"), "--population", "4", "--generations",
              "1", "--workers", "1", "--min-steady-minutes", "5"]
    result = CliRunner().invoke(app, [
        "calibrate", "--data", str(first["historian"]), "--data", str(second["historian"]),
        "--tags", str(first["tag_map"]), "--tags", str(second["tag_map"]), *common,
        "--prior", "friction_coefficient=lognormal:1.1:0.2", "--report", str(tmp_path / "r")])
    assert result.exit_code == 0, result.output
    assert "from 2 file(s)" in result.output and "ramps" in result.output
    assert "95 % interval" in result.output
    document = json.loads((tmp_path / "params.json").read_text())
    assert document["schema_version"] == 2
    assert document["priors"]["friction_coefficient"]["center"] == 1.1
    assert set(document["posterior"]["intervals"]) == {
        "flow_coefficient", "friction_coefficient", "heat_transfer_coefficient"}
    table6 = pd.read_csv(tmp_path / "r" / "table6_rmse.csv", index_col=0)
    # σ where a tag map gives it (file b: 0.4 K), NaN where none does (file a)
    assert "ramps" in table6.index and np.allclose(table6["instrument_error_K"], 0.4)
    assert (tmp_path / "r" / "table6_parameters.csv").exists()

    missing = tmp_path / "nowhere.csv"
    bad = CliRunner().invoke(app, [
        "calibrate", "--data", str(first["historian"]), "--data", str(missing),
        "--tags", str(first["tag_map"]), *common])
    assert bad.exit_code == 2 and str(missing) in bad.output
    counts = CliRunner().invoke(app, [
        "calibrate", "--data", str(first["historian"]), "--data", str(second["historian"]),
        "--data", str(second["historian"]), "--tags", str(first["tag_map"]),
        "--tags", str(second["tag_map"]), *common])
    assert counts.exit_code == 2 and "one --tags for all 3 --data files" in counts.output


def test_calibrate_with_the_control_stage_pressure_as_witness(plant_run, tmp_path):
    """--pressure-witness fits the control-stage pressure beside the temperatures (σ typical
    25 kPa, the tag map states none), with a transmitter bias under --sensor-bias: the params
    record it among the sensors and the RMSE stays a temperature RMSE (K)."""
    paths = write_plant(plant_run, tmp_path / "plant", file_format="csv")
    app = typer.Typer()
    app.command()(calibrate)
    app.command("other")(lambda: None)
    start, end = plant_run.measured.index[-600], plant_run.measured.index[-1]
    arguments = ["calibrate", "--data", str(paths["historian"]), "--tags",
                 str(paths["tag_map"]), "--surrogate", "--max-evaluations", "40",
                 "--window", f"{start.isoformat()}/{end.isoformat()}", "--workers", "1",
                 "--sensor-bias"]
    result = CliRunner().invoke(app, [*arguments, "--out", str(tmp_path / "p.json"),
                                      "--pressure-witness"])
    assert result.exit_code == 0, result.output
    document = json.loads((tmp_path / "p.json").read_text())
    assert document["calibration"]["sensors"][-1] == "control_stage_pressure"
    assert 0.0 < document["calibration"]["rmse_K"] < 5.0
    tags = paths["tag_map"].read_text().replace(
        '[signals.control_stage_pressure]\ncolumn = "10MAA10CP001"\nunit = "MPa"\n'
        'range = [0.0, 20.0]\n', "")
    assert "control_stage_pressure" not in tags
    (tmp_path / "no-p1.toml").write_text(tags)
    missing = CliRunner().invoke(app, [*arguments[:4], str(tmp_path / "no-p1.toml"),
                                       *arguments[5:], "--out", str(tmp_path / "q.json"),
                                       "--pressure-witness"])
    assert missing.exit_code == 2
    assert "--pressure-witness" in missing.output and "control_stage_pressure" in missing.output
