"""``steamtwin turbine derive``: a spec file from a heat balance, errors as exit code 2."""

from __future__ import annotations

from importlib.resources import files

from typer.testing import CliRunner

from steamtwin.cli.main import app
from steamtwin.spec import load_spec

runner = CliRunner()
KIT = files("steamtwin.spec").joinpath("data/example-600mw-heat-balance.toml")


def test_derive_writes_a_loadable_spec_and_prints_notes(tmp_path):
    out = tmp_path / "new" / "unit.toml"
    result = runner.invoke(app, ["turbine", "derive", str(KIT), "--out", str(out),
                                 "--name", "Unit 3"])
    assert result.exit_code == 0, result.output
    assert "note: design point: 'THA'" in result.output
    assert f"wrote {out}: 'Unit 3', 11 pressure stages, 6 governing valves" in result.output
    assert load_spec(out).name == "Unit 3"


def test_derive_bad_heat_balance_is_exit_2_naming_the_point(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(KIT.read_text(encoding="utf-8").replace(
        'control_stage_mean_diameter = "1.05 m"', 'control_stage_mean_diameter = "0.25 m"'),
        encoding="utf-8")
    result = runner.invoke(app, ["turbine", "derive", str(bad), "--out", str(tmp_path / "u.toml")])
    assert result.exit_code == 2
    assert "error: " in result.output and "points[2] ('THA')" in result.output
    assert not (tmp_path / "u.toml").exists()


def test_derive_checks_the_output_path_first(tmp_path):
    result = runner.invoke(app, ["turbine", "derive", str(tmp_path / "missing.toml"),
                                 "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert "--out" in result.output and "is a folder" in result.output


def test_derive_help_has_an_example():
    result = runner.invoke(app, ["turbine", "derive", "--help"])
    assert result.exit_code == 0 and "steamtwin turbine derive heat-balance.toml" in result.output
