"""``steamtwin turbine fit`` and ``turbine check --heat-balance`` on a thermal kit written as TOML.

The kit is what the reference model itself computes along its sliding line, so a spec whose
part-load laws were perturbed must be brought back onto it by the fit (issue 17, item 4), and
``check`` must mark the perturbed spec's points outside the band and pass the fitted one.
"""

from __future__ import annotations

from importlib import resources

import pytest
from typer.testing import CliRunner

from steamtwin.cli.main import app
from steamtwin.model.design_check import design_line
from steamtwin.model.design_fit import fitted_spec_toml
from steamtwin.spec import load_spec
from steamtwin.spec.turbine import PartLoad

pytestmark = pytest.mark.slow  # 6 s of the full suite (2026-11-27): not in the quick loop

runner = CliRunner()
LOADS = (1.0, 0.75, 0.6, 0.5, 0.4, 0.3)
PERTURBED = PartLoad(reynolds_exponent=0.15, admission_loss_multiplier=1.6,
                     control_stage_velocity_ratio_factor=0.92, flow_capacity_multiplier=1.04)


@pytest.fixture(scope="module")
def files(tmp_path_factory, reference_spec):
    folder = tmp_path_factory.mktemp("kit")
    line = design_line(reference_spec, LOADS)
    text = ['name = "the reference model\'s own line"', "", "[machine]",
            "pressure_stages = 12", 'rotational_speed = "3000 rpm"',
            'control_stage_mean_diameter = "1.10 m"', "valve_arcs = [0.25, 0.25, 0.22, 0.20]",
            "valve_opening_order = [1, 1, 2, 3]"]
    for load, row in line.iterrows():
        text += ["", "[[points]]", f'label = "{load:.0%}"', f'load = "{600.0 * load:.3f} MW"']
        text += [f'{name} = "{row[name] / 1e6:.6f} MPa"' for name in
                 ("main_steam_pressure", "control_stage_pressure", "hp_exhaust_pressure")]
        text += [f'{name} = "{row[name] - 273.15:.4f} degC"' for name in
                 ("main_steam_temperature", "control_stage_temperature",
                  "hp_exhaust_temperature")]
        text.append(f'main_steam_flow = "{row["main_steam_flow"] * 3.6:.4f} t/h"')
    kit = folder / "kit.toml"
    kit.write_text("\n".join(text) + "\n", encoding="utf-8")
    reference = (resources.files("steamtwin.spec") / "data" / "reference.toml").read_text(
        encoding="utf-8")
    perturbed = folder / "perturbed.toml"
    perturbed.write_text(fitted_spec_toml(reference, PERTURBED), encoding="utf-8")
    return kit, perturbed


def test_fit_brings_perturbed_laws_back_onto_the_kit(files, tmp_path):
    kit, perturbed = files
    out = tmp_path / "fitted" / "unit.toml"
    result = runner.invoke(app, ["turbine", "fit", str(perturbed), "--heat-balance", str(kit),
                                 "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "Before the fit" in result.output and "After the fit" in result.output
    assert "Fitted [part_load] laws" in result.output and f"wrote {out}" in result.output
    fitted = load_spec(out).part_load
    for name, default in vars(PartLoad()).items():
        assert getattr(fitted, name) == pytest.approx(default, abs=2e-3), name
    check = runner.invoke(app, ["turbine", "check", str(out), "--loads", "1,0.5",
                                "--heat-balance", str(kit)])
    assert check.exit_code == 0, check.output
    assert "The model at the points of" in check.output and " !" not in check.output


def test_check_marks_points_outside_the_band(files):
    kit, perturbed = files
    result = runner.invoke(app, ["turbine", "check", str(perturbed), "--loads", "1",
                                 "--heat-balance", str(kit)])
    assert result.exit_code == 1, result.output
    assert "outside ±0.5 % / ±1.0 K" in result.output and " !" in result.output


def test_fit_refuses_bad_input_before_any_work(files, tmp_path):
    kit, perturbed = files
    (tmp_path / "folder.toml").mkdir()
    onto_folder = runner.invoke(app, ["turbine", "fit", str(perturbed), "--heat-balance",
                                      str(kit), "--out", str(tmp_path / "folder.toml")])
    assert onto_folder.exit_code == 2 and "is a folder" in onto_folder.output
    too_many = runner.invoke(app, ["turbine", "fit", str(perturbed), "--heat-balance", str(kit),
                                   "--out", str(tmp_path / "o.toml"), "--parameters",
                                   "reynolds_exponent,no_such_law"])
    assert too_many.exit_code == 2 and "no_such_law" in too_many.output
    bad_kit = tmp_path / "bad.toml"
    bad_kit.write_text(kit.read_text(encoding="utf-8").replace("[machine]", "[machin]"),
                       encoding="utf-8")
    refused = runner.invoke(app, ["turbine", "fit", str(perturbed), "--heat-balance",
                                  str(bad_kit), "--out", str(tmp_path / "o.toml")])
    assert refused.exit_code == 2 and "machin" in refused.output


def test_help_has_an_example():
    result = runner.invoke(app, ["turbine", "fit", "--help"])
    assert result.exit_code == 0 and "Example: steamtwin turbine fit" in result.output
