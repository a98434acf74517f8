"""``steamtwin.Twin`` and ``steamtwin.load_history``: the Python entry (issue 20, items 1–2)."""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import json
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import typer
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import steamtwin
from steamtwin.calibration.windowset import find_calibration_windows
from steamtwin.dcs.history import History, check_history
from steamtwin.dcs.plant import PlantRun, run_plant, write_plant
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.windows import find_windows
from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.model.parameters import ModelParameters
from steamtwin.spec.fingerprint import spec_hash
from steamtwin.twin import Twin, TwinError

pytestmark = pytest.mark.slow  # 12 s of the full suite (2026-11-27): not in the quick loop

ROOT = Path(__file__).resolve().parents[1]
TRUE_FLOW = 0.965  # PlantTruth's default flow coefficient (steamtwin.dcs.plant)


@pytest.fixture(scope="module")
def plant() -> PlantRun:
    return run_plant("deep-peak-50", hours=0.25, random_state=1)


@pytest.fixture(scope="module")
def plant_files(plant, tmp_path_factory) -> dict[str, Path]:
    return write_plant(plant, tmp_path_factory.mktemp("plant"), file_format="csv")


@pytest.fixture(scope="module")
def small_rom(reference_spec):
    """A coarse ROM of the reference unit (8 snapshots on a 6-mm blade mesh)."""
    twin = Twin.from_spec("reference", ModelParameters(0.98, 1.1, 1.2))
    return twin.build_rom(element_size=0.006, n_snapshots=8, energy=0.9999, workers=1)


def test_from_spec_stores_and_computes_nothing(reference_spec, tmp_path):
    twin = Twin.from_spec("reference")
    assert spec_hash(twin.spec) == spec_hash(reference_spec)
    assert twin.parameters == ModelParameters() and twin.blade_rom is None
    assert not [name for name in vars(twin) if name.endswith("_")]  # nothing fitted yet
    path = tmp_path / "unit.toml"
    path.write_text(twin.spec_toml, encoding="utf-8")
    assert spec_hash(Twin.from_spec(path).spec) == spec_hash(reference_spec)
    with pytest.raises(TypeError, match="spec must be"):
        Twin("reference")  # type: ignore[arg-type]
    with pytest.raises(TwinError, match="no blade ROM"):
        twin.signals_needed()
    with pytest.raises(TypeError, match=r"takes histories from steamtwin\.load_history"):
        twin.calibrate(pd.DataFrame())  # type: ignore[arg-type]


def test_simulate_is_the_full_order_model_bit_for_bit(reference_spec, reference_model):
    params = ModelParameters(0.97, 1.2, 1.4)
    inputs = load_profile_inputs(reference_spec, ramp_profile(1.0, 0.5, 0.03, 60.0, 120.0))
    twin = Twin.from_spec("reference", params)
    pd.testing.assert_frame_equal(twin.simulate(inputs), reference_model.simulate(inputs, params),
                                  check_exact=True)


def test_save_load_round_trip(small_rom, tmp_path):
    folder = small_rom.save(tmp_path / "twin")
    loaded = Twin.load(folder)
    assert spec_hash(loaded.spec) == spec_hash(small_rom.spec)
    assert loaded.parameters == small_rom.parameters
    rom, again = small_rom.blade_rom.rom, loaded.blade_rom.rom
    conditions = small_rom.blade_rom.conditions[list(rom.input_names_)].to_numpy(float)
    np.testing.assert_array_equal(again.predict(conditions), rom.predict(conditions))
    manifest = json.loads((folder / "twin.json").read_text())
    assert set(manifest["files"]) == {"spec.toml", "params.json", "rom.npz"}
    assert [step["step"] for step in manifest["provenance"]] == ["from_spec", "build_rom"]
    assert manifest["versions"]["numpy"] == np.__version__
    assert not list(folder.glob("*.pkl")) and not list(folder.glob("*.pickle"))
    # saved again, a loaded twin keeps its files and adds its own step
    second = json.loads((loaded.save(tmp_path / "again") / "twin.json").read_text())
    assert second["files"]["params.json"] == manifest["files"]["params.json"]
    assert [step["step"] for step in second["provenance"]][-1] == "load"


