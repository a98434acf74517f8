"""``steamtwin validate`` end to end: a tiny ROM, virtual-plant holds at 30 % and 50 % load.

The same measurements written with another tag map (renamed tags, °F / psi / kPa / bar / kg/s /
kW, another time zone, CSV) and in the long layout must give the same Table 8.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
import typer
from typer.testing import CliRunner

from steamtwin.cli.validate import validate
from steamtwin.dcs.plant import plant_tag_map, run_plant
from steamtwin.dcs.plant_model import PlantTruth
from steamtwin.dcs.readers import canonical_to_historian
from steamtwin.dcs.tagmap import TagMap, TagSpec, write_tag_map
from steamtwin.geometry.meshing import blade_volume_mesh
from steamtwin.rom.build import build_rom
from steamtwin.rom.romfile import load_rom, save_rom
from steamtwin.validation import NotesSection, monitor_windows
from steamtwin.validation import validate as validate_windows

pytestmark = pytest.mark.slow  # 10 s of the full suite (2026-11-27): not in the quick loop

app = typer.Typer()
app.command()(validate)
runner = CliRunner()

OTHER_UNITS = {
    "main_steam_pressure": "psi", "main_steam_temperature": "degF", "main_steam_flow": "kg/s",
    "control_stage_pressure": "kPa", "control_stage_temperature": "degF",
    "hp_exhaust_pressure": "bar", "hp_exhaust_temperature": "degF",
    "hp_inner_casing_temperature": "K", "load": "kW",
}


@pytest.fixture(scope="module")
def rom_file(tmp_path_factory, reference_spec):
    mesh = blade_volume_mesh(reference_spec, "hp1", element_size=0.006)
    bundle, _ = build_rom(reference_spec, mesh, n_snapshots=8, energy=0.9999, max_workers=1)
    return save_rom(bundle, tmp_path_factory.mktemp("rom") / "rom.npz")


@pytest.fixture(scope="module")
def measured() -> pd.DataFrame:
    """A 30 % hold one day before a 50 % hold (15-min holds, 1-s samples, SI).

    The plant keeps its main-steam temperature rated at 30 % here: with its boiler schedule
    (520 °C) the 30 % hold lies outside the reference ROM's snapshots (528–548 °C) and is
    flagged as extrapolated — issue 18, item 4 (a ROM envelope from the unit) — while this test
    is about the tables from other tag maps, units and layouts."""
    truth = PlantTruth(main_steam_schedule=None, reheat_schedule=None)
    parts = []
    for load, days_before in ((30, 1), (50, 0)):
        frame = run_plant(f"deep-peak-{load}", hours=0.25, random_state=load, truth=truth).measured
        parts.append(frame.set_axis(frame.index - pd.Timedelta(days=days_before)))
    return pd.concat(parts)


def _write(measured: pd.DataFrame, tag_map: TagMap, folder, suffix: str):
    folder.mkdir(parents=True, exist_ok=True)
    wide = canonical_to_historian(measured, tag_map)
    if tag_map.layout == "long":
        wide = wide.melt(id_vars=[tag_map.time_column], var_name=tag_map.tag_column,
                         value_name=tag_map.value_column, ignore_index=False)
        wide = wide.reset_index().sort_values("index", kind="stable").drop(columns="index")
    data = folder / f"historian.{suffix}"
    if suffix == "csv":
        wide.to_csv(data, index=False)
    else:
        wide.to_parquet(data, index=False)
    tags = folder / "tags.toml"
    write_tag_map(tag_map, tags)
    return data, tags


def _renamed_map() -> TagMap:
    signals = {name: TagSpec(signal=name, column=f"U1 {name.replace('_', ' ')}", unit=unit)
               for name, unit in OTHER_UNITS.items()}
    return TagMap(layout="wide", time_column="Zeit", time_zone="Europe/Berlin", tag_column=None,
                  value_column=None, quality_column=None, signals=signals, source="other.toml")


def _run(rom_file, data, tags, report, *extra: str):
    result = runner.invoke(app, ["--rom", str(rom_file), "--data", str(data), "--tags",
                                 str(tags), "--report", str(report), *extra])
    return result


def _report(folder) -> dict:
    return json.loads((folder / "report.json").read_text(encoding="utf-8"))


def test_help_has_an_example():
    result = runner.invoke(app, ["--help"])
    assert result.exit_code == 0 and "Example: steamtwin validate" in result.output


def test_same_table8_from_other_tags_units_and_layout(tmp_path, rom_file, measured):
    layouts = {
        "plant": (plant_tag_map("wide"), "parquet"),
        "other": (_renamed_map(), "csv"),
        "long": (plant_tag_map("long"), "csv"),
    }
    tables = {}
    for name, (tag_map, suffix) in layouts.items():
        data, tags = _write(measured, tag_map, tmp_path / name, suffix)
        extra = ("--field-check",) if name == "plant" else ()
        result = _run(rom_file, data, tags, tmp_path / f"report-{name}", "--hours", "0.2", *extra)
        assert result.exit_code == 0, result.output
        tables[name] = pd.read_csv(tmp_path / f"report-{name}" / "table8_deviation.csv")
        lines = [line for line in result.output.splitlines() if "mean abs deviation" in line]
        assert len(lines) == 2 and lines[0].startswith("34 % load: hp_exhaust_temperature")
    reference = tables["plant"]
    assert list(reference["window"].unique()) == ["34 % load", "56 % load"]
    assert list(reference["signal"].unique()) == [
        "hp_exhaust_temperature", "control_stage_temperature", "hp_inner_casing_temperature",
        "control_stage_pressure"]  # the FOM's outputs; its input pressures are not compared
    assert reference.groupby("signal")["unit"].first().to_dict() == {
        "hp_exhaust_temperature": "K", "control_stage_temperature": "K",
        "hp_inner_casing_temperature": "K", "control_stage_pressure": "MPa"}
    assert (reference["n_used"] > 700).all()
    numeric = reference.select_dtypes("number").columns
    for name in ("other", "long"):
        table = tables[name]
        assert table[["signal", "window"]].equals(reference[["signal", "window"]])
        np.testing.assert_allclose(table[numeric].to_numpy(float),
                                   reference[numeric].to_numpy(float), rtol=1e-7, atol=1e-9)
    folder = tmp_path / "report-plant"
    for file in ("report.html", "table5_operating.csv", "rom_provenance.csv",
                 "figure10_exhaust_tracking.png", "figure9_field_1.png", "figure9_field_2.png"):
        assert (folder / file).stat().st_size > 0, file
    document = _report(folder)
    records = pd.DataFrame(document["tables"]["table8_deviation"]["records"])
    pd.testing.assert_frame_equal(records, reference)
    field_error = pd.DataFrame(document["tables"]["figure9_field_error"]["records"])
    assert (field_error["max_abs_error_K"] < 10.0).all()
    assert "FOM blade fields (Figure 9)" in document["timings_s"]
    _check_series_and_time_zone(tmp_path, measured, reference)


def _check_series_and_time_zone(tmp_path, measured, table8):
    """Issue 18, item 7: per-sample series beside the tables, times in the data's zone."""
    import pyarrow.parquet as pq

    folder = tmp_path / "report-plant"
    document = _report(folder)
    assert document["settings"]["times in"] == "Asia/Shanghai"
    table5 = pd.DataFrame(document["tables"]["table5_operating"]["records"])
    assert all(text.endswith("+08:00") for text in table5["start"])
    berlin = pd.DataFrame(_report(tmp_path / "report-other")["tables"]["table5_operating"][
        "records"])
    assert all(text.endswith("+01:00") for text in berlin["start"])  # Europe/Berlin in March
    assert [pd.Timestamp(t) for t in berlin["start"]] == [pd.Timestamp(t)
                                                          for t in table5["start"]]
    files = document["files"]
    assert [f["file"] for f in files] == ["series_1_34_pct_load.parquet",
                                          "series_2_56_pct_load.parquet"]
    html = (folder / "report.html").read_text(encoding="utf-8")
    for entry, window in zip(files, ("34 % load", "56 % load"), strict=True):
        assert f'<a href="{entry["file"]}">' in html
        series = pd.read_parquet(folder / entry["file"])
        assert str(series.index.tz) == "Asia/Shanghai"
        assert series.index[0].isoformat() == table5.set_index("window").loc[window, "start"]
        metadata = json.loads(pq.read_schema(folder / entry["file"]).metadata[b"steamtwin"])
        assert metadata["window"] == window and metadata["time_zone"] == "Asia/Shanghai"
        assert metadata["units"]["control_stage_pressure_residual_MPa"] == "MPa"
        assert metadata["units"]["hp_exhaust_temperature_residual_K"] == "K"
        source = measured.loc[series.index]
        np.testing.assert_allclose(series["control_stage_pressure_measured_MPa"],
                                   source["control_stage_pressure"] / 1e6, rtol=1e-12)
        np.testing.assert_allclose(series["hp_exhaust_temperature_measured_degC"],
                                   source["hp_exhaust_temperature"] - 273.15, atol=1e-9)
        for row in table8[table8["window"] == window].itertuples(index=False):
            unit = "degC" if row.unit == "K" else "MPa"
            used = series[f"{row.signal}_used"].to_numpy()
            residual = series[f"{row.signal}_residual_{row.unit}"].to_numpy()[used]
            twin = series[f"{row.signal}_twin_{unit}"].to_numpy()[used]
            truth = series[f"{row.signal}_measured_{unit}"].to_numpy()[used]
            np.testing.assert_allclose(residual, twin - truth, atol=1e-12)
            assert used.sum() == row.n_used
            assert np.abs(residual).mean() == pytest.approx(row.mean_abs_deviation, rel=1e-9)
            assert np.sqrt(np.mean(residual**2)) == pytest.approx(row.rmse, rel=1e-9)
            assert 100 * np.sqrt(np.mean(residual**2)) / truth.mean() == pytest.approx(
                row.rmse_pct, rel=1e-9)


