"""Model parameters: bounds, JSON round trip, clear errors."""

from __future__ import annotations

import json

import pytest

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


def test_json_round_trip_and_errors(tmp_path):
    params = ModelParameters(0.97, 1.3, 1.6)
    path = tmp_path / "params.json"
    params.to_json(path)
    assert ModelParameters.from_json(path) == params
    path.write_text(json.dumps({"flow_coefficient": 1.0, "leakage": 2.0}))
    with pytest.raises(ParameterError, match=r"params.json: unknown parameter\(s\) \['leakage'\]"):
        ModelParameters.from_json(path)