def test_validate_writes_the_report_the_twin_folder_keeps(small_rom, plant, plant_files,
                                                          tmp_path):
    """Twin.validate on the plant's last 10 min: Table 8 for the HP exhaust from the FOM with
    the ROM's parameters; the saved twin carries the report, hashed like every file."""
    history = steamtwin.load_history(plant_files["historian"])
    span = (plant.measured.index[-600], plant.measured.index[-1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        twin = copy.copy(small_rom)  # the module's other tests see the twin without a report
        report = twin.validate(history, tmp_path / "report", windows=[span])
    table8 = report.tables["table8_deviation"]
    row = table8[table8["signal"] == "hp_exhaust_temperature"].iloc[0]
    assert row["n_used"] + row["n_skipped_missing"] + row["n_skipped_rom_invalid"] == 599
    assert abs(row["mean_deviation"]) < 10.0  # K: the twin follows the plant
    assert (tmp_path / "report" / "report.html").is_file()
    manifest = json.loads((twin.save(tmp_path / "twin") / "twin.json").read_text())
    assert "reports/validation/report.html" in manifest["files"]
    assert manifest["provenance"][-1]["step"] == "validate"


def test_validate_runs_the_fom_on_through_the_file_and_says_when_it_cannot(
        small_rom, plant, plant_files, tmp_path):
    """The FOM is run once from the file's start through the ramp into the window (its metal
    still settling there), not started steady at the window; a row it cannot take before the
    window makes each window start steady instead, with a warning and the report saying so."""
    history = steamtwin.load_history(plant_files["historian"])
    span = (plant.measured.index[-600], plant.measured.index[-1])

    def exhaust_deviation(report) -> float:
        table8 = report.tables["table8_deviation"]
        return float(table8[table8["signal"] == "hp_exhaust_temperature"].iloc[0][
            "mean_deviation"])

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        continuous = copy.copy(small_rom).validate(history, tmp_path / "continuous",
                                                   windows=[span])
    assert continuous.settings["model runs"].startswith(
        f"one continuous run from {history.data.index[0]}")
    data = history.data.copy()
    data.iloc[60, data.columns.get_loc("main_steam_flow")] *= 5.0  # beyond the valves
    broken = dataclasses.replace(history, data=data)
    with pytest.warns(UserWarning, match="each window from steady state"):
        steady = copy.copy(small_rom).validate(broken, tmp_path / "steady", windows=[span])
    assert steady.settings["model runs"].startswith("each window from steady state")
    # the window starts ~5 min after a 3 %/min ramp: the steady start misses the metal's lag
    assert abs(exhaust_deviation(steady) - exhaust_deviation(continuous)) > 0.05


def test_load_refuses_a_changed_or_mismatched_folder(small_rom, tmp_path):
    folder = small_rom.save(tmp_path / "twin")
    params = folder / "params.json"
    original = params.read_text()
    params.write_text(original.replace("0.98", "0.99", 1))
    with pytest.raises(TwinError, match=r"params\.json: its SHA-256 .* changed after"):
        Twin.load(folder)
    # the manifest updated too: the ROM then no longer matches the parameters
    manifest_text = (folder / "twin.json").read_text()
    manifest = json.loads(manifest_text)
    manifest["files"]["params.json"] = hashlib.sha256(params.read_bytes()).hexdigest()
    (folder / "twin.json").write_text(json.dumps(manifest))
    with pytest.raises(TwinError, match=r"rom\.npz: built with parameters .* rebuild the ROM"):
        Twin.load(folder)
    params.write_text(original)
    (folder / "twin.json").write_text(manifest_text)
    assert Twin.load(folder).parameters == small_rom.parameters  # restored: accepted again
    (folder / "rom.npz").unlink()
    with pytest.raises(TwinError, match=r"rom\.npz: listed in twin\.json but missing"):
        Twin.load(folder)
    with pytest.raises(TwinError, match="not a twin folder"):
        Twin.load(tmp_path)


def test_calibrate_recovers_the_flow_coefficient_as_the_cli_does(plant, plant_files, tmp_path):
    """The last 10 min of the virtual plant's 50 % hold: the surrogate calibration puts the
    plant's hidden flow coefficient (0.965) inside its 95 % interval, within 0.015; the CLI,
    given the same settings, writes the same parameters."""
    from steamtwin.cli.calibrate import calibrate

    history = steamtwin.load_history(plant_files["historian"])  # tags.toml found beside it
    start, end = plant.measured.index[-600], plant.measured.index[-1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a 10-min hold cannot identify heat transfer
        twin = Twin.from_spec("reference").calibrate(
            history, windows=[(start, end)], method="surrogate", max_evaluations=40, workers=1)
    flow = twin.params_.flow_coefficient
    low, high = twin.intervals["flow_coefficient"]
    assert low <= TRUE_FLOW <= high
    assert abs(flow - TRUE_FLOW) < 0.015
    assert twin.calibrator_.rmse_ < twin.initial_rmse_
    assert twin.steps[-1]["step"] == "calibrate" and twin.steps[-1]["windows"] == 1
    app = typer.Typer()
    app.command()(calibrate)
    app.command("other")(lambda: None)
    result = CliRunner().invoke(app, [
        "calibrate", "--data", str(plant_files["historian"]), "--tags",
        str(plant_files["tag_map"]), "--out", str(tmp_path / "params.json"), "--surrogate",
        "--max-evaluations", "40", "--workers", "1",
        "--window", f"{start.isoformat()}/{end.isoformat()}"])
    assert result.exit_code == 0, result.output
    assert ModelParameters.from_json(tmp_path / "params.json") == twin.params_
    saved = Twin.load(twin.save(tmp_path / "calibrated"))
    assert saved.parameters == twin.params_ and saved.intervals == twin.intervals
    assert (tmp_path / "calibrated" / "reports" / "calibration_windows.csv").exists()


def test_history_windows_are_the_calibrations_rule(plant_files, reference_spec):
    """One rule: the steady windows a validation takes (min = max duration) are those the
    calibration's search finds with the same durations (before its dropout cut)."""
    history = steamtwin.load_history(plant_files["historian"], plant_files["tag_map"])
    rated = reference_spec.design.generator_power
    found = history.windows(rated, min_steady_s=600.0, max_steady_s=600.0, ramps=False)
    assert [w.kind for w in found] == ["steady", "steady"]  # the 100 % and the 50 % hold
    assert found[0].load_fraction > 0.95 and 0.45 < found[1].load_fraction < 0.6
    calibration = find_calibration_windows(history.data, rated, min_steady_s=600.0,
                                           max_steady_s=600.0)
    steady = [w for w in calibration if w.kind == "steady"]
    assert [w.data.index[0] for w in steady] == [w.data.index[0] for w in found]
    assert len(find_windows(history.data, rated, min_steady_s=600.0, max_steady_s=600.0)) == (
        len(calibration))
    given = history.windows(rated, given=[f"{found[1].data.index[0].isoformat()}/"
                                          f"{found[1].data.index[-1].isoformat()}"])
    assert given[0].kind == "given" and len(given[0].data) == len(found[1].data) - 1


def _wide_csv(path: Path, rows: int, start: str, bad_row: int | None = None) -> Path:
    times = pd.date_range(start, periods=rows, freq="1s", tz="UTC")
    values = np.round(16.7 + 0.01 * np.random.default_rng(rows).standard_normal(rows), 3)
    text = [f"{t:%Y-%m-%dT%H:%M:%SZ},{v}" for t, v in zip(times, values, strict=True)]
    if bad_row is not None:
        text[bad_row - 1] = text[bad_row - 1].split(",")[0] + ",n/a-oops"
    path.write_text("time,10LBA10CP001\n" + "\n".join(text) + "\n", encoding="utf-8")
    return path


def _tags(path: Path) -> Path:
    path.write_text('[historian]\nlayout = "wide"\ntime_column = "time"\n\n'
                    '[signals.main_steam_pressure]\ncolumn = "10LBA10CP001"\nunit = "MPa"\n'
                    'range = [0, 25]\n', encoding="utf-8")
    return path


def test_load_history_names_the_file_tag_and_row_of_a_bad_value(tmp_path):
    tags = _tags(tmp_path / "tags.toml")
    bad = _wide_csv(tmp_path / "day2.csv", 120, "2026-03-02T00:00Z", bad_row=37)
    with pytest.raises(HistorianFormatError) as caught:
        steamtwin.load_history([_wide_csv(tmp_path / "day1.csv", 120, "2026-03-01T00:00Z"), bad],
                               tags)
    message = str(caught.value)
    assert "day2.csv" in message and "10LBA10CP001" in message and "line 38" in message
    # a number out of the tag map's range: excluded, and the finding says where
    text = bad.read_text().replace("n/a-oops", "99.0")
    bad.write_text(text)
    history = steamtwin.load_history(bad, tags)
    assert history.excluded == {"main_steam_pressure": 1}
    assert np.isnan(history.data["main_steam_pressure"].iloc[36])
    (finding,) = [f for f in history.report.findings if f.action == "rejected"]
    assert finding.tag == "10LBA10CP001" and finding.first_row == 36


def test_several_files_load_as_one_history(tmp_path):
    tags = _tags(tmp_path / "tags.toml")
    first = _wide_csv(tmp_path / "a.csv", 300, "2026-03-01T00:00Z")
    second = _wide_csv(tmp_path / "b.csv", 200, "2026-03-01T00:05Z")  # right after the first
    joined = steamtwin.load_history([second, first])  # order of the files does not matter
    parts = [steamtwin.load_history(path, tags) for path in (first, second)]
    pd.testing.assert_frame_equal(joined.data, pd.concat([p.data for p in parts]))
    assert isinstance(joined, History) and joined.report.n_rows == 500
    assert joined.historian.source == f"{first}; {second}"
    overlapping = _wide_csv(tmp_path / "c.csv", 100, "2026-03-01T00:04Z")
    with pytest.raises(ValueError, match="overlap in time"):
        steamtwin.load_history([first, overlapping], tags)
    with pytest.raises(ValueError, match=r"no tag map given and no tags\.toml"):
        steamtwin.load_history(tmp_path / "elsewhere" / "a.csv")
    historian, report = check_history(first, tags, required=["main_steam_pressure"])
    assert report.ok and len(historian.signals) == 300


def test_import_steamtwin_is_light_and_reexports_the_handful():
    code = ("import sys, steamtwin; print([m for m in ('steamtwin.twin', 'pandas', "
            "'steamtwin.dcs.history') if m in sys.modules])")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True, env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
    assert result.stdout.splitlines() == ["[]"]  # nothing heavy until asked for
    assert steamtwin.Twin is Twin and steamtwin.History is History
    assert steamtwin.load_history.__module__ == "steamtwin.dcs.history"
    assert {"Twin", "load_history", "History", "ModelParameters", "load_spec"} <= set(
        steamtwin.__all__)
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        _ = steamtwin.nothing


def test_readme_python_example_runs_as_printed(tmp_path, monkeypatch):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text[text.index("## Python"):]
    (block,) = re.findall(r"```python\n(.*?)```", section[:section.index("\n## ", 3)], re.S)
    assert len(block.strip().splitlines()) <= 14
    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exec(compile(block, "README.md", "exec"), {})  # the README's own example
    loaded = Twin.load(tmp_path / "my-twin")
    assert abs(loaded.parameters.flow_coefficient - TRUE_FLOW) < 0.015


@settings(max_examples=15, deadline=None)
@given(split=st.integers(min_value=40, max_value=460))
def test_one_export_split_anywhere_loads_as_the_whole(tmp_path_factory, split):
    """Exports cut at any row give the history of the uncut export (smooth, noisy data:
    nothing for the gate to exclude at the cut)."""
    folder = tmp_path_factory.mktemp("split")
    tags = _tags(folder / "tags.toml")
    whole = _wide_csv(folder / "whole.csv", 500, "2026-03-01T00:00Z")
    lines = whole.read_text().splitlines()
    (folder / "a.csv").write_text("\n".join(lines[:split + 1]) + "\n")
    (folder / "b.csv").write_text("\n".join([lines[0], *lines[split + 1:]]) + "\n")
    parts = steamtwin.load_history([folder / "b.csv", folder / "a.csv"], tags)
    pd.testing.assert_frame_equal(parts.data, steamtwin.load_history(whole, tags).data)
    assert parts.excluded == {"main_steam_pressure": 0}
