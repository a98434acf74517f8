"""``steamtwin turbine check`` and the model's design point in ``turbine show``."""

from __future__ import annotations

from importlib.resources import files

import pandas as pd
import pytest
from typer.testing import CliRunner

from steamtwin.cli.main import app
from steamtwin.model.design_check import design_line

runner = CliRunner()


@pytest.fixture(scope="module")
def all_valves_open_spec(tmp_path_factory):
    """The reference spec with GV4 open at design too: every valve open at rated load."""
    text = files("steamtwin.spec").joinpath("data/reference.toml").read_text(encoding="utf-8")
    assert text.count("open_at_design = false") == 1
    path = tmp_path_factory.mktemp("spec") / "all-open.toml"
    path.write_text(text.replace("open_at_design = false", "open_at_design = true"),
                    encoding="utf-8")
    return path


def test_check_reference_prints_verdict_design_point_and_line(reference_model):
    result = runner.invoke(app, ["turbine", "check", "reference"])
    assert result.exit_code == 0, result.output
    assert "reference: consistent" in result.output
    assert "13.03 MPa" in result.output and "13.026 MPa" in result.output  # spec, model p1
    assert "177.36 MW" in result.output
    for row in ("p1 (MPa)", "T ex (°C)", "HP power (MW)", "GV4 opening (%)", "30 %"):
        assert row in result.output


def test_check_writes_the_line_in_engineering_units(tmp_path, reference_spec,
                                                    reference_model):
    out = tmp_path / "new" / "line.csv"
    result = runner.invoke(app, ["turbine", "check", "reference", "--loads", "1,0.5",
                                 "--csv", str(out)])
    assert result.exit_code == 0, result.output
    table = pd.read_csv(out, index_col="load_pct")
    assert list(table.index) == [100, 50]
    line = design_line(reference_spec, loads=(1.0, 0.5), model=reference_model)
    pd.testing.assert_series_equal(
        table["control_stage_pressure_MPa"],
        pd.Series(line["control_stage_pressure"].to_numpy() / 1e6, index=table.index,
                  name="control_stage_pressure_MPa"), rtol=1e-5)
    assert table.loc[100, "main_steam_flow_t_per_h"] == pytest.approx(1800)
    assert table.loc[50, "hp_exhaust_temperature_degC"] == pytest.approx(
        line.loc[0.5, "hp_exhaust_temperature"] - 273.15, abs=1e-3)
    # the reference's valve management (10 % overlap) cracks GV4 as GV3 nears full lift
    assert 0.0 < table.loc[100, "GV4_opening_pct"] < 5.0


def test_check_refuses_every_valve_open_with_the_reason(all_valves_open_spec, tmp_path):
    out = tmp_path / "line.csv"
    result = runner.invoke(app, ["turbine", "check", str(all_valves_open_spec),
                                 "--csv", str(out)])
    assert result.exit_code == 1
    assert "cannot pass its rated flow" in result.output
    assert "open_at_design = false on GV4" in result.output
    assert not out.exists()


def test_show_puts_the_model_beside_the_heat_balance(reference_model):
    result = runner.invoke(app, ["turbine", "show", "reference"])
    assert result.exit_code == 0, result.output
    assert "model − spec" in result.output and "13.026 MPa" in result.output


def test_show_refuses_a_spec_the_model_cannot_run(all_valves_open_spec):
    result = runner.invoke(app, ["turbine", "show", str(all_valves_open_spec)])
    assert result.exit_code == 1
    assert "GV4" in result.output  # the spec is still shown
    assert "error: the model cannot run this spec" in result.output
    assert "every governing valve is open at rated load" in result.output


@pytest.mark.parametrize(
    ("arguments", "message"),
    [(["--loads", "1,x"], "comma-separated load fractions"),
     (["--loads", "1,0.1"], "0.2…1.1 (got 0.1)")],
)
def test_bad_loads_are_usage_errors(arguments, message):
    result = runner.invoke(app, ["turbine", "check", "reference", *arguments])
    assert result.exit_code == 2
    assert message in " ".join(result.output.replace("│", " ").split())


def test_csv_that_cannot_be_written_is_refused_first(tmp_path):
    result = runner.invoke(app, ["turbine", "check", "reference", "--csv", str(tmp_path)])
    assert result.exit_code == 2
    assert "--csv" in result.output and "is a folder" in result.output


def test_check_help_has_an_example():
    result = runner.invoke(app, ["turbine", "check", "--help"])
    assert result.exit_code == 0 and "Example: steamtwin turbine check" in result.output
