"""The demo end to end at a tiny size: every table and figure present, numbers from the run."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from steamtwin.pipeline import STAGES, DemoSettings, run_demo
from steamtwin.twin import Twin
from steamtwin.validation.html import format_value
from steamtwin.web.screenshots import find_chromium, png_size

pytestmark = pytest.mark.slow  # 71 s of the full suite (2026-11-27): not in the quick loop

TINY = DemoSettings.quick(hold_hours=0.25, scan_points=12_000, uncertainty_samples=2,
                          evaluations=40, population=10, table7_generations=2, snapshots=8,
                          held_out=4, sobol_n_base=8, noise_repeats=1, workers=1)


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    calls = []
    result = run_demo(tmp_path_factory.mktemp("demo"), TINY,
                      progress=lambda fraction, message: calls.append((fraction, message)))
    return result, calls


def test_every_stage_reports_progress_and_time(demo):
    result, calls = demo
    started = [message for _, message in calls if message in STAGES]
    assert list(dict.fromkeys(started)) == list(STAGES)
    assert all(any(message.startswith(stage) for stage in STAGES) for _, message in calls)
    fractions = [fraction for fraction, _ in calls]
    assert fractions[0] == 0.0 and fractions[-1] == 1.0
    assert fractions == sorted(fractions)  # one callback for the run, never going back
    assert set(STAGES) <= set(result.timings)
    assert all(result.timings[s] > 0.0 for s in STAGES)


def test_the_output_folder_is_the_twin(demo):
    """The demo saves its twin with Twin.save: Twin.load reads the calibrated parameters and
    the ROM back, checked against the spec."""
    result, _ = demo
    twin = Twin.load(result.out)
    assert twin.parameters == result.params == result.twin.parameters
    assert twin.blade_rom is not None
    assert [step["step"] for step in twin.steps][:3] == ["from_spec", "calibrate", "build_rom"]


def test_report_holds_every_table_and_figure_of_the_method(demo):
    result, _ = demo
    document = json.loads((result.out / "report.json").read_text(encoding="utf-8"))
    for table in ("table5_operating", "table6_rmse", "table7_ga_sensitivity",
                  "table8_deviation", "sobol_indices", "noise_propagation",
                  "geometry_fidelity", "scan_uncertainty", "figure9_field_error", "live_twin",
                  "rotor_life_day"):
        assert document["tables"][table]["records"], table
        assert (result.out / document["tables"][table]["csv"]).stat().st_size > 0
    files = {figure["file"] for figure in document["figures"]}
    for pattern in ("figure7", "figure8", "figure9", "figure10", "sobol", "noise",
                    "deviation_map", "rotor/rotor_stress"):
        matches = [name for name in files if name.startswith(pattern)]
        assert matches, pattern
        assert all((result.out / name).stat().st_size > 10_000 for name in matches)
    html = (result.out / "report.html").read_text(encoding="utf-8")
    for name in files:  # embedded (self-contained page), the file beside it named
        assert f'data-file="{name}"' in html
    assert html.count('src="data:image/png;base64,') == len(files)
    assert html.index("<h2>Summary</h2>") < html.index("Run settings, versions and timings</h2>")
    assert set(STAGES) <= set(document["timings_s"])
    assert document["versions"]["steamtwin"]


def test_report_numbers_are_the_runs_own(demo):
    result, _ = demo
    document = json.loads((result.out / "report.json").read_text(encoding="utf-8"))
    table6 = pd.DataFrame(document["tables"]["table6_rmse"]["records"])
    expected = 100.0 * (1.0 - table6["rmse_calibrated_K"] / table6["rmse_empirical_K"])
    np.testing.assert_allclose(table6["reduction_pct"], expected, rtol=1e-12)
    pd.testing.assert_frame_equal(table6, result.tables["table6_rmse"].reset_index(drop=True),
                                  check_dtype=False)
    parameters = pd.DataFrame(document["tables"]["calibrated_parameters"]["records"])
    calibrated = dict(zip(parameters["parameter"], parameters["calibrated"], strict=True))
    assert calibrated["flow_coefficient"] == pytest.approx(result.params.flow_coefficient)
    assert (parameters["low_95"] <= parameters["calibrated"]).all()
    assert (parameters["calibrated"] <= parameters["high_95"]).all()
    saved = json.loads((result.out / "params.json").read_text(encoding="utf-8"))
    assert saved["posterior"]["intervals"]["flow_coefficient"]["low"] == pytest.approx(
        parameters.loc[parameters["parameter"] == "flow_coefficient", "low_95"].item())
    assert saved["parameters"]["flow_coefficient"] == pytest.approx(
        result.params.flow_coefficient)
    table8 = pd.DataFrame(document["tables"]["table8_deviation"]["records"])
    exhaust = table8[table8["signal"] == "hp_exhaust_temperature"]
    assert set(exhaust["window"]) == {"30 % load", "50 % load"}
    assert (exhaust["n_used"] + exhaust["n_skipped_missing"] + exhaust["n_skipped_rom_invalid"]
            == exhaust["n_samples"]).all()
    html = (result.out / "report.html").read_text(encoding="utf-8")
    for value in exhaust["max_abs_deviation"]:  # rounded for the row's unit, K
        assert f">{format_value(value, 'K')}<" in html


def test_the_live_stage_stored_what_the_plant_published(demo):
    """Issue 21: the demo's live stage — the plant over OPC UA into the service's database."""
    result, _ = demo
    document = json.loads((result.out / "report.json").read_text(encoding="utf-8"))
    rows = {row["quantity"]: row["value"]
            for row in document["tables"]["live_twin"]["records"]}
    published, stored = rows["samples published over OPC UA"], rows["samples stored"]
    # all but the gate's last look-ahead and its open 60-s clock bin
    assert published - 121 <= stored <= published
    # the plant the twin was calibrated on (its instruments, new noise): the residual is the
    # twin's error, not another plant's thermocouple bias (that was 1.8 K on the quick demo)
    assert 0.0 < rows["HP-exhaust residual, mean abs (K)"] < 1.2
    assert (result.out / "live.duckdb").stat().st_size > 0


def test_the_report_shows_each_dashboard_page_or_what_to_install(demo):
    """Issue 22, item 4: the live stage's dashboard, a 1366 × 768 screenshot of each unit page
    in the report (the Unit, History, Blade and Rotor pages drew the run's data: the live unit
    steps the rotor model the rotor stage fitted); without chromium, the section says what to
    install."""
    result, _ = demo
    document = json.loads((result.out / "report.json").read_text(encoding="utf-8"))
    html = (result.out / "report.html").read_text(encoding="utf-8")
    assert "Dashboard screenshots</h2>" in html
    shots = {figure["file"]: figure["caption"] for figure in document["figures"]
             if figure["file"].startswith("dashboard/")}
    if find_chromium() is None:
        assert not shots and "apt-get install chromium" in html
        return
    names = ("unit", "history", "alarms", "calibration", "blade", "rotor")
    assert sorted(shots) == sorted(f"dashboard/dashboard-{name}.png" for name in names)
    for file in shots:
        assert png_size(result.out / file) == (1366, 768)
    for name in ("unit", "history", "blade", "rotor"):
        caption = shots[f"dashboard/dashboard-{name}.png"]
        assert "did not render" not in caption and " points" in caption, caption