def test_a_sensor_without_any_value_is_said_not_reported_as_nan(tmp_path, rom_file, measured):
    """Issue 16, finding 7: an all-NaN sensor gave NaN in report.json and the summary."""
    blank = measured.copy()
    blank["hp_exhaust_temperature"] = np.nan
    data, tags = _write(blank, plant_tag_map("wide"), tmp_path / "data", "parquet")
    result = _run(rom_file, data, tags, tmp_path / "report",
                  "--window", "2026-03-01T00:30:00Z/2026-03-01T00:40:00Z")
    assert result.exit_code == 0, result.output
    assert "hp_exhaust_temperature: no usable sample" in result.output
    assert "nan" not in result.output.lower()
    text = (tmp_path / "report" / "report.json").read_text(encoding="utf-8")
    json.loads(text, parse_constant=lambda name: pytest.fail(f"{name} in report.json"))
    records = pd.DataFrame(_report(tmp_path / "report")["tables"]["table8_deviation"]["records"])
    exhaust = records[records["signal"] == "hp_exhaust_temperature"].iloc[0]
    assert exhaust["n_used"] == 0 and exhaust["n_skipped_missing"] == 600
    assert exhaust["rmse"] is None or np.isnan(exhaust["rmse"])
    quality = pd.DataFrame(_report(tmp_path / "report")["tables"]["data_quality"]["records"])
    assert ((quality["signal"] == "hp_exhaust_temperature") & (quality["kind"] == "nan")).any()


