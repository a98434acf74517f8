"""The steamtwin command: help with examples, turbine show, simulate round trip, errors."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from steamtwin.cli.main import app
from steamtwin.dcs.plant import KKS_TAGS, plant_tag_map
from steamtwin.dcs.tagmap import write_tag_map
from steamtwin.model.operating import load_profile_inputs
from steamtwin.model.parameters import ModelParameters

runner = CliRunner()


@pytest.mark.parametrize(
    "command",
    [[], ["turbine", "show"], ["simulate"], ["demo"], ["dcs", "check"], ["plant"], ["calibrate"],
     ["calibrate-online"], ["rom", "build"], ["rom", "predict"], ["rom", "info"],
     ["geometry", "scan"], ["geometry", "preprocess"], ["geometry", "mesh"],
     ["geometry", "assemble"], ["geometry", "uncertainty"], ["validate"], ["plant", "serve"],
     ["history", "export"], ["serve"]],
)
def test_every_command_has_help_with_an_example(command):
    result = runner.invoke(app, [*command, "--help"])
    assert result.exit_code == 0
    assert "Example: steamtwin" in result.output


def _description_lines(output: str) -> list[str]:
    """The help's prose between the usage line and the first option box."""
    lines = output.splitlines()
    start = next(i for i, line in enumerate(lines) if "Usage:" in line) + 1
    stop = next((i for i, line in enumerate(lines) if line.lstrip().startswith("╭")),
                len(lines))
    return [line.strip() for line in lines[start:stop]]


@pytest.mark.parametrize("command", [["calibrate"], ["calibrate-online"], ["validate"],
                                     ["rom", "predict"], ["geometry", "scan"]])
def test_help_prose_is_wrapped_to_the_terminal_not_the_source(command):
    """Issue 20, item 6: a docstring hard-wrapped at 100 columns read as broken lines at 80
    ("… recursive filter (a" / "random-walk state …"): every prose line but a paragraph's last
    fills the 80-column terminal."""
    result = runner.invoke(app, [*command, "--help"], env={"COLUMNS": "80"}, terminal_width=80)
    assert result.exit_code == 0
    lines = _description_lines(result.output)
    short = [line for line, following in itertools.pairwise(lines)
             if line and following and not following.startswith(("-", "*"))
             and len(line) < 50]
    assert short == []


def test_turbine_show_prints_heat_balance_and_stages():
    result = runner.invoke(app, ["turbine", "show", "reference"])
    assert result.exit_code == 0, result.output
    assert "13.03 MPa" in result.output and "1800 t/h" in result.output
    assert "GV4" in result.output and "0.1155" not in result.output
    # the drawn rotor section of the reference spec's [rotor], in mm and rpm
    assert "HP rotor section (30CrMoNiV5-11, 3000 rpm)" in result.output
    assert "600.0" in result.output and "25.0" in result.output


def test_simulate_round_trip_in_wire_units(tmp_path, reference_model, reference_spec):
    frame = load_profile_inputs(reference_spec, np.full(5, 0.5))
    wire = pd.DataFrame({
        "time": frame.index.strftime("%Y-%m-%dT%H:%M:%SZ"),
        "main_steam_pressure": frame["main_steam_pressure"] / 1e6,
        "main_steam_temperature": frame["main_steam_temperature"] - 273.15,
        "main_steam_flow": frame["main_steam_flow"] * 3.6,
        "hp_exhaust_pressure": frame["hp_exhaust_pressure"] / 1e6,
    })
    inputs, outputs = tmp_path / "inputs.csv", tmp_path / "outputs.csv"
    wire.to_csv(inputs, index=False)
    result = runner.invoke(app, ["simulate", "--inputs", str(inputs), "--out", str(outputs)])
    assert result.exit_code == 0, result.output
    written = pd.read_csv(outputs)
    expected = reference_model.simulate(frame).iloc[-1]
    assert written["hp_exhaust_temperature"].iloc[-1] == pytest.approx(
        expected.hp_exhaust_temperature - 273.15, abs=1e-3)
    assert written["control_stage_pressure"].iloc[-1] == pytest.approx(
        expected.control_stage_pressure / 1e6, rel=1e-5)
    assert written["hp_power"].iloc[-1] == pytest.approx(expected.hp_power / 1e6, rel=1e-5)


