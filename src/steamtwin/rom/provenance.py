"""Which turbine and which parameters a ROM was built from, and the checks that use it.

``rom build`` records in the ROM file the spec (``provenance["spec"]``: name, SHA-256 of its
canonical form, :mod:`steamtwin.spec.fingerprint`; the TOML text itself in the file's
``spec_toml`` array) and the model parameters (``provenance["model_parameters"]``, with
``provenance["parameters_source"]``: the parameter file's path and SHA-256, or the empirical
defaults). ``validate`` and ``rom predict`` use the ROM's own spec unless given one
(:func:`resolve_spec`) and refuse a spec or parameter file that differs from what the ROM was
built from (:class:`ProvenanceError`), naming both and saying how to go on.

ROM files of format 2 (before these records) still load; they record no spec, so a command
that needs one asks for ``--turbine`` and says that it cannot be checked (rebuild to get the
check).
"""

from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path
from typing import Any

from steamtwin.errors import RomError
from steamtwin.model.parameters import ModelParameters
from steamtwin.rom.romfile import BladeRom
from steamtwin.spec import SpecError, TurbineSpec, parse_spec
from steamtwin.spec.fingerprint import builtin_spec_text, short_hash, spec_hash

__all__ = ["ProvenanceError", "check_parameters", "parameters_source", "resolve_spec",
           "rom_parameters", "spec_provenance"]


class ProvenanceError(RomError):
    """A spec or parameter file differs from the one the ROM was built from, or the ROM does
    not record what a command needs."""


def spec_provenance(spec: TurbineSpec, toml_text: str | None) -> tuple[dict[str, str], str]:
    """The ROM's record of ``spec``: (``{"name", "sha256"}``, its TOML text).

    ``toml_text`` must describe ``spec`` (same hash; ValueError otherwise); None takes the
    built-in turbine's text when ``spec`` is one, else the ROM records no text ("").
    """
    digest = spec_hash(spec)
    if toml_text is None:
        toml_text = builtin_spec_text(spec) or ""
    elif spec_hash(parse_spec(toml_text, "the spec TOML given to build_rom")) != digest:
        raise ValueError(f"the spec TOML text given for {spec.name!r} describes another "
                         "turbine (its hash differs from the spec's)")
    return {"name": spec.name, "sha256": digest}, toml_text


def parameters_source(path: str | Path | None) -> dict[str, str]:
    """Where the parameters came from: the file's path and SHA-256, or the empirical defaults."""
    if path is None:
        return {"kind": "empirical defaults (no parameter file)"}
    content = Path(path).read_bytes()
    return {"kind": "parameter file", "path": str(path),
            "sha256": hashlib.sha256(content).hexdigest()}


def _label(name: str, digest: str) -> str:
    return f"{name!r} (sha256 {short_hash(digest)})"


def resolve_spec(bundle: BladeRom, given: TurbineSpec | None = None, given_as: str = "--turbine",
                 rom_path: str | Path = "the ROM") -> TurbineSpec:
    """The turbine to use with ``bundle``: its own spec, or ``given`` if it is the same.

    ``given_as`` (e.g. ``"--turbine fitted.toml"``) and ``rom_path`` name the two in messages.
    Raises :class:`ProvenanceError` when ``given`` differs from the ROM's spec (by hash), or
    when nothing is given and the ROM records no spec text.
    """
    record = bundle.provenance.get("spec")
    if not isinstance(record, dict) or "sha256" not in record:
        if given is None:
            raise ProvenanceError(
                f"{rom_path} records no turbine spec (a ROM file written before format 3); "
                f"give the turbine it was built from with --turbine, or rebuild it with "
                "'steamtwin rom build' so that it records its spec")
        return given
    if given is not None:
        digest = spec_hash(given)
        if digest != record["sha256"]:
            raise ProvenanceError(
                f"{given_as} is turbine {_label(given.name, digest)}, but {rom_path} was built "
                f"from turbine {_label(str(record.get('name')), record['sha256'])}; omit "
                "--turbine to use the ROM's own spec, or rebuild the ROM for this turbine "
                f"('steamtwin rom build --turbine ...')")
        return given
    if not bundle.spec_toml:
        raise ProvenanceError(
            f"{rom_path} records turbine {_label(str(record.get('name')), record['sha256'])} "
            "by hash but not its TOML text; give it with --turbine")
    try:
        own = parse_spec(bundle.spec_toml, f"{rom_path} (its recorded spec)")
    except SpecError as error:
        raise ProvenanceError(f"{error}; give the turbine with --turbine or rebuild the ROM"
                              ) from None
    if spec_hash(own) != record["sha256"]:
        raise ProvenanceError(
            f"{rom_path}: its recorded spec TOML no longer gives the recorded hash "
            f"{short_hash(record['sha256'])} (a spec format change, or a corrupt file); "
            "rebuild the ROM")
    return own


def rom_parameters(bundle: BladeRom) -> ModelParameters:
    """The model parameters the ROM was built with, from its provenance (strictly checked:
    a missing or misspelled coefficient is a ParameterError, never a default)."""
    values = bundle.provenance.get("model_parameters")
    if not isinstance(values, dict):
        raise ValueError("the ROM file records no model_parameters in its provenance; rebuild "
                         "it with 'steamtwin rom build' or monitor with the ROM alone")
    return ModelParameters.from_dict(values, "the ROM file's provenance.model_parameters")


def check_parameters(bundle: BladeRom, given: ModelParameters, given_as: str = "--params",
                     rom_path: str | Path = "the ROM") -> None:
    """Refuse ``given`` parameters that differ from those the ROM was built with.

    Raises :class:`ProvenanceError` naming each coefficient that differs, the ROM's source of
    parameters and how to go on; ValueError when the ROM records no parameters.
    """
    own = rom_parameters(bundle)
    differing = [f"{field.name} {getattr(given, field.name)!r} vs the ROM's "
                 f"{getattr(own, field.name)!r}" for field in dataclasses.fields(own)
                 if getattr(given, field.name) != getattr(own, field.name)]
    if differing:
        raise ProvenanceError(
            f"{given_as} differs from the parameters {rom_path} was built with "
            f"({'; '.join(differing)}; the ROM's came from {_source_text(bundle.provenance)}); "
            "omit --params to use the ROM's own, or rebuild the ROM with these parameters "
            "('steamtwin rom build --params ...')")


def _source_text(provenance: dict[str, Any]) -> str:
    source = provenance.get("parameters_source")
    if not isinstance(source, dict):
        return "an unrecorded source"
    if "path" in source:
        return f"{source['path']}, sha256 {short_hash(str(source.get('sha256', '')))}"
    return str(source.get("kind", "an unrecorded source"))
