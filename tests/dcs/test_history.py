"""The quality gate every command passes historian data through (issue 16, findings 3 and 4)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.dcs.history import DataQualityError, load_history
from steamtwin.dcs.quality import Flag
from steamtwin.model.simulator import INPUT_SIGNALS

#: A steady full-load hold in the units a plant exports (MPa, °C, t/h, MW) and noise σ.
LEVELS = {
    "main_steam_pressure": ("MPa", 16.7, 0.01),
    "main_steam_temperature": ("degC", 538.0, 0.5),
    "main_steam_flow": ("t/h", 1700.0, 5.0),
    "control_stage_pressure": ("MPa", 12.3, 0.01),
    "control_stage_temperature": ("degC", 497.8, 0.5),
    "hp_exhaust_pressure": ("MPa", 3.75, 0.005),
    "hp_exhaust_temperature": ("degC", 322.8, 0.5),
    "load": ("MW", 600.0, 1.0),
}
TAGS = {name: f"10TAG{j:02d}" for j, name in enumerate(LEVELS)}
N = 900


def _values(seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {name: np.round(level + sigma * rng.standard_normal(N), 3)
            for name, (_, level, sigma) in LEVELS.items()}


def _tag_map(path, units: dict[str, str] | None = None, ranges: dict[str, str] | None = None,
             long: bool = False):
    units, ranges = units or {}, ranges or {}
    head = ('[historian]\nlayout = "long"\ntime_column = "time"\ntag_column = "tag"\n'
            'value_column = "value"\nquality_column = "quality"\n' if long else
            '[historian]\nlayout = "wide"\ntime_column = "time"\n')
    lines = [head]
    for name, (unit, _, _) in LEVELS.items():
        lines.append(f'[signals.{name}]\ncolumn = "{TAGS[name]}"\n'
                     f'unit = "{units.get(name, unit)}"\n')
        if name in ranges:
            lines.append(f"range = {ranges[name]}\n")
    path.write_text("\n".join(lines), encoding="utf-8")
    return path


def _wide_csv(path, values: dict[str, np.ndarray]):
    times = pd.date_range("2026-03-01T00:00:00Z", periods=N, freq="1s")
    frame = pd.DataFrame({"time": times.strftime("%Y-%m-%dT%H:%M:%SZ")})
    for name, column in values.items():
        frame[TAGS[name]] = column
    frame.to_csv(path, index=False)
    return path


def test_clean_data_pass_with_nothing_excluded(tmp_path):
    history = load_history(_wide_csv(tmp_path / "h.csv", _values()),
                           _tag_map(tmp_path / "t.toml"), required=INPUT_SIGNALS)
    assert not history.report.errors
    assert sum(history.excluded.values()) == 0
    assert history.data.index.tz is not None and len(history.data) == N
    assert history.data["main_steam_pressure"].iloc[0] == pytest.approx(
        _values()["main_steam_pressure"][0] * 1e6)


def test_samples_outside_the_tag_map_range_are_excluded_and_counted(tmp_path):
    values = _values()
    values["main_steam_temperature"][[100, 400, 401]] = 700.0
    history = load_history(_wide_csv(tmp_path / "h.csv", values),
                           _tag_map(tmp_path / "t.toml",
                                    ranges={"main_steam_temperature": "[400.0, 600.0]"}),
                           required=INPUT_SIGNALS)
    column = history.data["main_steam_temperature"]
    assert column.iloc[[100, 400, 401]].isna().all() and column.notna().sum() == N - 3
    flags = history.flags["main_steam_temperature"].to_numpy()
    assert ((flags[[100, 400, 401]] & int(Flag.OUT_OF_RANGE | Flag.REMOVED)) != 0).all()
    assert history.excluded["main_steam_temperature"] == 3
    assert history.report.counts("rejected").loc["main_steam_temperature", "out_of_range"] == 3


@pytest.mark.parametrize(("signal", "declared", "scale"), [
    ("hp_exhaust_temperature", "degF", 1.0),  # °C written, °F declared
    ("main_steam_pressure", "MPa", 10.0),  # bar written, MPa declared
])
def test_a_unit_mix_up_stops_unless_accepted_and_never_feeds_a_model(tmp_path, signal,
                                                                     declared, scale):
    values = _values()
    values[signal] = values[signal] * scale
    data = _wide_csv(tmp_path / "h.csv", values)
    tags = _tag_map(tmp_path / "t.toml", units={signal: declared})
    with pytest.raises(DataQualityError) as caught:
        load_history(data, tags, required=INPUT_SIGNALS)
    message = str(caught.value)
    assert str(data) in message and signal in message and "--accept-quality-errors" in message
    accepted = load_history(data, tags, required=INPUT_SIGNALS, accept_errors=True)
    assert accepted.report.errors
    assert accepted.data[signal].isna().all()  # excluded: it can reach no model input
    assert accepted.excluded[signal] == N


def test_historian_quality_bad_and_uncertain_are_excluded(tmp_path):
    """Finding 4: rows marked Bad passed and shifted blade temperatures by 63 K."""
    values = _values()
    times = pd.date_range("2026-03-01T00:00:00Z", periods=N, freq="1s")
    rows = []
    for name, column in values.items():
        quality = np.array(["Good"] * N, dtype=object)
        if name == "main_steam_temperature":
            column = column.copy()
            column[200:205] = 475.0  # what a failing thermocouple reports, marked Bad
            quality[200:205] = "Bad"
            quality[300] = "Uncertain"
        rows.append(pd.DataFrame({"time": times.strftime("%Y-%m-%dT%H:%M:%SZ"),
                                  "tag": TAGS[name], "value": column, "quality": quality}))
    pd.concat(rows).to_csv(tmp_path / "long.csv", index=False)
    history = load_history(tmp_path / "long.csv", _tag_map(tmp_path / "t.toml", long=True),
                           required=INPUT_SIGNALS)
    column = history.data["main_steam_temperature"]
    assert column.iloc[200:205].isna().all() and np.isnan(column.iloc[300])
    assert column.notna().sum() == N - 6
    flags = history.flags["main_steam_temperature"].to_numpy()
    assert ((flags[200:205] & int(Flag.BAD_QUALITY)) != 0).all()
    assert history.excluded["main_steam_temperature"] == 6
    assert history.excluded["main_steam_pressure"] == 0


def test_required_signals_must_be_mapped_and_present(tmp_path):
    values = _values()
    data = _wide_csv(tmp_path / "h.csv", values)
    tags = _tag_map(tmp_path / "t.toml")
    with pytest.raises(ValueError, match="hp_power"):
        load_history(data, tags, required=("hp_power",))
    frame = pd.read_csv(data).drop(columns=[TAGS["main_steam_flow"]])
    frame.to_csv(tmp_path / "short.csv", index=False)
    with pytest.raises(ValueError, match=r"main_steam_flow.*needed"):
        load_history(tmp_path / "short.csv", tags, required=INPUT_SIGNALS)


def _cli(*arguments: str):
    from typer.testing import CliRunner

    from steamtwin.cli.main import app

    return CliRunner().invoke(app, list(arguments))


def test_calibrate_stops_on_a_unit_mix_up_before_any_model_run(tmp_path):
    """Finding 3: °C declared as °F gave params.json with 'RMSE 1000 K' and exit 0."""
    values = _values()
    data = _wide_csv(tmp_path / "h.csv", values)
    tags = _tag_map(tmp_path / "t.toml", units={"hp_exhaust_temperature": "degF"})
    out = tmp_path / "params.json"
    result = _cli("calibrate", "--data", str(data), "--tags", str(tags), "--out", str(out),
                  "--window", "2026-03-01T00:00:00Z/2026-03-01T00:10:00Z")
    assert result.exit_code == 1, result.output
    assert "hp_exhaust_temperature" in result.output and "--accept-quality-errors" in result.output
    assert not out.exists()


def test_window_times_need_a_utc_offset(tmp_path):
    data = _wide_csv(tmp_path / "h.csv", _values())
    tags = _tag_map(tmp_path / "t.toml")
    result = _cli("calibrate", "--data", str(data), "--tags", str(tags), "--out",
                  str(tmp_path / "p.json"), "--window", "2026-03-01 00:00/2026-03-01 00:10")
    assert result.exit_code == 2
    assert "no UTC offset" in result.output and "+08:00" in result.output


@pytest.mark.parametrize("command", [
    ["calibrate", "--out", "{folder}"],
    ["rom", "predict", "--rom", "missing.npz", "--out", "{folder}"],
    ["validate", "--rom", "missing.npz", "--report", "{file}"],
])
def test_output_paths_are_checked_before_any_work(tmp_path, command):
    data = _wide_csv(tmp_path / "h.csv", _values())
    tags = _tag_map(tmp_path / "t.toml")
    (tmp_path / "a-folder").mkdir()
    (tmp_path / "a-file").write_text("x")
    arguments = [part.format(folder=tmp_path / "a-folder", file=tmp_path / "a-file")
                 for part in command]
    result = _cli(*arguments, "--data", str(data), "--tags", str(tags))
    assert result.exit_code == 2, result.output
    assert ("is a folder" in result.output) or ("is a file" in result.output)
