"""Heat-balance files: the shipped example thermal kit, the issue's format and every refusal.

Each bad-input case edits the shipped example (a 600 MW unit that is not the reference unit)
and expects a :class:`HeatBalanceError` whose message names the file, the point (1-based
position and label) and the field; a property test mutates the example at random and accepts
only a valid result or such an error.
"""

from __future__ import annotations

import copy
import re
import runpy
import tomllib
from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from toml_documents import KeyPath, key_paths, toml_text

from steamtwin.spec import (
    HeatBalanceError,
    load_heat_balance,
    parse_heat_balance,
)
from steamtwin.spec.heat_balance import HEAT_BALANCE_KEYS
from steamtwin.steam import if97

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "make_example_heat_balance.py"

EXAMPLE_TEXT = (resources.files("steamtwin.spec") / "data" /
                "example-600mw-heat-balance.toml").read_text(encoding="utf-8")
EXAMPLE = tomllib.loads(EXAMPLE_TEXT)
SOURCE = "kit.toml"

ISSUE_SNIPPET = '''
name = "Unit 3 thermal kit"
[machine]                     # what the drawings give
pressure_stages = 12
rotational_speed = "3000 rpm"
control_stage_mean_diameter = "1.05 m"
valve_arcs = [0.25, 0.25, 0.21, 0.21]
valve_opening_order = [1, 1, 2, 3]
[[points]]                    # one per heat-balance diagram, any number >= 1
label = "THA"
load = "600 MW"
main_steam_pressure = "16.7 MPa"
main_steam_temperature = "538 degC"
main_steam_flow = "1700 t/h"
control_stage_pressure = "12.30 MPa"
control_stage_temperature = "497.8 degC"   # optional
hp_exhaust_pressure = "3.75 MPa"
hp_exhaust_temperature = "322.8 degC"
'''


def _parse(edit: Callable[[dict[str, Any]], Any]) -> Any:
    document = copy.deepcopy(EXAMPLE)
    edit(document)
    return parse_heat_balance(toml_text(document), SOURCE)


def _point(document: dict[str, Any], number: int) -> dict[str, Any]:
    return document["points"][number - 1]


def _isentropic_exhaust_temperature_c(number: int) -> float:
    """The exhaust temperature of an isentropic HP expansion at example point ``number``, °C."""
    point = _point(EXAMPLE, number)
    p0 = float(point["main_steam_pressure"].split()[0]) * 1e6
    t0 = float(point["main_steam_temperature"].split()[0]) + 273.15
    p_exh = float(point["hp_exhaust_pressure"].split()[0]) * 1e6
    s0 = if97.entropy_pt(p0, t0)
    return float(if97.temperature_ps(p_exh, s0)) - 273.15


# --------------------------------------------------------------------------------------------
# Valid files
# --------------------------------------------------------------------------------------------