def test_explicit_window(tmp_path, rom_file, measured):
    data, tags = _write(measured, plant_tag_map("wide"), tmp_path / "data", "parquet")
    result = _run(rom_file, data, tags, tmp_path / "report",
                  "--window", "2026-03-01T00:30:00Z/2026-03-01T00:40:00Z")
    assert result.exit_code == 0, result.output
    table5 = pd.read_csv(tmp_path / "report" / "table5_operating.csv", index_col="window")
    assert list(table5.index) == ["56 % load"]
    assert table5.loc["56 % load", "samples"] == 600
    assert pd.Timestamp(table5.loc["56 % load", "start"]) == pd.Timestamp("2026-03-01T00:30Z")
    window = measured.loc["2026-03-01T00:30:00Z":"2026-03-01T00:39:59Z"]
    assert table5.loc["56 % load", "main_steam_pressure_MPa_mean"] == pytest.approx(
        window["main_steam_pressure"].mean() / 1e6, rel=1e-9)
    json_table5 = pd.DataFrame(_report(tmp_path / "report")["tables"]["table5_operating"][
        "records"]).set_index("window")
    assert json_table5["main_steam_pressure_MPa_mean"].equals(
        table5["main_steam_pressure_MPa_mean"])


def test_clear_errors(tmp_path, rom_file, measured):
    data, tags = _write(measured, plant_tag_map("wide"), tmp_path / "data", "parquet")
    plant = plant_tag_map("wide")
    unmapped = TagMap(**{**plant.__dict__, "signals": {
        k: v for k, v in plant.signals.items() if k != "control_stage_pressure"}})
    write_tag_map(unmapped, tmp_path / "unmapped.toml")
    result = _run(rom_file, data, tmp_path / "unmapped.toml", tmp_path / "r1")
    assert result.exit_code == 2
    assert "unmapped.toml" in result.output and "control_stage_pressure" in result.output
    wrong_tag = TagMap(**{**plant.__dict__, "signals": {
        **plant.signals, "control_stage_pressure": TagSpec("control_stage_pressure",
                                                           "10MAA99CP999", "MPa")}})
    write_tag_map(wrong_tag, tmp_path / "wrong.toml")
    result = _run(rom_file, data, tmp_path / "wrong.toml", tmp_path / "r2")
    assert result.exit_code == 2
    assert "'10MAA99CP999'" in result.output and "historian.parquet" in result.output
    garbage = tmp_path / "garbage.parquet"
    garbage.write_bytes(b"not parquet")
    result = _run(rom_file, garbage, tags, tmp_path / "r3")
    assert result.exit_code == 2 and "cannot read Parquet" in result.output
    result = _run(rom_file, data, tags, tmp_path / "r4",
                  "--window", "2026-02-28T12:00:00Z/2026-02-28T13:00:00Z")
    assert result.exit_code == 2 and "holds no sample" in result.output
    result = _run(rom_file, data, tags, tmp_path / "r5", "--window", "2026-03-01T00:30:00Z")
    assert result.exit_code == 2 and "START/END" in result.output
    result = _run(rom_file, data, tags, tmp_path / "r6", "--hours", "3")
    assert result.exit_code == 2 and "no steady-load span" in result.output
    bad_rom = tmp_path / "bad.npz"
    bad_rom.write_bytes(b"not a zip")
    result = _run(bad_rom, data, tags, tmp_path / "r7")
    assert result.exit_code == 2 and "not a readable ROM file" in result.output
    assert "Traceback" not in result.output


