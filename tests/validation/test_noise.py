"""Main-steam temperature noise through the FOM: steam follows, metal filters, linear in σ."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.model.parameters import ModelParameters
from steamtwin.validation.noise import noise_figure, noise_propagation


@pytest.fixture(scope="module")
def ramp_inputs(reference_spec) -> pd.DataFrame:
    """80 → 40 % at 3 %/min and a 5-min hold, 1-s samples (~20 min)."""
    load = ramp_profile(0.8, 0.4, 0.03, hold_before_s=60.0, hold_after_s=300.0)
    return load_profile_inputs(reference_spec, load)


@pytest.fixture(scope="module")
def table(reference_model, ramp_inputs) -> pd.DataFrame:
    return noise_propagation(reference_model, ramp_inputs, ModelParameters(), repeats=2,
                             random_state=7)


def test_steam_follows_the_inlet_and_the_metal_filters(table, reference_model):
    gain = table["gain"].unstack("output")
    assert list(gain.columns) == sorted(reference_model.output_signals)
    for sigma in (0.5, 1.0):
        row = gain.loc[sigma]
        # expansion at a fixed pressure ratio: ΔT_out/ΔT_in ≈ T_out/T_in (~0.7 at the exhaust)
        assert 0.9 <= row["control_stage_temperature"] <= 1.2
        assert 0.5 <= row["hp_exhaust_temperature"] <= 0.9
        assert row["hp_inner_casing_temperature"] < 0.2 * row["hp_exhaust_temperature"]
    exhaust = table.loc[(1.0, "hp_exhaust_temperature")]
    assert exhaust["mean_abs_deviation"] < exhaust["rms_deviation"] < exhaust["max_abs_deviation"]
    # a Gaussian's mean absolute value is √(2/π) of its RMS
    assert exhaust["mean_abs_deviation"] / exhaust["rms_deviation"] == pytest.approx(
        np.sqrt(2 / np.pi), rel=0.05)


def test_deviation_is_linear_in_sigma(table):
    rms = table["rms_deviation"].unstack("sigma_K")
    assert (rms[1.0] / rms[0.5]).to_numpy() == pytest.approx(2.0, rel=0.1)


def test_same_random_state_same_table(reference_model, ramp_inputs, table):
    window = ramp_inputs.iloc[:300]
    first = noise_propagation(reference_model, window, sigmas_K=(1.0,), repeats=1, random_state=3)
    again = noise_propagation(reference_model, window, sigmas_K=(1.0,), repeats=1, random_state=3)
    other = noise_propagation(reference_model, window, sigmas_K=(1.0,), repeats=1, random_state=4)
    pd.testing.assert_frame_equal(first, again)
    assert not first.equals(other)


@pytest.mark.parametrize(("arguments", "message"), [
    ({"sigmas_K": ()}, "sigmas_K"),
    ({"sigmas_K": (0.5, -1.0)}, "sigmas_K"),
    ({"sigmas_K": (np.nan,)}, "sigmas_K"),
    ({"repeats": 0}, "repeats"),
    ({"repeats": 1.5}, "repeats"),
    ({"random_state": -2}, "random_state"),
])
def test_bad_arguments_are_named(reference_model, ramp_inputs, arguments, message):
    with pytest.raises(ValueError, match=message):
        noise_propagation(reference_model, ramp_inputs, **arguments)


def test_missing_input_and_figure(reference_model, ramp_inputs, tmp_path):
    with pytest.raises(ValueError, match="main_steam_temperature"):
        noise_propagation(reference_model, ramp_inputs.drop(columns="main_steam_temperature"))
    path = noise_figure(reference_model, ramp_inputs, tmp_path / "noise.png", minutes=3.0)
    assert path.stat().st_size > 10_000
    with pytest.raises(ValueError, match="outputs"):
        noise_figure(reference_model, ramp_inputs, tmp_path / "x.png", outputs=("load",))
