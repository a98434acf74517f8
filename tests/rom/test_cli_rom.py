"""``steamtwin rom build | info | predict`` end to end on a coarse blade."""

from __future__ import annotations

import dataclasses
import json

import meshio
import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from steamtwin.cli.rom import rom_app
from steamtwin.dcs.plant import run_plant, write_plant
from steamtwin.dcs.tagmap import load_tag_map, write_tag_map

pytestmark = pytest.mark.slow  # 7 s of the full suite (2026-11-27): not in the quick loop


@pytest.fixture(scope="module")
def plant_files(tmp_path_factory):
    run = run_plant("deep-peak-50", hours=0.1, random_state=2)
    return write_plant(run, tmp_path_factory.mktemp("plant"), file_format="csv"), run


def test_help_has_examples():
    runner = CliRunner()
    for command in ("build", "predict", "info"):
        result = runner.invoke(rom_app, [command, "--help"])
        assert result.exit_code == 0 and "Example:" in result.output


def test_build_info_predict(tmp_path, plant_files, reference_model):
    runner = CliRunner()
    rom_path = tmp_path / "rom.npz"
    built = runner.invoke(rom_app, ["build", "--turbine", "reference", "--snapshots", "8",
                                    "--element-size", "0.006", "--workers", "1",
                                    "--energy", "0.9999", "--out", str(rom_path)])
    assert built.exit_code == 0, built.output
    assert "modes" in built.output and rom_path.exists()
    info = runner.invoke(rom_app, ["info", str(rom_path)])
    assert info.exit_code == 0, info.output
    assert "main_steam_pressure" in info.output and "provenance" in info.output
    paths, run = plant_files
    out = tmp_path / "monitored.csv"
    predicted = runner.invoke(rom_app, [
        "predict", "--rom", str(rom_path), "--data", str(paths["historian"]),
        "--tags", str(paths["tag_map"]), "--out", str(out), "--fields-every", "200",
        "--vtu-dir", str(tmp_path / "vtu")])
    assert predicted.exit_code == 0, predicted.output
    table = pd.read_csv(out, index_col="time")
    assert len(table) == len(run.measured)
    assert "control_stage_temperature [degC]" in table.columns
    assert "blade_leading_edge [degC]" in table.columns
    assert {"rom_invalid_input", "rom_extrapolated"} <= set(table.columns)
    valid = ~table["rom_invalid_input"]
    assert table.loc[valid, "blade_leading_edge [degC]"].between(400, 560).all()
    files = sorted((tmp_path / "vtu").glob("*.vtu"))
    assert files and "temperature_K" in meshio.read(files[0]).point_data

    # issue 18, item 3: the sensors are read as calibrate and validate read them — the tag
    # map's thermocouple lags and the calibration's sensor offsets; --steady-values without
    params = tmp_path / "params.json"
    params.write_text(json.dumps({"flow_coefficient": 1.0, "friction_coefficient": 1.0,
                                  "heat_transfer_coefficient": 1.0,
                                  "sensor_offsets": {"hp_exhaust_temperature": 1.5}}))
    steady_out, offset_out = tmp_path / "steady.csv", tmp_path / "offset.csv"
    common = ["predict", "--rom", str(rom_path), "--data", str(paths["historian"]),
              "--tags", str(paths["tag_map"])]
    steady = runner.invoke(rom_app, [*common, "--out", str(steady_out), "--steady-values"])
    offset = runner.invoke(rom_app, [*common, "--out", str(offset_out), "--params",
                                     str(params)])
    assert steady.exit_code == 0 and offset.exit_code == 0, steady.output + offset.output
    assert "offset +1.50 K" in offset.output
    steady_table = pd.read_csv(steady_out, index_col="time")
    offset_table = pd.read_csv(offset_out, index_col="time")
    exhaust = "hp_exhaust_temperature [degC]"
    ok = ~steady_table["rom_invalid_input"]
    difference = (offset_table.loc[ok, exhaust] - table.loc[ok, exhaust]).to_numpy()
    assert np.allclose(difference, 1.5, atol=1e-9)  # same lag, plus the offset
    lagged = table.loc[ok, exhaust] - steady_table.loc[ok, exhaust]
    assert lagged.abs().max() > 1e-3  # the thermocouple's lag is applied by default
    pressure = "control_stage_pressure [MPa]"
    assert np.array_equal(table[pressure].to_numpy(), steady_table[pressure].to_numpy(),
                          equal_nan=True)

    # issue 16, finding 3: the tag map's valid range applies to predict (the quality gate)
    measured = run.measured["main_steam_temperature"] - 273.15
    limit = float(measured.quantile(0.99))
    tag_map = load_tag_map(paths["tag_map"])
    spec = tag_map.signals["main_steam_temperature"]
    signals = {**tag_map.signals, "main_steam_temperature": dataclasses.replace(
        spec, valid_range_si=(673.15, limit + 273.15))}
    ranged = tmp_path / "ranged.toml"
    write_tag_map(dataclasses.replace(tag_map, signals=signals), ranged)
    gated = runner.invoke(rom_app, [
        "predict", "--rom", str(rom_path), "--data", str(paths["historian"]),
        "--tags", str(ranged), "--out", str(tmp_path / "gated.csv"),
        "--accept-quality-errors"])
    assert gated.exit_code == 0, gated.output
    assert "excluded" in gated.output
    gated_table = pd.read_csv(tmp_path / "gated.csv", index_col="time")
    above = (measured > limit).to_numpy()
    assert above.any()
    assert gated_table["rom_invalid_input"].to_numpy()[above].all()
    assert pd.isna(gated_table["blade_leading_edge [degC]"].to_numpy()[above]).all()


