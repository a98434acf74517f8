"""RotorModel (rotor/model.py): the fitted ROM against the FEM on an unseen ramp, streaming vs
batch, save/load, and the fatigue scalar."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from steamtwin.errors import RotorAreaError
from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.rotor.model import RotorModel, RotorState
from steamtwin.rotor.stress_points import COMPONENTS, StressState
from steamtwin.spec import load_spec

STEP_S = 30.0


@pytest.fixture(scope="module")
def spec():
    return load_spec("reference")


@pytest.fixture(scope="module")
def model(spec):
    """A coarse model (≈ 360 nodes, 30-s training steps, 30-min holds): a few seconds to fit."""
    return RotorModel(spec, mesh_size=0.06, groove_mesh_size=0.004, training_step_s=STEP_S,
                      training_hold_s=1800.0).fit()


@pytest.fixture(scope="module")
def unseen(spec, model):
    """A 5 %/min ramp 100 → 30 → 100 % (not a training rate) as steam-side conditions."""
    load = np.concatenate([ramp_profile(1.0, 0.3, 0.05, 60.0, 900.0, STEP_S),
                           ramp_profile(0.3, 1.0, 0.05, 0.0, 900.0, STEP_S)[1:]])
    return model.steam_side(load_profile_inputs(spec, load, STEP_S))


def test_rom_follows_the_fem_on_an_unseen_ramp(model, unseen):
    rom = model.simulate_steam(unseen).frame
    fem = model.simulate_steam(unseen, full_order=True, stress_every=4).frame
    for location in ("groove", "bore"):
        error = (rom[f"{location}_temperature"] - fem[f"{location}_temperature"]).abs().max()
        assert error < 0.3, (location, error)
    sampled = fem["groove_axial"].notna()
    for column in ("groove_axial", "groove_hoop", "groove_von_mises", "groove_equivalent"):
        reference = fem.loc[sampled, column]
        span = reference.max() - reference.min()
        assert span > 1e8  # a real thermal transient: hundreds of MPa at the groove root
        error = (rom.loc[sampled, column] - reference).abs().max()
        assert error <= 0.02 * span, (column, error / span)


def test_streamed_steps_equal_the_batch_run(model, unseen):
    batch = model.simulate_steam(unseen)
    state = model.initial_state(unseen)
    rows = [model.observe(state)]
    for _, row in unseen.iloc[1:].iterrows():
        state, observed = model.step(state, row, STEP_S)
        rows.append(observed)
    streamed = pd.DataFrame(rows, index=unseen.index)[batch.frame.columns]
    np.testing.assert_allclose(streamed.to_numpy(), batch.frame.to_numpy(), rtol=1e-12,
                               atol=1e-6)
    np.testing.assert_array_equal(state.rom.coordinates, batch.state.rom.coordinates)


def test_a_run_split_in_two_with_a_saved_state_equals_one_run(model, unseen):
    whole = model.simulate_steam(unseen)
    half = len(unseen) // 2
    first = model.simulate_steam(unseen.iloc[:half + 1])
    restored = RotorState.from_dict(json.loads(json.dumps(first.state.to_dict())))
    second = model.simulate_steam(unseen.iloc[half:], state=restored)
    pd.testing.assert_frame_equal(second.frame, whole.frame.iloc[half:], rtol=1e-12)


def test_save_load_round_trip_is_exact(model, unseen, spec, tmp_path):
    path = model.save(tmp_path / "rotor.npz")
    loaded = RotorModel.load(path, spec)
    pd.testing.assert_frame_equal(loaded.simulate_steam(unseen).frame,
                                  model.simulate_steam(unseen).frame, check_exact=True)
    assert loaded.critical_points == model.critical_points
    assert loaded.fingerprint == model.fingerprint  # states carry over a save/load


def test_the_groove_equivalent_range_is_the_asme_range_and_cooling_is_tensile(model, unseen):
    # ASME VIII-2 §5.5.3.2: von Mises of the component differences between the two instants
    frame = model.simulate_steam(unseen).frame
    equivalent = frame["groove_equivalent"].to_numpy()
    high, low = int(np.argmax(equivalent)), int(np.argmin(equivalent))
    components = frame[[f"groove_{name}" for name in COMPONENTS]].to_numpy()
    difference = StressState.from_components(components[high] - components[low])
    assert equivalent[high] - equivalent[low] == pytest.approx(float(difference.von_mises),
                                                               rel=5e-3)
    # the surface is hottest relative to the core on the way up (compressive), coolest on the
    # way down (tensile): the cooling ramp holds the maximum, the heating ramp the minimum
    assert high < len(unseen) // 2 < low


def test_unfitted_model_and_bad_steam_frames_are_refused(model, spec, unseen):
    with pytest.raises(RotorAreaError, match="not fitted"):
        RotorModel(spec).simulate_steam(unseen)
    with pytest.raises(RotorAreaError, match="lacks the columns"):
        model.simulate_steam(unseen.drop(columns=unseen.columns[0]))
    uneven = unseen.iloc[[0, 1, 3]]
    with pytest.raises(RotorAreaError, match=r"equally spaced.*row 2"):
        model.simulate_steam(uneven)
