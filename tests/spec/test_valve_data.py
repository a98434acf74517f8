"""Governing-valve data in the spec (issue 17, item 1): the valves' flow characteristic, the
nozzle-group throat areas and the valve outlet pressure of a rated point between valve points
load in SI or are refused naming the field."""

from __future__ import annotations

import copy
import tomllib
from importlib import resources

import pytest
from toml_documents import toml_text

from steamtwin.spec import SpecError, parse_spec

REFERENCE = tomllib.loads((resources.files("steamtwin.spec") / "data" / "reference.toml")
                          .read_text(encoding="utf-8"))
CONCAVE = ((0.0, 0.3, 1.0), (0.0, 0.8, 1.0))


def _spec_text(edit) -> str:
    document = copy.deepcopy(REFERENCE)
    edit(document)
    return toml_text(document)


def _characteristic(lift: list[float], flow: list[float]):
    def edit(document: dict) -> None:
        document["control_stage"]["valve_characteristic"] = {"lift": lift, "flow": flow}
    return edit


def _throat(valve: int, area: str | None):
    def edit(document: dict) -> None:
        for number, entry in enumerate(document["control_stage"]["valves"]):
            if number == valve:
                entry["throat_area"] = area
    return edit


@pytest.mark.parametrize(("edit", "message"), [
    (_characteristic([0.0, 0.5], [0.0, 0.5, 1.0]), "lift has 2 values but flow has 3"),
    (_characteristic([0.1, 1.0], [0.0, 1.0]), r"lift must rise strictly from 0 to 1"),
    (_characteristic([0.0, 0.6, 0.6, 1.0], [0.0, 0.5, 0.6, 1.0]), "lift must rise strictly"),
    (_characteristic([0.0, 0.5, 1.0], [0.0, 0.9, 0.8]), r"flow must rise from 0 to 1 \(never "
                                                         r"fall\), got \[0.0, 0.9, 0.8\]"),
    (_characteristic([0.0, 0.5, 1.0], [0.0, 1.2, 1.0]),
     r"control_stage.valve_characteristic.flow\[2\] = 1.2 is outside the valid range"),
    (_characteristic([0.0], [0.0]), r"lift must be an array of ≥ 2 numbers"),
    (_throat(0, "0.01 m^2"), r"control_stage.valves\[\]\.throat_area is given for some valves but "
                             r"not for GV2, GV3, GV4"),
    (_throat(1, "2 m^2"), r"control_stage.valves\[2\].throat_area = '2 m\^2' is outside"),
    (lambda d: d["design"].__setitem__("valve_outlet_pressure", "16.5 MPa"),
     r"design.valve_outlet_pressure 16.5 MPa must lie above design.control_stage_pressure .* "
     r"and not above the wide-open valve outlet"),
    (lambda d: d["design"].__setitem__("valve_outlet_pressure", "12 MPa"),
     r"design.valve_outlet_pressure 12 MPa must lie above"),
])
def test_bad_valve_data_are_refused_naming_the_field(edit, message):
    with pytest.raises(SpecError, match=r"^unit\.toml: .*" + message):
        parse_spec(_spec_text(edit), "unit.toml")


def test_valve_data_load_in_si(reference_spec):
    def edit(document: dict) -> None:
        _characteristic(list(CONCAVE[0]), list(CONCAVE[1]))(document)
        document["design"]["valve_outlet_pressure"] = "15.9 MPa"
        for entry in document["control_stage"]["valves"]:
            entry["throat_area"] = "85 cm^2"
    spec = parse_spec(_spec_text(edit), "unit.toml")
    assert spec.control_stage.valve_characteristic == CONCAVE
    assert spec.design.valve_outlet_pressure == 15.9e6
    assert [valve.throat_area for valve in spec.control_stage.valves] == pytest.approx([85e-4] * 4)
    # the reference unit states its poppet valves' curve: quick opening, flow share ≥ lift
    lift, flow = reference_spec.control_stage.valve_characteristic
    assert lift[0] == flow[0] == 0.0 and lift[-1] == flow[-1] == 1.0
    assert all(f >= x for x, f in zip(lift, flow, strict=True)) and flow[1] > 1.4 * lift[1]