def test_example_loads_in_si_units():
    kit = load_heat_balance(resources.files("steamtwin.spec") / "data" /
                            "example-600mw-heat-balance.toml")
    machine = kit.machine
    assert machine.pressure_stages == 11
    assert machine.rotational_speed_rad_s == pytest.approx(100 * np.pi)
    assert machine.control_stage_mean_diameter_m == pytest.approx(1.05)
    assert machine.valve_arcs == (0.16, 0.16, 0.16, 0.16, 0.13, 0.13)
    assert machine.valve_opening_order == (1, 1, 1, 1, 1, 2)
    assert machine.valve_names == ("GV1", "GV2", "GV3", "GV4", "GV5", "GV6")
    assert machine.valve_overlap is None and machine.valve_pressure_drop is None
    assert machine.rated_load_w == pytest.approx(600e6)
    assert [p.label for p in kit.points] == ["VWO", "THA", "75 %", "50 %", "40 %", "30 %"]
    np.testing.assert_allclose(kit.loads_w, [627.7e6, 600e6, 450e6, 300e6, 240e6, 180e6])
    tha = kit.point("THA")
    assert tha.main_steam_pressure_pa == pytest.approx(16.67e6)
    assert tha.main_steam_temperature_k == pytest.approx(810.15)
    assert tha.main_steam_flow_kg_s == pytest.approx(1750 / 3.6)
    assert tha.control_stage_pressure_pa == pytest.approx(13.009e6)
    assert tha.control_stage_temperature_k == pytest.approx(503.9 + 273.15)
    assert tha.valve_outlet_pressure_pa == pytest.approx(16.003e6)
    assert tha.hp_exhaust_pressure_pa == pytest.approx(3.62e6)
    assert tha.hp_exhaust_temperature_k == pytest.approx(318.5 + 273.15)
    assert tha.hp_exhaust_flow_kg_s == pytest.approx(1609.2 / 3.6)
    assert tha.hp_power_w == pytest.approx(175.7e6)
    assert tha.reheat_temperature_k == pytest.approx(810.15)
    assert tha.feedwater_temperature_k == pytest.approx(274.8 + 273.15)
    assert [(b.name, b.flow_kg_s, b.pressure_pa) for b in tha.extractions] == [
        ("HP heater 1", pytest.approx(123.3 / 3.6), pytest.approx(5.95e6)),
        ("HP heater 2", pytest.approx(133.4 / 3.6), pytest.approx(3.62e6))]
    # whole-HP efficiency falls at part load (throttling, partial admission), inside the band
    efficiencies = [p.hp_isentropic_efficiency for p in kit.points]
    assert all(0.5 <= e <= 0.95 for e in efficiencies)
    assert efficiencies[1] == pytest.approx(0.867, abs=1e-3)
    assert np.all(np.diff(efficiencies) < 0)
    assert kit.source.endswith("example-600mw-heat-balance.toml")


def test_example_is_what_the_tool_computes(capsys):
    """The shipped kit is reproducible: tools/make_example_heat_balance.py prints it."""
    runpy.run_path(str(TOOL), run_name="__main__")
    assert capsys.readouterr().out == EXAMPLE_TEXT


def test_example_is_not_the_reference_unit(reference_spec):
    tha = parse_heat_balance(EXAMPLE_TEXT).point("THA")
    design = reference_spec.design
    assert tha.main_steam_pressure_pa != pytest.approx(design.main_steam_pressure)
    assert tha.main_steam_flow_kg_s != pytest.approx(design.main_steam_flow)
    assert len(reference_spec.stages) != parse_heat_balance(EXAMPLE_TEXT).machine.pressure_stages


def test_issue_snippet_loads():
    kit = parse_heat_balance(ISSUE_SNIPPET, "unit3.toml")
    assert kit.name == "Unit 3 thermal kit"
    assert kit.description is None
    assert kit.machine.valve_names == ("GV1", "GV2", "GV3", "GV4")
    assert kit.machine.valve_overlap is None and kit.machine.rated_load_w is None
    (tha,) = kit.points
    assert tha.load_w == pytest.approx(600e6)
    assert tha.main_steam_flow_kg_s == pytest.approx(1700 / 3.6)
    assert tha.control_stage_pressure_pa == pytest.approx(12.30e6)
    assert tha.hp_exhaust_temperature_k == pytest.approx(322.8 + 273.15)
    assert tha.hp_exhaust_flow_kg_s is None and tha.hp_power_w is None
    assert tha.reheat_temperature_k is None and tha.feedwater_temperature_k is None
    assert tha.extractions == ()


def test_control_stage_temperature_is_optional():
    kit = _parse(lambda d: [p.pop("control_stage_temperature") for p in d["points"]])
    assert all(p.control_stage_temperature_k is None for p in kit.points)


def test_docs_describe_every_field():
    docs = (ROOT / "docs" / "heat-balance.md").read_text(encoding="utf-8")
    documented = set(re.findall(r"^\| `(\w+)` \|", docs, re.MULTILINE))
    assert documented == set().union(*HEAT_BALANCE_KEYS.values())


def test_point_lookup_names_the_labels():
    kit = parse_heat_balance(EXAMPLE_TEXT, SOURCE)
    with pytest.raises(HeatBalanceError, match=r"kit.toml: no point labelled '60 %'.*'THA'"):
        kit.point("60 %")


