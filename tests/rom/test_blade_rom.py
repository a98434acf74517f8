"""The ROM of the control-stage blade: snapshots, fit, errors, file, series, VTU."""

from __future__ import annotations

import warnings

import meshio
import numpy as np
import pandas as pd
import pytest

from steamtwin.rom.estimator import ExtrapolationWarning, PodRbfRom
from steamtwin.rom.reconstruction import (
    DISTANCE,
    FLAG_EXTRAPOLATED,
    FLAG_INVALID,
    FLAG_OUT_OF_DOMAIN,
    predict_field,
    predict_series,
    write_vtu,
)
from steamtwin.rom.romfile import (
    BladeRom,
    RomFileError,
    load_rom,
    probe_nodes,
    save_rom,
)
from steamtwin.rom.snapshots import ROM_INPUTS, design_conditions, generate_snapshots
from steamtwin.rom.validation import leave_one_out, rom_errors


@pytest.fixture(scope="module")
def bundle(blade_snapshots) -> BladeRom:
    s = blade_snapshots
    rom = PodRbfRom(energy=0.99999).fit(s.fields, s.rom_inputs(), ROM_INPUTS,
                                        sensors=s.sensors.to_numpy(),
                                        sensor_names=tuple(s.sensors.columns))
    return BladeRom(rom=rom, mesh=s.mesh, probes=probe_nodes(s.mesh), conditions=s.conditions,
                    provenance={"test": True})


def test_design_covers_the_load_levels(reference_spec):
    design = design_conditions(reference_spec, 32)
    assert len(design) == 32
    assert sorted(design["load_level"].unique()) == [0.3, 0.5, 0.75, 1.0]
    for _, level in design.groupby("load_level"):
        assert len(level) == 8
        for name in ("main_steam_pressure", "main_steam_temperature", "main_steam_flow"):
            assert level[name].nunique() == 8  # a Latin hypercube: distinct values per input
    assert design["main_steam_flow"].max() <= reference_spec.design.main_steam_flow * 1.01
    corners = design_conditions(reference_spec, 32, layout="corners")
    assert corners.groupby("load_level")["main_steam_temperature"].nunique().max() == 2
    bands = design_conditions(reference_spec, 32, layout="bands")
    for level, group in bands.groupby("load_level"):
        assert len(group) == 8
        # each band reaches halfway to the neighbouring levels, no further
        assert group["load_fraction"].between(level - 0.125 - 1e-12, level + 0.125 + 1e-12).all()
    assert bands["load_fraction"].min() >= 0.2 and bands["load_fraction"].max() <= 1.01
    with pytest.raises(ValueError, match="layout"):
        design_conditions(reference_spec, 32, layout="grid")


def test_snapshots_carry_conditions_sensors_and_balanced_fields(blade_snapshots,
                                                                 reference_spec):
    s = blade_snapshots
    assert s.fields.shape == (16, s.mesh.points.shape[0])
    assert {"control_stage_pressure", "active_admission_arc"} <= set(s.conditions.columns)
    assert "control_stage_temperature" in s.sensors.columns
    # sensor temperatures and field are physically ordered: blade below main steam, above
    # nothing colder than the wheel chamber minus a few K
    assert np.all(s.fields.max(axis=1) < s.conditions["main_steam_temperature"].to_numpy())
    assert np.all(s.fields.min(axis=1) > s.sensors["control_stage_temperature"].to_numpy() - 5)


def test_parallel_and_serial_snapshots_agree(reference_spec, coarse_blade, blade_snapshots):
    conditions = blade_snapshots.conditions.iloc[:2]
    parallel = generate_snapshots(reference_spec, coarse_blade, conditions, max_workers=2)
    np.testing.assert_allclose(parallel.fields, blade_snapshots.fields[:2], atol=1e-6)


def test_rom_errors_on_held_out_and_leave_one_out(bundle, blade_snapshots, held_out_snapshots):
    rom = bundle.rom
    report = rom_errors(rom, held_out_snapshots.fields, held_out_snapshots.rom_inputs())
    summary = report.summary()
    # 16 coarse snapshots: a few kelvin at worst, and the split is consistent
    assert summary["max_total"] < 4.0
    table = report.table
    assert np.all(table["total"] <= table["projection"] + table["interpolation"] + 1e-9)
    loo = leave_one_out(rom, blade_snapshots.fields, blade_snapshots.rom_inputs()).table
    assert len(loo) == 16 and loo["total"].max() < 10.0


def test_rom_file_round_trip(bundle, tmp_path, held_out_snapshots):
    path = save_rom(bundle, tmp_path / "rom.npz")
    loaded = load_rom(path)
    conditions = held_out_snapshots.rom_inputs()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        np.testing.assert_allclose(loaded.rom.predict(conditions), bundle.rom.predict(conditions),
                                   rtol=0, atol=1e-9)
    assert loaded.probes == bundle.probes
    assert loaded.provenance == {"test": True}
    assert loaded.sensor_names == bundle.sensor_names
    np.testing.assert_array_equal(loaded.mesh.tetrahedra, bundle.mesh.tetrahedra)


