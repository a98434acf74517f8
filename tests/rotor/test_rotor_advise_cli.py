"""``steamtwin rotor advise`` (cli/rotor_advise.py) on a saved coarse rotor model: the printed
and JSON advice agree with the library, bad input exits 2 naming the value."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from steamtwin.cli.rotor import rotor_app
from steamtwin.rotor.advisor import RampAdvisor
from steamtwin.rotor.model import RotorModel
from steamtwin.spec import load_spec


@pytest.fixture(scope="module")
def model():
    return RotorModel(load_spec("reference"), mesh_size=0.08, groove_mesh_size=0.006,
                      fit_ramps=[(1.0, 0.75, 0.02)], training_hold_s=900.0,
                      training_step_s=120.0).fit()


@pytest.fixture(scope="module")
def model_file(model, tmp_path_factory):
    return model.save(tmp_path_factory.mktemp("rotor") / "rotor.npz")


def _advise(*options):
    return CliRunner().invoke(rotor_app, ["advise", *options])


def test_advice_json_matches_the_library(model, model_file, tmp_path):
    out = tmp_path / "advice.json"
    result = _advise("--from", "100", "--to", "80", "--model", str(model_file),
                     "--allowable", "80 MPa", "--hold", "900", "--json", str(out))
    assert result.exit_code == 0, result.output
    advice = json.loads(out.read_text())["advice"]
    expected = RampAdvisor(model, 80e6).fit().advise(None, 1.0, 0.8, hold_after_s=900.0)
    assert advice["rate_percent_per_min"] == pytest.approx(100 * expected.rate_per_min)
    assert advice["limited_by"] == "allowable"
    assert advice["allowable_pa"]["groove"] == pytest.approx([-80e6, 80e6])
    assert f"{100 * expected.rate_per_min:.2f} %/min" in result.output
    assert "groove: peak" in result.output and "life cost at the groove" in result.output


@pytest.mark.parametrize(("options", "named"), [
    (["--from", "50", "--to", "10"], "to_load = 0.1 (10 % of rated load)"),
    (["--from", "60", "--to", "40", "--allowable", "10MPa"], "standing"),
    (["--from", "60", "--to", "40", "--allowable", "400MPa", "--cycles", "1000"], "not both"),
    (["--from", "60", "--to", "40", "--allowable", "400 K"], "allowable"),
    (["--from", "60", "--to", "40", "--state", "rotor.npz"], "not a rotor state"),
])
def test_bad_input_exits_2_naming_it(model_file, options, named):
    options = [str(model_file) if item == "rotor.npz" else item for item in options]
    result = _advise(*options, "--model", str(model_file))
    assert result.exit_code == 2
    assert named in result.output


def test_help_has_an_example():
    result = _advise("--help")
    assert result.exit_code == 0 and "steamtwin rotor advise --from 50 --to 30" in result.output