# --------------------------------------------------------------------------------------------
# Bad input: each case names the file, the point and the field
# --------------------------------------------------------------------------------------------

P2, P3, P4 = r'points\[2\] \("THA"\): ', r'points\[3\] \("75 %"\): ', r'points\[4\] \("50 %"\): '


def _set(number: int, key: str, value: Any) -> Callable[[dict[str, Any]], None]:
    return lambda d: _point(d, number).__setitem__(key, value)


def _drop(number: int, key: str) -> Callable[[dict[str, Any]], None]:
    return lambda d: _point(d, number).pop(key)


def _machine(key: str, value: Any) -> Callable[[dict[str, Any]], None]:
    return lambda d: d["machine"].__setitem__(key, value)


def _swap(d: dict[str, Any]) -> None:
    d["points"][1], d["points"][2] = d["points"][2], d["points"][1]


def _rename(d: dict[str, Any]) -> None:
    point = _point(d, 2)
    point["hp_exhaust_temprature"] = point.pop("hp_exhaust_temperature")


def _both(*edits: Callable[[dict[str, Any]], Any]) -> Callable[[dict[str, Any]], None]:
    def edit(d: dict[str, Any]) -> None:
        for one in edits:
            one(d)
    return edit


BAD_POINTS = [
    # missing, unknown, wrong unit
    (_drop(4, "control_stage_pressure"), P4 + "control_stage_pressure is missing"),
    (_drop(2, "label"), r"points\[2\]: label is missing"),
    (_rename, P2 + r"hp_exhaust_temprature is not a heat balance field \(did you mean "
              r"'hp_exhaust_temperature'\?\)"),
    (_set(2, "main_steam_pressure", 16.67), P2 + "main_steam_pressure: 16.67 has no unit"),
    (_set(2, "main_steam_pressure", "16.67 degC"), P2 + "main_steam_pressure: .*not convertible"),
    (_set(2, "main_steam_flow", True), P2 + "main_steam_flow is a boolean"),
    (_set(2, "main_steam_pressure", "16.67 kPa"), P2 + r"main_steam_pressure = '16.67 kPa' is "
                                                      r"outside the plausible range \[0.5 MPa"),
    (_set(2, "label", ""), r'points\[2\] \(""\): label = \'\': expected a non-empty string'),
    # order and duplicates
    (_swap, r'points\[3\] \("THA"\): load = 600 MW is above the load of points\[2\].*out of '
            "order"),
    (_set(4, "load", "450 MW"), P4 + r'load = 450 MW duplicates the load of points\[3\] '
                                     r'\("75 %"\)'),
    (_set(4, "label", "THA"), r'points\[4\] \("THA"\): label repeats the label of points\[2\]'),
    # flow and pressures must fall with load
    (_both(_set(4, "main_steam_flow", "1300 t/h"), _drop(4, "hp_power")),
     P4 + r"main_steam_flow = 1300 t/h is not below that of points\[3\].*fall with load"),
    (_set(3, "control_stage_pressure", "6.0 MPa"), P4 + "control_stage_pressure = .* fall"),
    (_both(_set(3, "hp_exhaust_pressure", "1.6 MPa"), _drop(3, "hp_exhaust_flow"),
           _drop(3, "hp_power")),
     P4 + "hp_exhaust_pressure = .* fall with load"),
    # pressures and temperatures through the HP
    (_set(2, "control_stage_pressure", "16.8 MPa"), P2 + "control_stage_pressure = 16.8 MPa is "
                                                         "not below main_steam_pressure"),
    (_set(2, "hp_exhaust_pressure", "13.5 MPa"), P2 + "hp_exhaust_pressure = 13.5 MPa is not "
                                                      "below control_stage_pressure"),
    (_set(6, "main_steam_temperature", "270 degC"),
     r'points\[6\] \("30 %"\): main_steam_temperature .* is not superheated steam'),
    (_set(2, "hp_exhaust_temperature", "540 degC"),
     P2 + "hp_exhaust_temperature = 540 °C is not below main_steam_temperature .* hotter than"),
    (_set(2, "hp_exhaust_temperature", "240 degC"),
     P2 + "hp_exhaust_temperature .* is not superheated steam"),
    (_set(2, "control_stage_temperature", "300 degC"),
     P2 + "control_stage_temperature = 300 °C is not between hp_exhaust_temperature"),
    (_set(2, "control_stage_temperature", "537 degC"),
     P2 + "control_stage_temperature = 537 °C is not between"),
    (_set(2, "hp_exhaust_temperature", "420 degC"),
     P2 + r"hp_exhaust_temperature = 420 °C implies an HP isentropic efficiency of 0\.[0-4]"),
    (_set(2, "hp_exhaust_temperature", f"{_isentropic_exhaust_temperature_c(2) + 2:.1f} degC"),
     P2 + r"hp_exhaust_temperature = .* efficiency of 0\.9[6-9].*expected \[0.5, 0.95\]"),
    # optional figures
    (_set(2, "hp_exhaust_flow", "1700 t/h"), P2 + "hp_exhaust_flow = 1700 t/h: expected between"),
    (_set(2, "valve_outlet_pressure", "17 MPa"),
     P2 + r"valve_outlet_pressure = 17 MPa is not between control_stage_pressure \(13\.01 MPa\)"
          r" and main_steam_pressure \(16\.67 MPa\): the governing valves only throttle"),
    (_set(2, "valve_outlet_pressure", "13 MPa"), P2 + "valve_outlet_pressure = 13 MPa is not"),
    (_set(2, "hp_exhaust_flow", "800 t/h"), P2 + "hp_exhaust_flow = 800 t/h: expected between"),
    (_set(2, "hp_power", "220 MW"), P2 + "hp_power = 220 MW does not match the expansion"),
    (_set(2, "hp_power", "140 MW"), P2 + "hp_power = 140 MW does not match the expansion"),
    (_set(2, "reheat_temperature", "310 degC"), P2 + "reheat_temperature = 310 °C is not above"),
    (_set(2, "feedwater_temperature", "280 degC"),
     P2 + r"feedwater_temperature = 280 °C: the top heater cannot heat .*saturation at the "
          r"highest bleed, 5\.95 MPa"),
    (_both(_set(2, "feedwater_temperature", "340 degC"),
           lambda d: [p.pop("extractions") for p in d["points"]]),
     P2 + "feedwater_temperature = 340 °C: .*saturation at control_stage_pressure"),
    (lambda d: _point(d, 2)["extractions"][0].__setitem__("pressure", "14 MPa"),
     P2 + r"extractions\[1\]: pressure = 14 MPa is outside the HP section"),
    (lambda d: _point(d, 2)["extractions"][1].__setitem__("name", "HP heater 1"),
     P2 + r"extractions\[2\]: name = 'HP heater 1' is listed twice"),
    (lambda d: _point(d, 2)["extractions"][1].__setitem__("flow", "900 t/h"),
     P2 + r"extractions: the bleeds take .* of main_steam_flow"),
    (lambda d: _point(d, 2)["extractions"][1].__setitem__("flw", "9 t/h"),
     P2 + r"extractions\[2\]: flw is not a heat balance field \(did you mean 'flow'\?\)"),
    (lambda d: _point(d, 4).pop("extractions"),
     P4 + r"extractions lists \[\] but points\[1\] lists \['HP heater 1', 'HP heater 2'\]"),
    (lambda d: _point(d, 4).__setitem__("extractions", []),
     P4 + "extractions: expected a non-empty array of tables"),
]


