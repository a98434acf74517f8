"""A ROM file records its turbine and parameters; validate / predict refuse another's."""

from __future__ import annotations

import dataclasses
import hashlib
import json

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from steamtwin.cli import validate as validate_cli
from steamtwin.cli.rom import rom_app
from steamtwin.geometry.meshing import blade_volume_mesh
from steamtwin.model.parameters import ModelParameters
from steamtwin.rom.build import build_rom
from steamtwin.rom.provenance import ProvenanceError, check_parameters, resolve_spec
from steamtwin.rom.romfile import FORMAT_VERSION, load_rom, save_rom
from steamtwin.spec import parse_spec
from steamtwin.spec.fingerprint import builtin_spec_text, short_hash, spec_hash

runner = CliRunner()
validate_app = typer.Typer()
validate_app.command()(validate_cli.validate)
PARAMS = ModelParameters(flow_coefficient=0.97, friction_coefficient=1.1,
                         heat_transfer_coefficient=0.9)


@pytest.fixture(scope="module")
def built(tmp_path_factory, reference_spec):
    folder = tmp_path_factory.mktemp("provenance")
    params_file = folder / "params.json"
    PARAMS.to_json(params_file)
    mesh = blade_volume_mesh(reference_spec, "hp1", element_size=0.01)
    bundle, _ = build_rom(reference_spec, mesh, PARAMS, n_snapshots=8, energy=0.9999,
                          max_workers=1, params_file=params_file)
    return save_rom(bundle, folder / "rom.npz"), params_file


def _other_spec_text(reference_spec) -> str:
    """The reference unit renamed and rated 10 MW higher: another turbine."""
    text = builtin_spec_text(reference_spec)
    assert 'name = "reference"' in text and 'generator_power = "600 MW"' in text
    return text.replace('name = "reference"', 'name = "unit-7"').replace(
        'generator_power = "600 MW"', 'generator_power = "610 MW"')


def test_round_trip_records_spec_and_parameters(built, reference_spec):
    path, params_file = built
    bundle = load_rom(path)
    with np.load(path, allow_pickle=False) as archive:
        assert int(archive["format_version"]) == FORMAT_VERSION == 3
    record = bundle.provenance["spec"]
    assert record == {"name": "reference", "sha256": spec_hash(reference_spec)}
    assert bundle.spec_toml == builtin_spec_text(reference_spec)
    assert spec_hash(parse_spec(bundle.spec_toml)) == record["sha256"]  # stable over re-loading
    assert bundle.provenance["model_parameters"] == dataclasses.asdict(PARAMS)
    source = bundle.provenance["parameters_source"]
    assert source["path"] == str(params_file)
    assert source["sha256"] == hashlib.sha256(params_file.read_bytes()).hexdigest()
    again = save_rom(bundle, path.with_name("again.npz"))
    assert load_rom(again).provenance == bundle.provenance
    assert resolve_spec(load_rom(again)) == reference_spec


def test_own_spec_is_used_and_another_is_refused(built, reference_spec, tmp_path):
    bundle = load_rom(built[0])
    other_text = _other_spec_text(reference_spec)
    other = parse_spec(other_text)
    moved = dataclasses.replace(bundle, spec_toml=other_text, provenance={
        **bundle.provenance, "spec": {"name": other.name, "sha256": spec_hash(other)}})
    assert resolve_spec(moved) == other
    assert resolve_spec(moved, other) == other
    with pytest.raises(ProvenanceError) as refused:
        resolve_spec(moved, reference_spec, "--turbine reference", "rom.npz")
    message = str(refused.value)
    for text in ("'reference'", short_hash(spec_hash(reference_spec)), "'unit-7'",
                 short_hash(spec_hash(other)), "omit --turbine", "rebuild"):
        assert text in message


