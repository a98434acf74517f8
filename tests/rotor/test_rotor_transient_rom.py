"""The rotor conduction ROM (POD–Galerkin) against its full-order implicit-Euler runs on a small
axisymmetric section (tests/rotor/rotor_section.py): exactness without truncation, error on
ramps it was not trained on, streaming = batch, invariants, properties, file round trip."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from rotor_section import (
    BORE,
    RIM,
    Section,
    ramp,
    random_walk,
    steam_history,
    surface_stress_operator,
)

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.implicit_euler import SteamHistory, bracket
from steamtwin.rotor.transient_rom import ConductionRom, RomState, full_order_run

DT = 30.0
OPERATING_K = 780.0
REFERENCES = (700.0, 760.0, 820.0)
CENTRIFUGAL_PA = 1.0e8


@pytest.fixture(scope="module")
def section() -> Section:
    return Section()


@pytest.fixture(scope="module")
def critical(section: Section) -> list[int]:
    return [section.node(RIM, 0.05), section.node(RIM, 0.15), section.node(BORE, 0.15),
            section.node(0.2, 0.05)]


@pytest.fixture(scope="module")
def stress(section: Section, critical: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """S, s₀: the surface thermal stress at the two rim nodes plus a centrifugal offset."""
    return surface_stress_operator(section, critical[:2]), np.full(2, CENTRIFUGAL_PA)


@pytest.fixture(scope="module")
def training() -> list[SteamHistory]:
    return [steam_history(ramp(rate, DT), DT) for rate in (2.0, 8.0)]


@pytest.fixture(scope="module")
def rom(section, training, critical, stress) -> ConductionRom:
    return ConductionRom().fit(section.operators(OPERATING_K), training,
                               temperature_nodes=critical, output_operator=stress[0],
                               output_offset=stress[1])


@pytest.mark.parametrize("references", [(OPERATING_K,), REFERENCES[::2]])
def test_rom_without_truncation_reproduces_the_full_order_run(section, training, critical,
                                                              stress, references):
    operators = [section.operators(t) for t in references]
    kwargs = {"reference_temperatures": references} if len(references) > 1 else {}
    # E/(1 − ν) falls with temperature: one stress operator per reference, interpolated too
    factors = np.linspace(1.0, 0.9, len(references))[:, None, None]
    full = ConductionRom(energy=1.0).fit(operators, training[:1], temperature_nodes=critical,
                                         output_operator=factors * stress[0],
                                         output_offset=factors[:, :, 0] * stress[1], **kwargs)
    fom = full_order_run(operators, training[0], **kwargs)
    run = full.simulate(training[0])
    np.testing.assert_allclose(run.temperature, fom[1:, critical], rtol=0, atol=1e-8)
    capacity = operators[0].mass @ np.ones(operators[0].size)
    mean = fom[1:] @ capacity / capacity.sum()
    theta = np.clip((mean - references[0]) / (references[-1] - references[0] + 1e-300), 0, 1)
    stress_k = factors[:, None, :, 0] * (fom[1:] @ stress[0].T + stress[1])  # (refs, t, out)
    expected = (1 - theta[:, None]) * stress_k[0] + theta[:, None] * stress_k[-1]
    assert 0 < theta.min() < theta.max() < 1 or len(references) == 1
    np.testing.assert_allclose(run.output, expected, rtol=1e-12, atol=1e-3)  # Pa, of ~1e8
    np.testing.assert_allclose(full.field(run.final), fom[-1], rtol=0, atol=1e-8)


def test_snapshots_from_another_solver_alone_make_a_rom(section, training, critical):
    operators = section.operators(OPERATING_K)
    fom = full_order_run(operators, training[1])
    external = ConductionRom(energy=1.0).fit(operators, [], snapshots=[fom.T],
                                             temperature_nodes=critical)
    assert np.isnan(external.training_error_)
    run = external.simulate(training[1], external.state_from_field(fom[0]))
    np.testing.assert_allclose(run.temperature, fom[1:, critical], rtol=0, atol=1e-8)
    with pytest.raises(RotorAreaError, match=r"snapshots\[0\] has shape \(3, 99\)"):
        ConductionRom().fit(operators, [], snapshots=[np.ones((3, 99))])


@pytest.mark.parametrize("load", [ramp(5.0, DT), random_walk(240, random_state=3)],
                         ids=["5 %/min ramp", "random walk"])
def test_unseen_loads_within_a_hundredth_of_the_one_kelvin_target(rom, section, critical,
                                                                   stress, load):
    history = steam_history(load, DT)
    fom = full_order_run(section.operators(OPERATING_K), history)
    run = rom.simulate(history)
    assert rom.n_modes_ <= 20 < section.basis.N // 4
    assert np.abs(run.temperature - fom[1:, critical]).max() < 0.05  # K; target 1 K
    reference = fom[1:] @ stress[0].T + stress[1]
    stress_range = np.ptp(reference, axis=0)
    assert np.all(stress_range > 1e6)  # the loads do swing the stress
    assert np.all(np.abs(run.output - reference).max(axis=0) < 0.005 * stress_range)


def test_streaming_steps_with_a_saved_state_equal_the_batch_run(rom):
    history = steam_history(ramp(5.0, DT), DT)
    batch = rom.simulate(history)
    state = rom.initial_state(history.htc[0], history.steam_temperature[0])
    temperature, output = [], []
    for k in range(history.steps):
        state = rom.step(state, history.htc[k], history.steam_temperature[k], DT)
        if k == history.steps // 3:
            state = RomState.from_dict(json.loads(json.dumps(state.to_dict())))
        observed = rom.observe(state)
        temperature.append(observed[0])
        output.append(observed[1])
    np.testing.assert_array_equal(state.coordinates, batch.final.coordinates)
    np.testing.assert_array_equal(np.array(temperature), batch.temperature)
    np.testing.assert_array_equal(np.array(output), batch.output)
    assert state.time_s == batch.final.time_s == pytest.approx(history.steps * DT)


def test_a_step_takes_strided_rows_of_a_frame_like_contiguous_ones(rom):
    history = steam_history(ramp(5.0, DT), DT)
    g = history.htc.shape[1]
    # DataFrame.to_numpy() of float columns is column-major: its rows are strided views
    table = np.asfortranarray(np.hstack([history.htc, history.steam_temperature]))
    state = rom.initial_state(history.htc[0], history.steam_temperature[0])
    strided_state = RomState(np.asfortranarray(np.vstack([state.coordinates] * 2))[0])
    assert not table[1, :g].flags.c_contiguous
    assert not strided_state.coordinates.flags.c_contiguous
    expected = rom.step(state, history.htc[1], history.steam_temperature[1], DT)
    stepped = rom.step(strided_state, table[1, :g], table[1, g:], DT)
    np.testing.assert_array_equal(stepped.coordinates, expected.coordinates)
    np.testing.assert_array_equal(rom.observe(strided_state)[1], rom.observe(state)[1])


def test_a_truncated_rom_keeps_the_energy_balance_and_uniform_equilibrium(section, training):
    operators = section.operators(OPERATING_K)
    coarse = ConductionRom(max_modes=3).fit(operators, training[1:])
    assert coarse.n_modes_ == 3
    history = steam_history(ramp(5.0, DT), DT)
    state = coarse.initial_state(history.htc[0], history.steam_temperature[0])
    capacity = operators.mass @ np.ones(operators.size)
    areas = np.array([b.sum() for b in operators.robin_load])
    for htc, steam in zip(history.htc[:40], history.steam_temperature[:40], strict=True):
        before = coarse.field(state)
        state = coarse.step(state, htc, steam, DT)
        after = coarse.field(state)
        stored = capacity @ (after - before) / DT  # W
        convected = sum(h * (t * a - np.ones(operators.size) @ (matrix @ after))
                        for h, t, a, matrix in zip(htc, steam, areas, operators.robin,
                                                   strict=True))
        assert stored == pytest.approx(convected, rel=1e-8, abs=1e-6 * abs(stored) + 1e-6)
    uniform = coarse.state_from_field(np.full(operators.size, 750.0))
    for _ in range(5):
        uniform = coarse.step(uniform, history.htc[20], [750.0] * 3, DT)
    np.testing.assert_allclose(coarse.field(uniform), 750.0, rtol=0, atol=1e-9)


def test_properties_interpolated_in_the_mean_temperature_track_local_properties(
        section, training, critical):
    operators = [section.operators(t) for t in REFERENCES]
    tracking = ConductionRom().fit(operators, training, reference_temperatures=REFERENCES,
                                   temperature_nodes=critical)
    cold = ConductionRom().fit(section.operators(REFERENCES[0]), training,
                               temperature_nodes=critical)
    history = steam_history(ramp(5.0, DT), DT)
    start = full_order_run(operators, history, reference_temperatures=REFERENCES)[0]
    local = section.local_property_run(history, start)[1:, critical]
    error = np.abs(tracking.simulate(history, tracking.state_from_field(start)).temperature
                   - local).max()
    frozen_error = np.abs(cold.simulate(history, cold.state_from_field(start)).temperature
                          - local).max()
    assert tracking.training_error_ < 0.05  # K, against the interpolated full order
    assert error < 0.3  # K: 0.12 measured (the spread of k(T), c(T) across the section)
    assert frozen_error > 5 * error  # 1.7 K with the properties frozen at 700 K


def test_error_based_truncation_keeps_the_fewest_modes_within_the_tolerance(section, training,
                                                                             critical, rom):
    operators = section.operators(OPERATING_K)
    reports = []
    tight = ConductionRom(tolerance=0.05).fit(operators, training, temperature_nodes=critical,
                                              progress=lambda f, m: reports.append((f, m)))
    assert tight.training_error_ <= 0.05
    fractions = [fraction for fraction, _ in reports]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    assert f"{tight.n_modes_} modes" in reports[-1][1]
    assert tight.n_modes_ < rom.n_modes_  # the energy criterion alone keeps more
    fewer = ConductionRom(max_modes=tight.n_modes_ - 1).fit(operators, training,
                                                            temperature_nodes=critical)
    assert fewer.training_error_ > 0.05


@given(st.lists(st.floats(200.0, 1200.0), min_size=1, max_size=5, unique=True),
       st.floats(0.0, 1500.0), st.floats(-1e3, 1e3), st.floats(-10.0, 10.0))
def test_bracket_interpolates_linear_properties_exactly_and_clamps(references, mean, a, b):
    references = np.sort(references)
    i, j, theta = bracket(mean, references)
    assert 0.0 <= theta <= 1.0 and j in (i, i + 1)
    value = (1 - theta) * (a + b * references[i]) + theta * (a + b * references[j])
    clamped = np.clip(mean, references[0], references[-1])
    assert value == pytest.approx(a + b * clamped, rel=1e-9, abs=1e-9 * (abs(a) + 1e4))


@given(arrays(float, st.integers(1, 40), elements=st.floats(allow_nan=False)),
       st.floats(0.0, 1e9))
def test_a_state_survives_json_bit_for_bit(coordinates, time_s):
    state = RomState(coordinates, time_s)
    restored = RomState.from_dict(json.loads(json.dumps(state.to_dict())))
    np.testing.assert_array_equal(restored.coordinates, coordinates)
    assert restored.time_s == time_s


def test_a_saved_rom_loads_and_runs_identically(rom, tmp_path):
    path = rom.save(tmp_path / "rotor_rom.npz")
    loaded = ConductionRom.load(path)
    history = steam_history(random_walk(60, random_state=5), DT)
    expected, got = rom.simulate(history), loaded.simulate(history)
    np.testing.assert_array_equal(got.temperature, expected.temperature)
    np.testing.assert_array_equal(got.output, expected.output)
    assert loaded.groups_ == rom.groups_ and loaded.n_modes_ == rom.n_modes_
    with np.load(path, allow_pickle=False) as archive:
        arrays = {name: archive[name] for name in archive.files if name != "reduced_load"}
    broken = tmp_path / "broken.npz"
    np.savez(broken, **arrays)
    with pytest.raises(RotorAreaError, match=r"broken\.npz.*not a rotor conduction ROM"):
        ConductionRom.load(broken)


def test_bad_input_is_refused_with_a_clear_message(rom, section, training):
    with pytest.raises(RotorAreaError, match=r"htc must be finite and ≥ 0.*row 1"):
        SteamHistory([[1.0, 1.0, 1.0], [1.0, -2.0, 1.0]], np.full((2, 3), 700.0), DT)
    with pytest.raises(RotorAreaError, match="kelvin, not °C"):
        SteamHistory(np.ones((1, 3)), [[500.0, -20.0, 500.0]], DT)
    with pytest.raises(RotorAreaError, match="2 boundary groups given, the ROM has 3"):
        rom.simulate(SteamHistory(np.ones((4, 2)), np.full((4, 2), 700.0), DT))
    with pytest.raises(RotorAreaError, match="not fitted"):
        ConductionRom().step(RomState(np.zeros(3)), [1.0] * 3, [700.0] * 3, DT)
    with pytest.raises(RotorAreaError, match="state has"):
        rom.step(RomState(np.zeros(2)), [1.0] * 3, [700.0] * 3, DT)
    with pytest.raises(RotorAreaError, match="temperature_nodes must be node indices"):
        ConductionRom().fit(section.operators(OPERATING_K), training, temperature_nodes=[10**6])
    with pytest.raises(RotorAreaError, match="output_operator has shape"):
        ConductionRom().fit(section.operators(OPERATING_K), training,
                            output_operator=np.ones((2, 5)))
    with pytest.raises(RotorAreaError, match=r"one per reference temperature"):
        ConductionRom().fit(section.operators(OPERATING_K), training,
                            output_operator=np.ones((2, 3, section.basis.N)))
    with pytest.raises(RotorAreaError, match="strictly ascending"):
        ConductionRom().fit([section.operators(t) for t in REFERENCES[:2]], training,
                            reference_temperatures=REFERENCES[1::-1])