@pytest.mark.parametrize(("edit", "message"), BAD_POINTS)
def test_bad_point_is_refused_naming_point_and_field(edit, message):
    with pytest.raises(HeatBalanceError, match=r"^kit\.toml: " + message):
        _parse(edit)


BAD_MACHINE = [
    (lambda d: d["machine"].pop("valve_arcs"), "valve_arcs is missing"),
    (_machine("pressure_stages", 0), r"pressure_stages = 0: expected an integer in \[1, 30\]"),
    (_machine("pressure_stages", 31), r"pressure_stages = 31: expected an integer"),
    (_machine("pressure_stages", 11.0), r"pressure_stages = 11.0: expected an integer"),
    (_machine("rotational_speed", "3000 m"), "rotational_speed: .*not convertible to rad/s"),
    (_machine("rotational_speed", "-3000 rpm"), r"rotational_speed = '-3000 rpm' is outside"),
    (_machine("control_stage_mean_diameter", "1.05 mm"), "control_stage_mean_diameter = "
                                                         "'1.05 mm' is outside"),
    (_machine("control_stage_mean_diameter", "2.6 m"),
     r"control_stage_mean_diameter: a mean blade speed of 408 m/s"),
    (_machine("valve_arcs", [0.16, 0.0, 0.16, 0.16, 0.13, 0.13]),
     r"valve_arcs\[2\] = 0.0: expected a fraction of the circumference in \(0, 1\]"),
    (_machine("valve_arcs", [0.16, 0.16, 0.16, 0.16, 0.13, 1.2]), r"valve_arcs\[6\] = 1.2"),
    (_machine("valve_arcs", [0.16, 0.16, 0.16, 0.16, 0.13, "0.13"]), r"valve_arcs\[6\] = '0.13'"),
    (_machine("valve_arcs", [0.25, 0.25, 0.16, 0.16, 0.13, 0.13]),
     "valve_arcs: the arcs sum to 1.08"),
    (_machine("valve_arcs", []), r"valve_arcs = \[\]: expected a non-empty array"),
    (_machine("valve_opening_order", [1, 1, 2, 3]),
     "valve_opening_order has 4 entries but valve_arcs has 6"),
    (_machine("valve_opening_order", [1, 1, 1, 1, 3, 4]),
     r"valve_opening_order = .*: no valve opens at step 2"),
    (_machine("valve_opening_order", [2, 2, 2, 2, 3, 4]),
     r"valve_opening_order = .*: no valve opens at step 1"),
    (_machine("valve_opening_order", [0, 1, 1, 1, 2, 3]),
     r"valve_opening_order\[1\] = 0: expected an integer ≥ 1"),
    (_machine("valve_names", ["GV1", "GV2"]), "valve_names = .*expected 6 distinct"),
    (_machine("valve_names", ["GV1", "GV1", "GV3", "GV4", "GV5", "GV6"]), "valve_names"),
    (_machine("valve_overlap", 0.6), r"valve_overlap = 0.6: expected a plain number in \[0, 0.5\)"),
    (_machine("valve_overlap", "10 %"), "valve_overlap = '10 %': expected a plain number"),
    (_both(_machine("valve_opening_order", [1] * 6), _machine("valve_overlap", 0.1)),
     "valve_overlap: every valve opens at step 1"),
    (_machine("valve_pressure_drop", 0.3), r"valve_pressure_drop = 0.3: expected a plain number "
                                           r"in \[0, 0.2\]"),
    (_machine("valve_pressure_drop", "3 %"), "valve_pressure_drop = '3 %': expected a plain"),
    (_machine("rated_load", "6000 MW"), "rated_load = '6000 MW' is outside the plausible range"),
    (_machine("pressure_stage", 11), r"pressure_stage is not a heat balance field \(did you "
                                      r"mean 'pressure_stages'\?\)"),
]