def test_simulate_reports_bad_rows_without_traceback(tmp_path):
    inputs = tmp_path / "inputs.csv"
    inputs.write_text(
        "time,main_steam_pressure,main_steam_temperature,main_steam_flow,hp_exhaust_pressure\n"
        "0,16.7,538,1800,3.9\n1,16.7,abc,1800,3.9\n"
    )
    result = runner.invoke(app, ["simulate", "--inputs", str(inputs), "--out",
                                 str(tmp_path / "o.csv")])
    assert result.exit_code == 2
    assert "column 'main_steam_temperature' data row 2 (line 3)" in result.output
    assert "Traceback" not in result.output


def test_demo_maps_its_options_and_prints_the_runs_figures(tmp_path, monkeypatch):
    """The CLI's wiring; the chain itself is tested in tests/validation/test_demo_report.py."""
    import steamtwin.cli.demo as demo_cli
    from steamtwin.pipeline import STAGES, DemoResult

    seen = {}

    def fake_run(out, settings, progress):
        seen["settings"] = settings
        import logging

        logging.getLogger("asyncua.client").warning("Publish iteration crashed")
        for k, stage in enumerate(settings.stages):  # as run_demo: equal shares, named
            progress(k / len(STAGES), stage)
            progress((k + 1) / len(STAGES), f"{stage}: done")
        tables = {
            "table6_rmse": pd.DataFrame({"condition": ["30 % load"], "rmse_empirical_K": [2.0],
                                         "rmse_calibrated_K": [0.5], "reduction_pct": [75.0]}),
            "table8_deviation": pd.DataFrame({"signal": ["hp_exhaust_temperature"],
                                              "window": ["30 % load"],
                                              "mean_abs_deviation": [0.21],
                                              "max_abs_deviation": [1.22]}),
        }
        return DemoResult(out=out, report=None, params=ModelParameters(0.98, 1.2, 1.3),
                          tables=tables, timings={stage: 1.0 for stage in STAGES},
                          warnings=["IdentifiabilityWarning: test"])

    monkeypatch.setattr(demo_cli, "run_demo", fake_run)
    result = runner.invoke(app, ["demo", "--out", str(tmp_path), "--full", "--hold-hours",
                                 "1.5", "--workers", "2", "--seed", "7", "--row", "hp13"])
    assert result.exit_code == 0, result.output
    settings = seen["settings"]
    assert (settings.mode, settings.calibration, settings.snapshots) == ("full", "ga", 32)
    assert (settings.hold_hours, settings.workers, settings.random_state) == (1.5, 2, 7)
    assert (settings.spec, settings.row) == ("reference", "hp13")
    text = " ".join(result.output.split())  # rich wraps long lines
    assert "flow 0.9800" in text and "2.00 → 0.50 K (−75 %)" in text
    assert "mean abs deviation 0.21 K, max 1.22 K" in text
    assert "warning: IdentifiabilityWarning: test" in text
    # the libraries' log goes to a file in the output folder, not between the progress bars
    assert "Publish iteration crashed" not in result.output
    log = (tmp_path / "demo.log").read_text()
    assert "WARNING asyncua.client: Publish iteration crashed" in log
    result = runner.invoke(app, ["demo", "--out", str(tmp_path / "quick"), "--quick",
                                 "--turbine", "unit.toml"])
    assert result.exit_code == 0, result.output
    assert (seen["settings"].mode, seen["settings"].spec) == ("quick", "unit.toml")


def _historian_csv(path, pressure_mpa):
    """Ten minutes of the four model inputs under the virtual plant's KKS tags, wire units."""
    times = pd.date_range("2026-03-01 10:00:00", periods=600, freq="1s")
    rng = np.random.default_rng(3)
    pd.DataFrame({
        "Timestamp": times.strftime("%Y-%m-%d %H:%M:%S"),
        KKS_TAGS["main_steam_pressure"]: pressure_mpa + rng.normal(0, 0.01, times.size),
        KKS_TAGS["main_steam_temperature"]: 538.0 + rng.normal(0, 0.5, times.size),
        KKS_TAGS["main_steam_flow"]: 1000.0 + rng.normal(0, 5.0, times.size),
        KKS_TAGS["hp_exhaust_pressure"]: 2.2 + rng.normal(0, 0.005, times.size),
    }).to_csv(path, index=False)


