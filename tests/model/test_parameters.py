"""Model parameters: bounds, JSON round trip, clear errors."""

from __future__ import annotations

import json

import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.calibration.calibrator import write_parameters
from steamtwin.calibration.online import ParameterStore
from steamtwin.model.parameters import PARAMETER_BOUNDS, ModelParameters, ParameterError


def test_defaults_are_the_empirical_constants():
    assert ModelParameters() == ModelParameters(1.0, 1.0, 1.0)


@pytest.mark.parametrize("name", list(PARAMETER_BOUNDS))
def test_out_of_bounds_is_refused(name):
    low, high = PARAMETER_BOUNDS[name]
    for value in (low * 0.99, high * 1.01):
        with pytest.raises(ParameterError, match=rf"{name} = .* outside its physical bounds"):
            ModelParameters(**{name: value})
    with pytest.raises(ParameterError, match=name):
        ModelParameters(**{name: float("nan")})


def _bounded(name):
    low, high = PARAMETER_BOUNDS[name]
    return st.floats(min_value=low, max_value=high, allow_nan=False)


@settings(max_examples=50, deadline=None)
@given(_bounded("flow_coefficient"), _bounded("friction_coefficient"),
       _bounded("heat_transfer_coefficient"))
def test_json_round_trip_is_exact(tmp_path_factory, flow, friction, heat):
    params = ModelParameters(flow, friction, heat)
    path = tmp_path_factory.mktemp("params") / "params.json"
    params.to_json(path)
    assert ModelParameters.from_json(path) == params


def test_files_the_package_writes_read_back(tmp_path):
    """Calibration's file (with its metadata) and the online store's file are valid input."""
    params = ModelParameters(0.97, 1.3, 1.6)
    history = pd.DataFrame({"best_rmse": [2.0, 1.5]})
    written, _ = write_parameters(tmp_path / "calibrated.json", params, 1.5,
                                  ["hp_exhaust_temperature"], 12,
                                  {"mode": "ga", "population": 6, "seed": 0}, history)
    assert set(json.loads(written.read_text())) == {"schema_version", "parameters", "bounds",
                                                    "calibration"}
    assert ModelParameters.from_json(written) == params
    store = ParameterStore(path=tmp_path / "live.json")
    store.swap(params)
    assert ModelParameters.from_json(tmp_path / "live.json") == params


def test_coefficients_may_sit_at_the_top_level(tmp_path):
    path = _write(tmp_path, {"flow_coefficient": 1, "friction_coefficient": 1.2,
                             "heat_transfer_coefficient": 0.8, "bounds": {}})
    assert ModelParameters.from_json(path) == ModelParameters(1.0, 1.2, 0.8)


def _write(folder, document, name="params.json"):
    path = folder / name
    path.write_text(document if isinstance(document, str) else json.dumps(document))
    return path


def _calibrated(**changes):
    """A calibration file's document with ``changes`` applied to its parameters."""
    parameters = {"flow_coefficient": 0.98, "friction_coefficient": 1.2,
                  "heat_transfer_coefficient": 1.4, **changes}
    return {"parameters": {k: v for k, v in parameters.items() if v is not None},
            "bounds": {name: list(b) for name, b in PARAMETER_BOUNDS.items()},
            "calibration": {"rmse_K": 1.5}}


def test_empty_object_lists_every_missing_coefficient(tmp_path):
    """Finding 5: ``{}`` used to run at 1/1/1."""
    with pytest.raises(ParameterError, match=r"params\.json: missing coefficient\(s\) "
                       r"flow_coefficient, friction_coefficient, heat_transfer_coefficient"):
        ModelParameters.from_json(_write(tmp_path, {}))


@pytest.mark.parametrize("name", list(PARAMETER_BOUNDS))
def test_a_missing_coefficient_is_named_not_defaulted(tmp_path, name):
    """Finding 5: a missing coefficient used to become 1.0 silently."""
    with pytest.raises(ParameterError,
                       match=rf"params\.json: missing coefficient\(s\) parameters\.{name};"):
        ModelParameters.from_json(_write(tmp_path, _calibrated(**{name: None})))