@pytest.mark.parametrize(("edit", "message"), BAD_MACHINE)
def test_bad_machine_is_refused_naming_the_field(edit, message):
    with pytest.raises(HeatBalanceError, match=r"^kit\.toml: machine: " + message):
        _parse(edit)


@pytest.mark.parametrize(("edit", "message"), [
    (lambda d: d.pop("name"), "name is missing"),
    (lambda d: d.__setitem__("points", []), "points: expected a non-empty array of tables"),
    (lambda d: d.__setitem__("points", [1]), r"points\[1\] is an integer: expected a table"),
    (lambda d: d.__setitem__("machien", d.pop("machine")),
     r"machien is not a heat balance field \(did you mean 'machine'\?\)"),
    (lambda d: d.__setitem__("description", 3), "description = 3: expected a non-empty string"),
])
def test_bad_document_is_refused(edit, message):
    with pytest.raises(HeatBalanceError, match=r"^kit\.toml: " + message):
        _parse(edit)


def test_files_that_are_not_heat_balances(tmp_path):
    with pytest.raises(HeatBalanceError, match=r"^kit\.toml: not valid TOML"):
        parse_heat_balance("name = ", SOURCE)
    missing = tmp_path / "missing.toml"
    with pytest.raises(HeatBalanceError, match=r"missing\.toml: cannot read the heat balance"):
        load_heat_balance(missing)
    gbk = tmp_path / "gbk.toml"
    gbk.write_bytes(EXAMPLE_TEXT.encode("utf-8") + "# 热平衡".encode("gbk"))
    with pytest.raises(HeatBalanceError, match=r"gbk\.toml: not UTF-8 text .*heat balance"):
        load_heat_balance(gbk)
    empty = tmp_path / "empty.toml"
    empty.write_text("  \n", encoding="utf-8")
    with pytest.raises(HeatBalanceError, match=r"empty\.toml: the file is empty"):
        load_heat_balance(empty)


