"""``steamtwin rotor stress`` on a short virtual-plant record: the files it writes agree with each
other and with the input; bad input (no ``[rotor]`` in the spec, a non-positive allowable) is
exit code 2 with a message saying what to change, before any work."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import steamtwin.rotor.report as rotor_report
from steamtwin.cli.main import app
from steamtwin.dcs.plant import run_plant, write_plant
from steamtwin.model.parameters import ModelParameters
from steamtwin.spec.fingerprint import load_spec_and_text

runner = CliRunner()
PLANT_HOURS = 0.1  # deep-peak-50: 10 min at 100 %, the 17-min ramp to 50 %, a 6-min hold


class CoarseRotorModel(rotor_report.RotorModel):
    """The command's rotor model with a coarse mesh and one training ramp at 1-min steps
    (~2 s CPU to fit instead of ~1 min): the command's path, not the model's accuracy, is
    under test here."""

    def __init__(self, spec, *, mesh_size=None):
        super().__init__(spec, mesh_size=0.1, groove_mesh_size=4e-3,
                         fit_ramps=((1.0, 0.3, 0.08),), training_step_s=60.0)


@pytest.fixture(scope="module")
def plant_files(tmp_path_factory):
    run = run_plant("deep-peak-50", hours=PLANT_HOURS, random_state=3)
    return write_plant(run, tmp_path_factory.mktemp("plant"))


@pytest.fixture(scope="module")
def stress_run(plant_files, tmp_path_factory):
    out = tmp_path_factory.mktemp("rotor-report")
    patch = pytest.MonkeyPatch()
    patch.setattr(rotor_report, "RotorModel", CoarseRotorModel)
    params = out / "params.json"
    ModelParameters(heat_transfer_coefficient=1.2).to_json(params)
    result = runner.invoke(app, ["rotor", "stress", "--data", str(plant_files["historian"]),
                                 "--tags", str(plant_files["tag_map"]), "--report", str(out),
                                 "--params", str(params), "--allowable", "450 MPa"])
    patch.undo()
    return result, out


def test_the_report_files_agree_with_the_input_and_each_other(stress_run, plant_files):
    result, out = stress_run
    assert result.exit_code == 0, result.output
    series = pd.read_parquet(out / "rotor_stress.parquet")
    historian = pd.read_parquet(plant_files["historian"])
    assert len(series) == len(historian)  # one row per input sample
    assert len(pd.read_csv(out / "rotor_stress.csv")) == len(series)
    life = json.loads((out / "rotor_life.json").read_text(encoding="utf-8"))
    per_ramp = sum(r["fatigue_damage"] + r["creep_damage"] for r in life["per_ramp"])
    per_day = sum(r["fatigue_damage"] + r["creep_damage"] for r in life["per_day"])
    total = life["summary"]["fatigue_damage"] + life["summary"]["creep_damage"]
    assert per_day == pytest.approx(total, rel=1e-9)
    assert per_ramp == pytest.approx(total, rel=1e-9)  # the ramps partition the record
    # one ramp, 100 → 50 % demand at 3 %/min; loads as fractions of the rated 600 MW output
    (ramp,) = life["per_ramp"]
    assert ramp["from_load"] > 0.9 and 0.45 < ramp["to_load"] < 0.6
    assert -0.035 < ramp["rate_per_min"] < -0.02
    cycles = pd.read_csv(out / "rotor_cycles.csv")
    assert cycles["damage"].sum() == pytest.approx(life["summary"]["fatigue_damage"], rel=1e-9)
    assert life["peak_groove_von_mises_pa"] == pytest.approx(series["groove_von_mises"].max())
    report = json.loads((out / "report.json").read_text(encoding="utf-8"))
    assert report["headlines"][0]["limit"] == pytest.approx(450.0)
    assert report["settings"]["params"].endswith("params.json")
    assert np.all(np.isfinite(series.to_numpy(dtype=float)))
    assert "peak von Mises at the groove" in result.output


def test_a_spec_without_rotor_is_refused_saying_what_to_add(tmp_path, plant_files):
    text = load_spec_and_text("reference")[1]
    start, end = text.index("[rotor]"), text.index("[sliding_pressure]")
    spec = tmp_path / "no-rotor.toml"
    spec.write_text(text[:start] + text[end:], encoding="utf-8")
    result = runner.invoke(app, ["rotor", "stress", "--data", str(plant_files["historian"]),
                                 "--tags", str(plant_files["tag_map"]), "--turbine", str(spec),
                                 "--report", str(tmp_path / "out")])
    assert result.exit_code == 2
    assert "has no [rotor] section: add one" in result.output
    assert not (tmp_path / "out" / "report.html").exists()


@pytest.mark.parametrize("allowable", ["-50 MPa", "0 MPa", "450"])
def test_a_bad_allowable_is_refused_naming_the_option(tmp_path, allowable):
    result = runner.invoke(app, ["rotor", "stress", "--data", "absent.parquet", "--tags",
                                 "absent.toml", "--report", str(tmp_path / "out"),
                                 "--allowable", allowable])
    assert result.exit_code == 2
    assert "--allowable" in result.output
    assert not (tmp_path / "out").exists()  # refused before any work


def test_help_shows_an_example():
    result = runner.invoke(app, ["rotor", "stress", "--help"])
    assert result.exit_code == 0
    assert "Example: steamtwin rotor stress --data" in " ".join(result.output.split())