def test_format_2_files_still_load_and_ask_for_the_turbine(built, reference_spec, tmp_path):
    with np.load(built[0], allow_pickle=False) as archive:
        arrays = {name: archive[name] for name in archive.files if name != "spec_toml"}
    provenance = json.loads(str(arrays["provenance"]))
    del provenance["spec"], provenance["parameters_source"]
    arrays |= {"format_version": np.array(2, dtype=np.int64),
               "provenance": np.array(json.dumps(provenance))}
    np.savez_compressed(tmp_path / "v2.npz", **arrays)
    old = load_rom(tmp_path / "v2.npz")
    assert old.spec_toml == "" and "spec" not in old.provenance
    with pytest.raises(ProvenanceError, match=r"records no turbine spec.*--turbine.*rebuild"):
        resolve_spec(old)
    assert resolve_spec(old, reference_spec) == reference_spec


def test_parameters_that_differ_are_refused(built):
    bundle = load_rom(built[0])
    check_parameters(bundle, PARAMS)
    with pytest.raises(ProvenanceError) as refused:
        check_parameters(bundle, dataclasses.replace(PARAMS, flow_coefficient=0.953),
                         "--params p.json", "rom.npz")
    message = str(refused.value)
    assert "flow_coefficient 0.953 vs the ROM's 0.97" in message
    assert "friction" not in message and "params.json" in message and "omit --params" in message


def test_cli_refuses_another_turbine_and_parameters_with_exit_2(built, reference_spec,
                                                                 tmp_path):
    path, params_file = built
    other = tmp_path / "unit-7.toml"
    other.write_text(_other_spec_text(reference_spec), encoding="utf-8")
    other_params = tmp_path / "other.json"
    dataclasses.replace(PARAMS, heat_transfer_coefficient=1.0).to_json(other_params)
    dummy = tmp_path / "data.csv"
    dummy.write_text("time,x\n", encoding="utf-8")
    common = ["--data", str(dummy), "--tags", str(dummy)]
    for app, argv in (
            (validate_app, ["--rom", str(path), *common, "--report", str(tmp_path / "r")]),
            (rom_app, ["predict", "--rom", str(path), *common, "--out",
                       str(tmp_path / "p.csv")])):
        result = runner.invoke(app, [*argv, "--turbine", str(other)])
        assert result.exit_code == 2, result.output
        assert "'unit-7'" in result.output and "'reference'" in result.output
        assert short_hash(spec_hash(reference_spec)) in result.output
        result = runner.invoke(app, [*argv, "--params", str(other_params)])
        assert result.exit_code == 2, result.output
        assert "heat_transfer_coefficient 1.0 vs the ROM's 0.9" in result.output
        # the ROM's own spec and parameters pass the check (and the run fails later, on data)
        result = runner.invoke(app, [*argv, "--turbine", "reference", "--params",
                                     str(params_file)])
        assert "built from" not in result.output and "differs" not in result.output


def test_validate_uses_the_roms_own_spec_without_turbine(built, reference_spec, tmp_path,
                                                         monkeypatch):
    path, _ = built
    bundle = load_rom(path)
    other_text = _other_spec_text(reference_spec)
    other = parse_spec(other_text)
    moved = dataclasses.replace(bundle, spec_toml=other_text, provenance={
        **bundle.provenance, "spec": {"name": other.name, "sha256": spec_hash(other)}})
    moved_path = save_rom(moved, tmp_path / "unit7.npz")
    seen = {}

    def stop(*args, **kwargs):
        raise ValueError("stopped after the spec was chosen")

    monkeypatch.setattr(validate_cli, "load_tag_map", lambda tags: None)
    monkeypatch.setattr(validate_cli, "load_history", stop)
    original = validate_cli.resolve_spec

    def recording(*args, **kwargs):
        seen["spec"] = original(*args, **kwargs)
        return seen["spec"]

    monkeypatch.setattr(validate_cli, "resolve_spec", recording)
    result = runner.invoke(validate_app, ["--rom", str(moved_path), "--data", "x.csv",
                                          "--tags", "t.toml", "--report", str(tmp_path / "r")])
    assert result.exit_code == 2 and "stopped after the spec was chosen" in result.output
    assert seen["spec"] == other and seen["spec"].design.generator_power == 610e6
    info = runner.invoke(rom_app, ["info", str(moved_path)])
    assert f"'unit-7' (sha256 {short_hash(spec_hash(other))})" in info.output
    assert json.loads(info.output.split("provenance: ", 1)[1])["spec"]["name"] == "unit-7"
