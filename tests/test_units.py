"""Quantities at the edges: 'value unit' text to SI."""

from __future__ import annotations

import numpy as np
import pytest

from steamtwin.units import UnitError, convert, parse_quantity


@pytest.mark.parametrize(("text", "unit", "expected"), [
    ("16.7 MPa", "Pa", 16.7e6), ("538 degC", "K", 811.15), ("1800 t/h", "kg/s", 500.0),
    ("3000 rpm", "rad/s", 100 * np.pi), ("13 deg", "rad", np.radians(13)), ("2.5 %", "", 0.025),
    (0.3, "", 0.3), ("7800 kg/m^3", "kg/m^3", 7800.0),
])
def test_parse_to_si(text, unit, expected):
    assert parse_quantity(text, unit, "field") == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(("text", "unit", "message"), [
    (16.7, "Pa", r"field: 16.7 has no unit"),
    ("16.7 parsecs per fortnight", "Pa", r"field: .*(unknown unit|not convertible)"),
    ("MPa", "Pa", r"field: cannot read 'MPa'"),
    (True, "", r"field: expected a quantity"),
])
def test_bad_quantities_name_the_field(text, unit, message):
    with pytest.raises(UnitError, match=message):
        parse_quantity(text, unit, "field")


def test_convert_arrays():
    assert np.allclose(convert([0.0, 100.0], "degC", "K"), [273.15, 373.15])
    assert convert(3.6, "t/h", "kg/s") == pytest.approx(1.0)