# --------------------------------------------------------------------------------------------
# Random mutations: a valid result or a HeatBalanceError naming the file, never a crash
# --------------------------------------------------------------------------------------------

KEY_PATHS = key_paths(EXAMPLE)


def _parent(document: Any, path: KeyPath) -> Any:
    for step in path[:-1]:
        document = document[step]
    return document


def _quantity_paths() -> list[KeyPath]:
    result = []
    for path in KEY_PATHS:
        value = _parent(EXAMPLE, path)[path[-1]]
        if isinstance(value, str) and re.fullmatch(r"-?[\d.]+ \S+", value):
            result.append(path)
    return result


QUANTITIES = _quantity_paths()
UNITS = ["MPa", "kPa", "bar", "degC", "K", "degF", "t/h", "kg/s", "MW", "kW", "rpm", "m", "mm",
         "kg", "furlong", "%", ""]


def _mutate(document: dict[str, Any], kind: str, index: int, unit: str, char: str) -> None:
    if kind == "delete":
        path = KEY_PATHS[index % len(KEY_PATHS)]
        _parent(document, path).pop(path[-1])
    elif kind == "rename":
        path = KEY_PATHS[index % len(KEY_PATHS)]
        table, key = _parent(document, path), str(path[-1])
        position = index % len(key)
        table[key[:position] + char + key[position + 1:]] = table.pop(key)
    elif kind == "swap":
        points = document["points"]
        first, second = index % len(points), (index // len(points)) % len(points)
        points[first], points[second] = points[second], points[first]
    else:
        path = QUANTITIES[index % len(QUANTITIES)]
        table = _parent(document, path)
        table[path[-1]] = f"{table[path[-1]].split()[0]} {unit}".strip()


@settings(max_examples=80, deadline=None)
@given(kinds=st.lists(st.sampled_from(["delete", "rename", "swap", "unit"]), min_size=1,
                      max_size=3),
       index=st.integers(0, 10_000), unit=st.sampled_from(UNITS),
       char=st.sampled_from(list("aeiz_ 0")))
def test_mutated_example_is_valid_or_refused_naming_the_file(kinds, index, unit, char):
    document = copy.deepcopy(EXAMPLE)
    for step, kind in enumerate(kinds):
        _mutate(document, kind, index + 7 * step, unit, char)
    try:
        kit = parse_heat_balance(toml_text(document), SOURCE)
    except HeatBalanceError as error:
        assert str(error).startswith(f"{SOURCE}: ")
    else:
        assert len(kit.points) >= 1
        assert np.all(np.diff(kit.loads_w) < 0)


def test_the_shipped_kit_loads_by_its_name():
    from steamtwin.spec.heat_balance import BUILT_IN_KITS

    assert BUILT_IN_KITS == ("example-600mw",)
    by_name = load_heat_balance("example-600mw")
    path = resources.files("steamtwin.spec") / "data" / "example-600mw-heat-balance.toml"
    assert by_name.points == load_heat_balance(str(path)).points
    assert by_name.source == "built-in 'example-600mw'"