@pytest.mark.parametrize(("document", "message"), [
    (_calibrated(frictoin_coefficient=1.2, friction_coefficient=None),
     r"parameters\.frictoin_coefficient is not a parameter file field "
     r"\(did you mean 'friction_coefficient'\?\)"),
    ({"paramters": _calibrated()["parameters"]},
     r"paramters is not a parameter file field \(did you mean 'parameters'\?\)"),
    ({**_calibrated(), "calibraton": {}},
     r"calibraton is not a parameter file field \(did you mean 'calibration'\?\)"),
    ({"flow_coefficient": 1.0, "friction_coefficient": 1.0, "heat_transfer_coeficient": 1.0},
     r"heat_transfer_coeficient is not a parameter file field "
     r"\(did you mean 'heat_transfer_coefficient'\?\)"),
    ({"flow_coefficient": 1.0, "leakage": 2.0}, r"leakage is not a parameter file field; "
     r"expected one of: bounds, calibration, flow_coefficient"),
], ids=["in-parameters", "wrapper", "metadata", "top-level", "no-close-match"])
def test_unknown_key_is_refused_with_a_hint(tmp_path, document, message):
    """Finding 5: a misspelled key never falls back to a default or goes unnoticed."""
    with pytest.raises(ParameterError, match=rf"params\.json: {message}"):
        ModelParameters.from_json(_write(tmp_path, document))


@pytest.mark.parametrize(("text", "shown"), [
    ('"0.98"', "'0.98'"), ("true", "True"), ("null", "None"), ("[1.0]", r"\[1\.0\]"),
    ("NaN", "nan"), ("Infinity", "inf"), ("-1e999", "-inf"), ("1.5", "1.5"), ("0", "0"),
    ("1" * 400, "1{400}"),
], ids=["string", "bool", "null", "array", "nan", "inf", "overflow", "above", "below", "huge"])
def test_bad_value_names_file_key_and_bounds(tmp_path, text, shown):
    document = json.dumps(_calibrated()).replace('"flow_coefficient": 0.98',
                                                 f'"flow_coefficient": {text}')
    with pytest.raises(ParameterError, match=rf"params\.json: parameters\.flow_coefficient = "
                       rf"{shown}: expected a number within its physical bounds \[0\.9, 1\.1\]"):
        ModelParameters.from_json(_write(tmp_path, document))


@pytest.mark.parametrize(("content", "message"), [
    (b"", r"the file is empty"),
    (b"  \n", r"the file is empty"),
    (b"[0.98, 1.2, 1.4]", r"expected a JSON object with flow_coefficient.*got list"),
    (b'"params"', r"expected a JSON object .*got str"),
    (b"{flow_coefficient: 1}", r"not valid JSON: Expecting property name"),
    (b'{"flow_coefficient": 1, "flow_coefficient": 1}',
     r"not valid JSON: key 'flow_coefficient' appears twice"),
    (b"[" * 100_000, r"not valid JSON"),
    (b"\x89PNG\r\n\x1a\n\x00\x00", r"not UTF-8 text \(byte 0x89 at offset 0, line 1\)"),
    ('{"注释": "摩擦系数"}'.encode("gbk"), r"not UTF-8 text"),
    (json.dumps({**_calibrated(), "bounds": [0.9, 1.1]}).encode(),
     r"bounds must be a JSON object \(informational metadata\), got list"),
    (json.dumps({**_calibrated(), "flow_coefficient": 1.0}).encode(),
     r"flow_coefficient given both at the top level and under 'parameters'"),
    (json.dumps({"parameters": [1, 1, 1]}).encode(), r"parameters must be a JSON object"),
], ids=["empty", "blank", "array", "string", "not-json", "duplicate", "deep", "binary", "gbk",
        "bounds-type", "both-forms", "parameters-type"])
def test_unreadable_file_is_refused_naming_it(tmp_path, content, message):
    path = tmp_path / "params.json"
    path.write_bytes(content)
    with pytest.raises(ParameterError, match=rf"params\.json: {message}"):
        ModelParameters.from_json(path)


def test_a_byte_order_mark_is_accepted(tmp_path):
    path = tmp_path / "params.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps(_calibrated()).encode())
    assert ModelParameters.from_json(path) == ModelParameters(0.98, 1.2, 1.4)


def test_a_folder_or_missing_file_is_refused(tmp_path):
    with pytest.raises(ParameterError, match=r"cannot read the parameter file: Is a directory"):
        ModelParameters.from_json(tmp_path)
    with pytest.raises(ParameterError,
                       match=r"nope\.json: cannot read the parameter file: No such file"):
        ModelParameters.from_json(tmp_path / "nope.json")


def test_from_dict_names_its_source():
    with pytest.raises(ParameterError, match=r"rom\.npz provenance: missing coefficient"):
        ModelParameters.from_dict({}, "rom.npz provenance")
    assert ModelParameters.from_dict(_calibrated()) == ModelParameters(0.98, 1.2, 1.4)
