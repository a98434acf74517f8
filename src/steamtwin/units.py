"""Unit handling at the edges of steamtwin (files, CLI, plots), with pint.

Everything inside the package is SI (Pa, K, kg/s, J/kg, W, m, s). Values arrive from users as
strings such as ``"16.7 MPa"`` or ``"538 degC"`` or as numbers in a declared unit, and leave in the
engineering units plant engineers read (MPa, °C, t/h, MW).
"""

from __future__ import annotations

import functools
import re
import tokenize
from functools import lru_cache

import numpy as np
import pint

from steamtwin.errors import DataError

# pint's expression parser lets these through on malformed unit text, past its own error
# types: "1 m)" (TokenError), "1 MPa/" (AssertionError), "1 m/0" (ZeroDivisionError),
# "1 adegC" (OffsetUnitCalculusError, a TypeError), "1 ma^0^2" (KeyError) — found by fuzzing
# the spec loader (tests/spec/test_spec_fuzz.py) with pint 0.25.
_PINT_PARSE_ERRORS = (AssertionError, ArithmeticError, LookupError, TypeError,
                      tokenize.TokenError)

_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


@lru_cache(maxsize=1)
def unit_registry() -> pint.UnitRegistry:
    """The package's single pint registry (t/h, rpm and °C understood)."""
    registry = pint.UnitRegistry(autoconvert_offset_to_baseunit=True)
    registry.define("tonne_per_hour = tonne / hour = t_per_h")
    return registry


class UnitError(DataError):
    """A value has no unit, an unknown unit or a unit of the wrong kind."""


def parse_quantity(text: str | float | int, expected_si_unit: str, where: str) -> float:
    """Parse ``"value unit"`` text and return the value in ``expected_si_unit``.

    ``where`` names the field or column for the error message. Plain numbers are accepted only
    when the expected unit is dimensionless (``""``).
    """
    registry = unit_registry()
    target = registry.Unit(expected_si_unit) if expected_si_unit else registry.dimensionless
    if isinstance(text, bool) or not isinstance(text, str | int | float):
        raise UnitError(
            f"{where}: expected a quantity in units of {expected_si_unit!r}, got {text!r}"
        )
    if isinstance(text, int | float):
        if expected_si_unit:
            raise UnitError(
                f"{where}: {text!r} has no unit; write it with one, "
                f"e.g. '{text} {expected_si_unit}'"
            )
        return float(text)
    match = _QUANTITY.match(text)
    if match is None:
        raise UnitError(f"{where}: cannot read {text!r} as 'value unit' (e.g. '16.7 MPa')")
    value, unit_text = float(match.group(1)), match.group(2) or "dimensionless"
    try:
        quantity = registry.Quantity(value, unit_text)
    except (pint.UndefinedUnitError, pint.errors.DefinitionSyntaxError, ValueError) as error:
        raise UnitError(f"{where}: unknown unit {unit_text!r} in {text!r}") from error
    except _PINT_PARSE_ERRORS:
        raise UnitError(f"{where}: cannot read the unit of {text!r}: expected 'value unit' with "
                        f"a unit convertible to {expected_si_unit or 'a plain number'}") from None
    if quantity.dimensionality != (1 * target).dimensionality:
        raise UnitError(
            f"{where}: {text!r} is not convertible to {expected_si_unit or 'a plain number'}"
        )
    return float(quantity.to(target).magnitude)


def convert(values: np.ndarray | float, from_unit: str, to_unit: str) -> np.ndarray:
    """Convert numbers between units (e.g. ``"MPa"`` → ``"Pa"``, ``"degC"`` → ``"K"``).

    The pair's units are parsed once (cached); a pure scale (every pair but the temperatures'
    offsets) is read from pint once and applied as a product, an offset pair goes through pint;
    a conversion the dimensions forbid raises pint's error."""
    source, target, scale = _pair(from_unit, to_unit)
    if scale is not None:
        return np.asarray(values, dtype=float) * scale
    quantity = unit_registry().Quantity(np.asarray(values, dtype=float), source)
    return np.asarray(quantity.to(target).magnitude, dtype=float)


@functools.lru_cache(maxsize=512)
def _pair(from_unit: str, to_unit: str) -> tuple[object, object, float | None]:
    registry = unit_registry()
    source, target = registry.Unit(from_unit), registry.Unit(to_unit)
    zero = float(registry.Quantity(0.0, source).to(target).magnitude)
    scale = float(registry.Quantity(1.0, source).to(target).magnitude)
    return source, target, scale if zero == 0.0 else None