def test_state_round_trip_lists_the_file(bundle, held_out_snapshots, tmp_path):
    """get_state → from_state rebuilds the same predictor (issue 20, item 5), and the ROM
    file holds exactly that state beside the mesh, probes and provenance."""
    from steamtwin.rom.estimator import PodRbfRom

    state = bundle.rom.get_state()
    assert all(isinstance(value, np.ndarray) and value.dtype != object
               for value in state.values())
    rebuilt = PodRbfRom.from_state(state)
    conditions = held_out_snapshots.rom_inputs()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        np.testing.assert_array_equal(rebuilt.predict(conditions),
                                      bundle.rom.predict(conditions))
    with np.load(save_rom(bundle, tmp_path / "rom.npz"), allow_pickle=False) as archive:
        for name, value in state.items():
            np.testing.assert_array_equal(archive[name], value)


def _rewrite(path, target, **changes):
    with np.load(path, allow_pickle=False) as archive:
        arrays = {name: archive[name] for name in archive.files}
    arrays.update(changes)
    np.savez(target, **arrays)
    return target


def test_corrupt_and_mismatched_files_are_refused(bundle, tmp_path):
    path = save_rom(bundle, tmp_path / "rom.npz")
    truncated = tmp_path / "truncated.npz"
    truncated.write_bytes(path.read_bytes()[:5000])
    with pytest.raises(RomFileError, match="not a readable ROM file"):
        load_rom(truncated)
    with pytest.raises(RomFileError, match="version"):
        load_rom(_rewrite(path, tmp_path / "v9.npz", format_version=np.array(9)))
    with pytest.raises(RomFileError, match="shape"):
        load_rom(_rewrite(path, tmp_path / "mean.npz", mean=bundle.rom.mean_[:-1]))
    with pytest.raises(RomFileError, match="missing array 'modes'"):
        with np.load(path) as archive:
            arrays = {k: archive[k] for k in archive.files if k != "modes"}
        np.savez(tmp_path / "nomodes.npz", **arrays)
        load_rom(tmp_path / "nomodes.npz")
    with pytest.raises(RomFileError, match="orthonormal"):
        load_rom(_rewrite(path, tmp_path / "modes.npz", modes=2.0 * bundle.rom.modes_))
    with pytest.raises(RomFileError, match="NaN"):
        nan_mean = bundle.rom.mean_.copy()
        nan_mean[3] = np.nan
        load_rom(_rewrite(path, tmp_path / "nan.npz", mean=nan_mean))
    objects = _rewrite(path, tmp_path / "pickled.npz",
                       provenance=np.array([{"evil": 1}], dtype=object))
    with pytest.raises(RomFileError):
        load_rom(objects)  # object arrays need pickle: refused, never unpickled
    with pytest.raises(RomFileError, match="steamtwin ROM"):
        np.savez(tmp_path / "other.npz", a=np.zeros(3))
        load_rom(tmp_path / "other.npz")


def test_series_prediction_flags_and_matches_fields(bundle, blade_snapshots):
    rom = bundle.rom
    conditions = blade_snapshots.conditions
    index = pd.date_range("2026-01-01", periods=5, freq="1s", tz="UTC")
    signals = pd.DataFrame({name: conditions[name].to_numpy()[:5] for name in ROM_INPUTS},
                           index=index)
    signals.iloc[2, 0] = np.nan
    t_span = conditions["main_steam_temperature"].max() - conditions["main_steam_temperature"].min()
    signals.iloc[4, 1] = conditions["main_steam_temperature"].max() + 0.5 * t_span
    with pytest.warns(ExtrapolationWarning, match="1 of 5 samples"):
        result = predict_series(bundle, signals, fields_every=2)
    table = result.sensors
    assert table[FLAG_INVALID].tolist() == [False, False, True, False, False]
    assert table[FLAG_EXTRAPOLATED].tolist() == [False, False, False, False, True]
    assert not table[FLAG_OUT_OF_DOMAIN].any()
    assert table.iloc[2].drop([FLAG_INVALID, FLAG_OUT_OF_DOMAIN, FLAG_EXTRAPOLATED]).isna().all()
    # at the snapshots the ROM reproduces the stored sensors and the field's probe nodes
    for row in (0, 1, 3):
        field = blade_snapshots.fields[row]
        for name, node in bundle.probes.items():
            assert table[name].iloc[row] == pytest.approx(
                rom.mean_[node] + rom.project(field)[0] @ rom.modes_[:, node], abs=1e-6)
        assert table["control_stage_temperature"].iloc[row] == pytest.approx(
            blade_snapshots.sensors["control_stage_temperature"].iloc[row], abs=1e-6)
    assert sorted(result.fields) == [0, 3]  # every 2nd valid sample
    expected = predict_field(bundle, {n: signals[n].iloc[3] for n in ROM_INPUTS})
    np.testing.assert_allclose(result.fields[3], expected, atol=1e-9)
    with pytest.raises(ValueError, match="lack the ROM input"):
        predict_series(bundle, signals.drop(columns=["control_stage_pressure"]))