@pytest.mark.filterwarnings("ignore::steamtwin.rom.estimator.ExtrapolationWarning")
def test_library_validate_without_exhaust_and_with_extra_sections(tmp_path, rom_file, measured):
    bundle = load_rom(rom_file)
    window = measured.loc["2026-03-01T00:30:00Z":"2026-03-01T00:34:59Z"]
    report = validate_windows(bundle, {"hold": window.drop(columns="hp_exhaust_temperature")},
                              tmp_path, settings={"case": "no exhaust"},
                              extra_sections=[NotesSection("from the caller", ("kept",))])
    table8 = report.tables["table8_deviation"]
    assert "hp_exhaust_temperature" not in set(table8["signal"])
    assert not (tmp_path / "figure10_exhaust_tracking.png").exists()
    document = json.loads((tmp_path / "report.json").read_text(encoding="utf-8"))
    assert document["notes"][-1] == {"heading": "from the caller", "paragraphs": ["kept"]}
    assert document["settings"]["case"] == "no exhaust"
    monitored = monitor_windows(bundle, {"hold": window})["hold"]
    assert {"rom_invalid_input", "rom_extrapolated"} <= set(monitored.columns)
    with pytest.raises(ValueError, match="none of the ROM's steam-path temperatures"):
        validate_windows(bundle, {"hold": window[["main_steam_pressure",
                                                  "main_steam_temperature",
                                                  "control_stage_pressure"]]}, tmp_path)
    with pytest.raises(ValueError, match="lacks the ROM input"):
        monitor_windows(bundle, {"hold": window.drop(columns="control_stage_pressure")})
    # issue 18, item 3: ROM monitoring reads its steady values through the sensors
    from steamtwin.model.sensor_setup import SensorSetup
    from steamtwin.rom.reconstruction import read_through

    setup = SensorSetup({"hp_exhaust_temperature": 30.0}, {"hp_exhaust_temperature": "test"},
                        offsets={"control_stage_temperature": 0.75})
    read = monitor_windows(bundle, {"hold": window}, sensors=setup)["hold"]
    pd.testing.assert_frame_equal(read, read_through(monitored, setup))
    assert np.allclose(read["control_stage_temperature"] - monitored["control_stage_temperature"],
                       0.75, equal_nan=True)
    with pytest.raises(ValueError, match="reads through its own"):
        monitor_windows(bundle, {"hold": window}, simulator=object(), sensors=setup)