@pytest.mark.parametrize(("pressure", "exit_code", "expected"), [
    (11.0, 0, "0 error(s), 0 warning(s)"),
    (110.0, 1, "bar"),  # a bar reading declared as MPa (the range 0–25 MPa flags it too)
])
def test_dcs_check_reports_and_exits(tmp_path, pressure, exit_code, expected):
    tags, data, report = tmp_path / "tags.toml", tmp_path / "history.csv", tmp_path / "q.json"
    write_tag_map(plant_tag_map(), tags)
    _historian_csv(data, pressure)
    result = runner.invoke(app, ["dcs", "check", str(data), "--tags", str(tags),
                                 "--json", str(report)])
    assert result.exit_code == exit_code, result.output
    assert expected in result.output
    assert report.exists() and '"findings"' in report.read_text()


def test_dcs_check_names_a_bad_tag_map(tmp_path):
    tags = tmp_path / "tags.toml"
    write_tag_map(plant_tag_map(), tags)
    tags.write_text(tags.read_text().replace('unit = "t/h"', 'unit = "MPa"'))
    result = runner.invoke(app, ["dcs", "check", str(tmp_path / "x.csv"), "--tags", str(tags)])
    assert result.exit_code == 2
    assert "main_steam_flow" in result.output and "MPa" in result.output


def _one_line(output):
    """CLI output with rich's error-box borders and line wraps removed."""
    import re

    return re.sub(r"[\s│╭╮╰╯─]+", " ", output)


def _reference_text():
    from importlib import resources

    return (resources.files("steamtwin.spec") / "data" / "reference.toml").read_text()


@pytest.mark.parametrize(("content", "expected"), [
    (_reference_text().replace("[[extractions]]", "[[extraction]]").encode(),
     "unit.toml: extraction is not a turbine spec field (did you mean 'extractions'?)"),
    (_reference_text().replace('mean_diameter = "0.9539 m"', 'pitch_diameter = "0.9539 m"')
     .encode(), "unit.toml: stage 3: stages[3].pitch_diameter is not a turbine spec field "
     "(did you mean 'mean_diameter'?)"),
    (bytes(range(256)) * 4, "unit.toml: not UTF-8 text (byte 0x80 at offset 128, line 2)"),
], ids=["extraction-typo", "stage-key", "binary"])
def test_turbine_show_refuses_a_bad_spec_without_traceback(tmp_path, content, expected):
    """Issue 16, findings 5 and 6: exit 0 on a dropped bleed, a traceback on a binary file."""
    spec = tmp_path / "unit.toml"
    spec.write_bytes(content)
    # a terminal wide enough that rich does not break the (long, temporary) path mid-word
    result = runner.invoke(app, ["turbine", "show", str(spec)], env={"COLUMNS": "400"},
                           terminal_width=400)
    assert result.exit_code == 2 and isinstance(result.exception, SystemExit)
    assert expected in _one_line(result.output)
    assert "Traceback" not in result.output


@pytest.mark.parametrize(("document", "expected"), [
    ("{}", "params.json: missing coefficient(s) flow_coefficient, friction_coefficient, "
     "heat_transfer_coefficient"),
    ('{"parameters": {"flow_coefficient": 1.0, "heat_transfer_coefficient": 1.0}}',
     "params.json: missing coefficient(s) parameters.friction_coefficient"),
    ('{"flow_coefficient": 1.0, "frictoin_coefficient": 1.2, "heat_transfer_coefficient": 1.0}',
     "params.json: frictoin_coefficient is not a parameter file field "
     "(did you mean 'friction_coefficient'?)"),
], ids=["empty", "missing", "misspelled"])
def test_simulate_refuses_a_params_file_that_would_default(tmp_path, document, expected):
    """Issue 16, finding 5: ``{}`` or a missing/misspelled coefficient used to run at 1.0."""
    params, inputs, out = tmp_path / "params.json", tmp_path / "in.csv", tmp_path / "out.csv"
    params.write_text(document)
    inputs.write_text("time,main_steam_pressure,main_steam_temperature,main_steam_flow,"
                      "hp_exhaust_pressure\n0,16.7,538,1800,3.9\n")
    result = runner.invoke(app, ["simulate", "--inputs", str(inputs), "--out", str(out),
                                 "--params", str(params)])
    assert result.exit_code == 2 and isinstance(result.exception, SystemExit)
    assert expected in _one_line(result.output)
    assert "Traceback" not in result.output and not out.exists()