def test_series_prediction_refuses_inputs_outside_the_physical_domain(bundle, blade_snapshots):
    """Issue 16, finding 3: wet main steam and a tenfold pressure gave -101 MW and 1862 MW."""
    conditions = blade_snapshots.conditions
    index = pd.date_range("2026-01-01", periods=5, freq="1s", tz="UTC")
    signals = pd.DataFrame({name: conditions[name].to_numpy()[:5] for name in ROM_INPUTS},
                           index=index)
    signals.loc[index[1], "main_steam_temperature"] = 281.0 + 273.15  # wet at 16.7 MPa
    signals.loc[index[1], "main_steam_pressure"] = 16.7e6
    signals.loc[index[2], "main_steam_pressure"] *= 10.0  # bar read as MPa
    signals.loc[index[3], "control_stage_pressure"] = signals["main_steam_pressure"].iloc[3]
    t_span = conditions["main_steam_temperature"].max() - conditions["main_steam_temperature"].min()
    signals.loc[index[4], "main_steam_temperature"] = (conditions["main_steam_temperature"].max()
                                                       + 1.5 * t_span)
    table = predict_series(bundle, signals).sensors
    assert table[FLAG_OUT_OF_DOMAIN].tolist() == [False, True, True, True, True]
    assert table[FLAG_INVALID].tolist() == [False, True, True, True, True]
    assert not table[FLAG_EXTRAPOLATED].iloc[1:].any()
    predicted = table.drop(columns=[FLAG_INVALID, FLAG_OUT_OF_DOMAIN, FLAG_EXTRAPOLATED, DISTANCE])
    assert predicted.iloc[1:].isna().all().all() and predicted.iloc[0].notna().all()
    # the same farthest sample is predicted when the caller widens the limit on purpose
    with pytest.warns(ExtrapolationWarning):
        wide = predict_series(bundle, signals, max_extrapolation=2.0).sensors
    assert not wide[FLAG_INVALID].iloc[4] and wide[FLAG_EXTRAPOLATED].iloc[4]
    with pytest.raises(ValueError, match="max_extrapolation"):
        predict_series(bundle, signals, max_extrapolation=-1.0)


def test_vtu_output_reads_back(bundle, tmp_path):
    field = bundle.rom.mean_
    path = write_vtu(bundle.mesh, {"temperature_K": field}, tmp_path / "field.vtu")
    mesh = meshio.read(path)
    np.testing.assert_allclose(mesh.point_data["temperature_K"], field)
    assert mesh.cells_dict["tetra"].shape == bundle.mesh.tetrahedra.shape
    with pytest.raises(ValueError, match="shape"):
        write_vtu(bundle.mesh, {"bad": field[:-1]}, tmp_path / "bad.vtu")


def test_figure_is_written(bundle, held_out_snapshots, tmp_path):
    from steamtwin.rom.figure import field_comparison_figure

    fom = held_out_snapshots.fields[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        rom = bundle.rom.predict(held_out_snapshots.rom_inputs()[0])
    path = field_comparison_figure(bundle.mesh, fom, rom, tmp_path / "fig9.png", "test")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="shape"):
        field_comparison_figure(bundle.mesh, fom[:-1], rom, tmp_path / "bad.png")


def test_dmd_comparison_on_a_short_ramp(reference_spec, coarse_blade, bundle):
    from steamtwin.rom.dmd import compare_rom_and_dmd, ramp_transient

    transient = ramp_transient(reference_spec, coarse_blade, start_load=0.75, end_load=0.6,
                               rate=0.05, hold_s=120.0, step_s=20.0)
    assert set(transient.phase) == {"ramp", "hold"}
    # the blade (a few mm of steel, h ~ 1e4) follows its steam within seconds: at the end of
    # the second hold the transient field equals the steady one
    from steamtwin.model.parameters import ModelParameters
    from steamtwin.rom.snapshots import BladeFieldSolver, SnapshotContext

    solver = BladeFieldSolver(SnapshotContext(reference_spec, bundle.mesh, ModelParameters()))
    last = transient.conditions.iloc[-1].to_dict()
    steady, _, _ = solver.solve(last)
    assert np.abs(transient.fields[-1] - steady).max() < 0.05
    assert np.abs(transient.fields[-1] - transient.fields[0]).max() > 1.0  # it did move
    report = compare_rom_and_dmd(transient, bundle.rom)
    summary = report.summary
    assert list(summary.index) == ["ramp", "hold"]
    assert summary["pod_rbf_max_abs"].max() < 5.0
    assert np.all(np.isfinite(report.samples[["pod_rbf_abs", "dmd_abs"]].to_numpy()))


def test_dask_scheduler_gives_the_same_snapshots(reference_spec, coarse_blade, blade_snapshots):
    from distributed import LocalCluster

    conditions = blade_snapshots.conditions.iloc[:2]
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=None) as cluster:
        done = []
        result = generate_snapshots(
            reference_spec, coarse_blade, conditions, scheduler=cluster.scheduler_address,
            progress=lambda fraction, message: done.append((fraction, message)))
    np.testing.assert_allclose(result.fields, blade_snapshots.fields[:2], atol=1e-6)
    assert done == [(0.5, "snapshot 1/2"), (1.0, "snapshot 2/2")]