def test_fom_monitoring_takes_the_roms_parameters_and_flags_missing_inputs(
        rom_file, measured, reference_model):
    from steamtwin.model.parameters import ModelParameters
    from steamtwin.rom.romfile import load_rom
    from steamtwin.validation.monitor import monitor_windows

    bundle = load_rom(rom_file)
    window = measured.iloc[:600].copy()
    window.iloc[:5, window.columns.get_loc("hp_exhaust_pressure")] = np.nan  # no FOM start
    by_fom = monitor_windows(bundle, {"w": window}, reference_model)["w"]
    by_rom = monitor_windows(bundle, {"w": window})["w"]
    params = ModelParameters(**bundle.provenance["model_parameters"])
    direct = reference_model.simulate(window.iloc[5:], params)
    np.testing.assert_allclose(by_fom["hp_exhaust_temperature"].iloc[5:],
                               direct["hp_exhaust_temperature"], rtol=0, atol=1e-9)
    assert by_fom["hp_exhaust_temperature"].iloc[:5].isna().all()
    assert by_fom["rom_invalid_input"].iloc[:5].all()
    assert not by_fom["rom_invalid_input"].iloc[5:].any()
    probes = [name for name in bundle.probes]
    pd.testing.assert_frame_equal(by_fom[probes], by_rom[probes])  # the blade stays the ROM's


def test_window_names_and_figure_labels_are_in_the_datas_zone():
    from steamtwin.cli.validate import _named
    from steamtwin.validation.figures import window_label

    index = pd.date_range("2026-03-01T00:00Z", periods=3, freq="1h").tz_convert("Asia/Shanghai")
    assert window_label("50 % load", index) == "50 % load, 2026-03-01T08:00+08:00 … 10:00"
    frames = [pd.DataFrame({"load": 300e6}, index=index),
              pd.DataFrame({"load": 300e6}, index=index + pd.Timedelta(days=1))]
    assert list(_named(frames, 600e6)) == ["50 % load, 2026-03-01 08:00",
                                           "50 % load, 2026-03-02 08:00"]


def test_the_calibrations_sensor_offsets_move_the_deviation_by_themselves(
        tmp_path, rom_file, measured):
    """--params with sensor_offsets (what calibrate --sensor-bias writes): the FOM reads each
    sensor through its offset, so Table 8's mean deviation of that sensor moves by exactly the
    offset and nothing else changes; --no-sensor-offsets gives the run without them."""
    data, tags = _write(measured, plant_tag_map("wide"), tmp_path / "data", "parquet")
    window = ("--window", "2026-03-01T00:30:00Z/2026-03-01T00:40:00Z")
    own = load_rom(rom_file).provenance["model_parameters"]
    params = tmp_path / "params.json"
    params.write_text(json.dumps({"parameters": own,
                                  "sensor_offsets": {"hp_exhaust_temperature": 1.5}}))
    tables = {}
    for name, extra in (("plain", ()), ("offset", ("--params", str(params))),
                        ("off", ("--params", str(params), "--no-sensor-offsets"))):
        result = _run(rom_file, data, tags, tmp_path / name, *window, *extra)
        assert result.exit_code == 0, result.output
        tables[name] = pd.read_csv(tmp_path / name / "table8_deviation.csv").set_index("signal")
    shift = tables["offset"]["mean_deviation"] - tables["plain"]["mean_deviation"]
    assert abs(shift["hp_exhaust_temperature"]) == pytest.approx(1.5, abs=1e-6)
    assert shift.drop("hp_exhaust_temperature").abs().max() < 1e-9
    pd.testing.assert_frame_equal(tables["off"], tables["plain"])
    settings = _report(tmp_path / "offset")["settings"]
    assert "+1.50 K" in settings["sensor offsets (measured − model)"]
    # the ROM monitoring reads through the same sensors (issue 18, item 3): offsets, and lags
    for name, extra in (("rom", ("--monitor", "rom")),
                        ("rom-offset", ("--monitor", "rom", "--params", str(params))),
                        ("rom-steady", ("--monitor", "rom", "--no-sensor-lag"))):
        result = _run(rom_file, data, tags, tmp_path / name, *window, *extra)
        assert result.exit_code == 0, result.output
        tables[name] = pd.read_csv(tmp_path / name / "table8_deviation.csv").set_index("signal")
    shift = tables["rom-offset"]["mean_deviation"] - tables["rom"]["mean_deviation"]
    assert abs(shift["hp_exhaust_temperature"]) == pytest.approx(1.5, abs=1e-6)
    lagged = tables["rom"]["rmse"] - tables["rom-steady"]["rmse"]
    assert lagged.abs().max() > 1e-4  # the thermowells' lags change what the ROM is read as