def test_errors_are_reported(tmp_path):
    runner = CliRunner()
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    result = runner.invoke(rom_app, ["info", str(bad)])
    assert result.exit_code == 2 and "not a readable ROM file" in result.output
    result = runner.invoke(rom_app, ["predict", "--rom", str(bad), "--data", "x.csv",
                                     "--tags", "t.toml", "--out", "o.csv", "--fields-every", "5"])
    assert result.exit_code == 2 and "go together" in result.output


def test_build_passes_the_accuracy_options(tmp_path, monkeypatch):
    import steamtwin.rom.workflow as workflow_module

    seen = {}

    def fake_build_rom(spec, mesh, params, **options):
        seen.update(options)
        raise ValueError("stop here")

    monkeypatch.setattr(workflow_module, "build_rom", fake_build_rom)
    runner = CliRunner()
    common = ["build", "--snapshots", "8", "--element-size", "0.006", "--out",
              str(tmp_path / "rom.npz")]
    result = runner.invoke(rom_app, common)
    assert result.exit_code == 2 and "stop here" in result.output
    assert seen["projection_tolerance"] == 0.1 and seen["physics_features"] is True
    runner.invoke(rom_app, [*common, "--projection-tolerance", "0", "--no-physics-features"])
    assert seen["projection_tolerance"] is None and seen["physics_features"] is False


def test_build_covers_the_historian_and_names_the_parameter(tmp_path, plant_files,
                                                            reference_model):
    """--data/--tags widen the envelope to the plant's inputs; a flow coefficient that cannot
    pass rated flow is named with its file; bad --param-interval and --data alone refused."""
    paths, _ = plant_files
    runner = CliRunner()
    common = ["build", "--snapshots", "8", "--element-size", "0.006", "--workers", "1"]
    built = runner.invoke(rom_app, [*common, "--data", str(paths["historian"]), "--tags",
                                    str(paths["tag_map"]), "--out", str(tmp_path / "r.npz")])
    assert built.exit_code == 0, built.output
    assert "0 beyond the extrapolation limit" in built.output
    params = tmp_path / "params.json"
    params.write_text('{"flow_coefficient": 0.9, "friction_coefficient": 1.0, '
                      '"heat_transfer_coefficient": 1.0}')
    failed = runner.invoke(rom_app, [*common, "--params", str(params), "--out",
                                     str(tmp_path / "f.npz")])
    assert failed.exit_code == 2
    assert f"flow_coefficient 0.9 from {params}: at 100% load" in failed.output
    bad = runner.invoke(rom_app, [*common, "--param-interval", "flow_coefficient=1", "--out",
                                  str(tmp_path / "b.npz")])
    assert bad.exit_code == 2 and "NAME=LOW:HIGH" in bad.output
    alone = runner.invoke(rom_app, [*common, "--data", str(paths["historian"]), "--out",
                                    str(tmp_path / "a.npz")])
    assert alone.exit_code == 2 and "go together" in alone.output
