"""The rotor stress report (steamtwin.rotor.report): files, figures, summary and life table on a
synthetic run frame of the RotorModel's columns, with the life of rotor_life."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.life import rotor_life
from steamtwin.rotor.report import (
    checked_allowable,
    default_allowable,
    life_table,
    rainflow_matrix,
    write_rotor_report,
)
from steamtwin.rotor.steel import steel

STEEL = steel("30CrMoNiV5-11")


def run_frame(hours: float = 6.0, step_s: float = 60.0) -> pd.DataFrame:
    """Two load cycles a day of a plausible groove/bore history (K, Pa)."""
    index = pd.date_range("2026-01-01 00:00", periods=int(hours * 3600 / step_s) + 1,
                          freq=f"{step_s:g}s", tz="Asia/Shanghai")
    phase = np.linspace(0.0, 2.0 * np.pi * hours / 3.0, len(index))
    groove_t = 780.0 + 20.0 * np.sin(phase)
    frame = pd.DataFrame(index=index)
    for location, scale in (("groove", 1.0), ("bore", 0.4)):
        equivalent = scale * (150e6 + 120e6 * np.cos(phase))
        frame[f"{location}_temperature"] = groove_t - (1.0 - scale) * 15.0
        for component, share in (("radial", 0.1), ("hoop", 1.0), ("axial", 0.5),
                                 ("shear", 0.05)):
            frame[f"{location}_{component}"] = share * equivalent
        frame[f"{location}_von_mises"] = np.abs(equivalent)
        frame[f"{location}_equivalent"] = equivalent
    frame["mean_temperature"] = groove_t - 10.0
    return frame


def life_of(frame: pd.DataFrame):
    """rotor_life at the groove with a load falling 100 → 30 % and back each 3 h."""
    hours = (frame.index - frame.index[0]).total_seconds().to_numpy() / 3600.0
    load = pd.Series(0.65 + 0.35 * np.cos(2.0 * np.pi * hours / 3.0), index=frame.index)
    return rotor_life(frame, STEEL, load=load)


def test_report_writes_every_file_with_the_run_and_the_summary(tmp_path):
    frame = run_frame()
    life = life_of(frame)
    result = write_rotor_report(tmp_path, frame, life, allowable_pa=450e6,
                                allowable_source="user", steam_temperature=
                                frame["groove_temperature"] + 15.0)
    for name in ("rotor_stress.parquet", "rotor_stress.csv", "rotor_cycles.csv",
                 "rotor_life.json", "report.html", "rotor_stress.png", "rotor_rainflow.png",
                 "rotor_ramps.png", "rotor_temperature.png"):
        assert (tmp_path / name).stat().st_size > 0, name
    back = pd.read_parquet(result.files["rotor_stress.parquet"])
    assert len(back) == len(frame)
    np.testing.assert_allclose(back["groove_von_mises"], frame["groove_von_mises"])
    assert len(pd.read_csv(tmp_path / "rotor_cycles.csv")) == len(life.cycles)
    document = json.loads((tmp_path / "report.json").read_text(encoding="utf-8"))
    peak = document["headlines"][0]
    assert peak["value"] == pytest.approx(frame["groove_von_mises"].max() / 1e6)
    assert peak["limit"] == pytest.approx(450.0) and peak["passed"]
    saved = json.loads((tmp_path / "rotor_life.json").read_text(encoding="utf-8"))
    assert len(saved["per_ramp"]) == len(life.per_ramp) == 4  # two falls, two rises
    assert sum(r["damage"] for r in saved["per_ramp"]) == pytest.approx(
        life.fatigue_damage + life.creep_damage, rel=1e-9)
    html = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert html.index("Summary") < html.index("Life consumed")


def test_an_allowable_below_the_peak_fails_the_summary(tmp_path):
    frame = run_frame(hours=3.0)
    result = write_rotor_report(tmp_path, frame, life_of(frame), allowable_pa=200e6,
                                allowable_source="user")
    document = json.loads(result.files["report.html"].with_name("report.json").read_text(
        encoding="utf-8"))
    assert not document["headlines"][0]["passed"]  # groove peak 270 MPa > 200 MPa
    assert document["headlines"][1]["passed"]  # bore peak 108 MPa


@pytest.mark.parametrize("bad", [-5e6, 0.0, float("nan")])
def test_a_non_positive_allowable_is_refused_naming_the_option(bad):
    with pytest.raises(RotorAreaError, match="--allowable"):
        checked_allowable(bad)


def test_the_default_allowable_is_the_tensile_strength_at_the_hottest_groove():
    # 3 S_m with S_m = R_m/3 (ASME III NB-3222.2, II-D App. 2) = R_m(T_max); R_m falls with T
    temperatures = np.array([700.0, 790.0, 750.0])
    assert default_allowable(STEEL, temperatures) == pytest.approx(
        float(STEEL.tensile_strength(790.0)))
    assert default_allowable(STEEL, temperatures) < float(STEEL.tensile_strength(700.0))


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.floats(0.0, 400e6), st.floats(-300e6, 300e6),
                          st.sampled_from([0.5, 1.0])), min_size=1, max_size=40))
def test_the_rainflow_matrix_keeps_every_cycle(rows):
    cycles = pd.DataFrame(rows, columns=["range_pa", "mean_pa", "count"])
    counts, range_edges, mean_edges = rainflow_matrix(cycles)
    assert counts.sum() == pytest.approx(cycles["count"].sum())
    assert range_edges[0] <= cycles["range_pa"].min() and range_edges[-1] >= cycles[
        "range_pa"].max()
    assert mean_edges[0] <= cycles["mean_pa"].min() and mean_edges[-1] >= cycles[
        "mean_pa"].max()


def test_life_table_per_day_is_the_record_over_its_days():
    frame = run_frame()
    life = life_of(frame)
    table = life_table(life).set_index("item")
    total = life.fatigue_damage + life.creep_damage
    assert table.loc["whole record", "total_damage"] == pytest.approx(total)
    assert table.loc["per day, mean", "total_damage"] == pytest.approx(total / len(life.per_day))
