"""``run_demo`` on any spec and row (issue 20, item 2): its settings' checks, and the cheap
stages on a spec given as a TOML path and a row other than hp1."""

from __future__ import annotations

import json

import numpy as np
import pytest

from steamtwin.pipeline import STAGES, DemoSettings, run_demo
from steamtwin.spec.fingerprint import load_spec_and_text
from steamtwin.twin import Twin

pytestmark = pytest.mark.slow  # 18 s of the full suite (2026-11-27): not in the quick loop


@pytest.fixture(scope="module")
def reference_toml(tmp_path_factory):
    """The reference unit's spec as a user's TOML file."""
    path = tmp_path_factory.mktemp("spec") / "unit.toml"
    path.write_text(load_spec_and_text("reference")[1], encoding="utf-8")
    return path


def test_settings_refuse_unknown_stages_and_missing_needs():
    with pytest.raises(ValueError, match=r"stages \['scan'\] unknown; the demo's stages"):
        DemoSettings.quick(stages=("scan",))
    with pytest.raises(ValueError, match=r"'GA sensitivity \(Table 7\)' needs \['calibration'\]"):
        DemoSettings.quick(stages=("virtual plant", "GA sensitivity (Table 7)"))
    with pytest.raises(ValueError, match=r"'calibration' needs \['virtual plant'\]"):
        DemoSettings.quick(stages=("calibration", "blade ROM", "geometry"))
    # in run order, the report always last
    settings = DemoSettings.quick(stages=("geometry", "full-order model"))
    assert settings.stages == ("full-order model", "geometry", "monitoring and report")
    assert DemoSettings.quick().stages == STAGES


def test_unknown_row_lists_the_specs_rows(tmp_path):
    with pytest.raises(ValueError, match=r"row 'hp99' is not a blade row of spec "
                                         r"'reference.*its rows: hp1, hp2, .*hp13, ip1"):
        run_demo(tmp_path / "out", DemoSettings.quick(row="hp99"))
    assert not (tmp_path / "out").exists()  # refused before any work


def test_plant_stages_need_the_reference_units_spec(tmp_path, reference_toml):
    other = tmp_path / "other.toml"
    text = reference_toml.read_text(encoding="utf-8")
    assert text.count("600") > 0
    spec, _ = load_spec_and_text(reference_toml)
    other.write_text(text.replace(f'"{spec.name}"', '"another unit"', 1), encoding="utf-8")
    with pytest.raises(ValueError, match=r"virtual plant, which simulates the built-in "
                                         r"reference unit, not spec 'another unit'"):
        DemoSettings.quick(spec=other).twin()
    # the stages that need no plant run on it
    assert DemoSettings.quick(spec=other, stages=("full-order model",)).twin().spec.name == (
        "another unit")


def test_cheap_stages_on_a_toml_spec_and_row_hp13(tmp_path, reference_toml):
    """The model and blade-ROM stages on the spec file and the last HP rotor row (no geometry
    stage: the ROM on the exact hp13 blade): the report holds the model's sections, the folder
    is the twin — Twin.load reads the spec file's text and the hp13 ROM back."""
    calls = []
    settings = DemoSettings.quick(spec=reference_toml, row="hp13",
                                  stages=("full-order model", "blade ROM"), snapshots=6,
                                  mesh_element_size=6e-3, workers=1)
    result = run_demo(tmp_path, settings, progress=lambda f, m: calls.append((f, m)))
    assert list(dict.fromkeys(m for _, m in calls if m in STAGES)) == [
        "full-order model", "blade ROM", "monitoring and report"]
    assert [f for f, _ in calls] == sorted(f for f, _ in calls) and calls[-1][0] == 1.0
    document = json.loads((tmp_path / "report.json").read_text(encoding="utf-8"))
    assert {"design_point", "off_design_line"} <= set(document["tables"])
    assert "table8_deviation" not in document["tables"]  # no plant, no monitoring
    assert document["settings"]["row"] == "hp13"
    design = document["tables"]["design_point"]["records"]
    power = next(row for row in design if row["quantity"] == "HP power (MW)")
    assert abs(power["difference"]) < 0.01 * power["spec"]  # the file is the reference unit
    twin = Twin.load(tmp_path)
    assert twin.spec_toml == reference_toml.read_text(encoding="utf-8")
    assert twin.steps[0] == {**twin.steps[0], "step": "from_spec", "source": str(reference_toml)}
    assert twin.steps[1]["step"] == "build_rom" and twin.steps[1]["row"] == "hp13"
    assert twin.parameters == result.params  # not calibrated: the empirical 1, 1, 1
    # the ROM's mesh is hp13's blade (span 163 mm), not hp1's (32 mm)
    extent = np.ptp(np.asarray(twin.blade_rom.mesh.points), axis=0).max()
    assert extent == pytest.approx(twin.blade_design("hp13").span, rel=0.1)


def test_the_live_stage_draws_the_calibrated_plants_instruments():
    """The demo's live stage runs the plant the twin was calibrated on: the instruments
    (calibration errors, drift rates) the plant stage's seed draws, whatever the scenario —
    with another seed's instruments the live residuals were the instruments' difference
    (HP exhaust 1.8 K mean abs, control-stage pressure 155 kPa, instead of 0.44 K / 2 kPa)."""
    from steamtwin.dcs.plant import run_plant
    from steamtwin.pipeline import _instruments

    drawn = _instruments(3)
    day = run_plant("day", hours=0.05, random_state=3).injected.sensors
    other = run_plant("day", hours=0.05, random_state=4).injected.sensors
    columns = ["bias_fraction", "drift_rate"]
    assert np.array_equal(drawn[columns].to_numpy(), day.loc[drawn.index, columns].to_numpy())
    assert not np.allclose(drawn["bias_fraction"], other.loc[drawn.index, "bias_fraction"])
