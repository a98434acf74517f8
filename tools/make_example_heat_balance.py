"""Compute the shipped example thermal kit (steamtwin/spec/data/example-600mw-heat-balance.toml).

An independent 600 MW subcritical single-reheat unit — 16.67 MPa / 537 °C / 537 °C, 1750 t/h at
THA, control stage of 1.05 m mean diameter with six governing valves, 11 HP pressure stages —
deliberately different from the built-in reference unit (16.7 MPa / 538 °C, 1800 t/h, 1.10 m,
four valves, 12 stages). The figures are the project's own engineering estimate, not a real
unit; they are computed here so that they are reproducible and physically consistent:

* Throttle flow vs load: m/m_THA = (P/P_THA)^1.08 — the steam rate of a sliding-pressure reheat
  unit falls slightly at part load because the reheater adds more heat per kg as the cold-reheat
  temperature rises; VWO passes 105 % of the THA flow at rated pressure.
* Main-steam pressure: rated 16.67 MPa at and above 90 % load, sliding linearly with load down to
  6.0 MPa at 30 % load (the unit's sliding-pressure line).
* Main-steam and reheat temperature: rated 537 °C down to 40 % resp. 50 % load, then falling (the
  boiler's own schedule at low firing rate).
* Expansion (IAPWS-IF97, steamtwin.steam.if97): governing-valve pressure drop, control stage at
  its efficiency over the isentropic drop from the valve outlet, then two groups of pressure
  stages (1-7 up to the HP heater 1 bleed, 8-11 up to the exhaust) at the pressure-stage
  efficiency. The control stage's drop at THA puts it at u/c0 = 0.45, just below the impulse
  optimum (~0.5) [Traupel, Thermische Turbomaschinen, 2001, §8]. Efficiencies fall at part load
  (partial admission, Reynolds number, incidence) as typical of HP sections [Cotton, Evaluating
  and Improving Steam Turbine Performance, 1998, ch. 6].
* Pressures vs flow: the HP-exhaust (cold-reheat) pressure is proportional to the throttle flow
  (the reheater and IP/LP sections act as one large Stodola group); the bleed pressure and the
  control-stage pressure follow from Stodola's cone law m = K·sqrt((p_in² − p_out²)/(p_in·v_in))
  of the two pressure-stage groups, K fixed at THA.
* Leakage: 1 % of the throttle flow leaves the control-stage chamber through the HP–IP balance
  piston (1-2 % usual [Cotton, ch. 6]) and does not pass the pressure stages.
* Bleeds from a feedwater-heater balance: the feedwater flow equals the throttle flow (drum unit,
  blowdown neglected) at p0 + 3 MPa; HP heater 1 (bleed after stage 7) and HP heater 2 (cold
  reheat) have desuperheating zones, terminal temperature difference −1.7 K, drain-cooler
  approach 5.6 K and 3 % pressure loss in the bleed pipe (HEI Standards for Closed Feedwater
  Heaters); the drain of heater 1 cascades to heater 2; heater 3's bleed pressure (IP section)
  is 1.75 MPa at THA and proportional to flow, and heater 2 receives the feedwater at heater 3's
  outlet temperature (same terminal difference).

Regenerate the file with::

    python tools/make_example_heat_balance.py \\
        > src/steamtwin/spec/data/example-600mw-heat-balance.toml
"""

from __future__ import annotations

import math

from steamtwin.steam import if97

SPEED_RPM = 3000.0  # 50 Hz grid, two-pole generator
SPEED = SPEED_RPM * 2.0 * math.pi / 60.0  # rad/s
CONTROL_DIAMETER = 1.05  # m
CONTROL_VELOCITY_RATIO = 0.45  # u/c0 of the control stage at THA
PRESSURE_STAGES = 11
BLEED_AFTER_STAGE = 7
RATED_LOAD = 600.0e6  # W, THA
THA_FLOW = 1750.0 / 3.6  # kg/s
VWO_FLOW_RATIO = 1.05
FLOW_EXPONENT = 1.08
RATED_PRESSURE = 16.67e6  # Pa
SLIDE_LOW, SLIDE_HIGH, SLIDE_LOW_PRESSURE = 0.30, 0.90, 6.0e6  # load fractions, Pa
THA_EXHAUST_PRESSURE = 3.62e6  # Pa, cold reheat ~22 % of throttle pressure [Cotton, ch. 2]
THA_BLEED_PRESSURE = 5.95e6  # Pa, HP heater 1 bleed after stage 7 at THA
THA_HEATER3_PRESSURE = 1.75e6  # Pa, IP bleed to HP heater 3 at THA
LEAKAGE = 0.01  # balance-piston leakage, fraction of throttle flow
FEEDWATER_PRESSURE_RISE = 3.0e6  # Pa, feedwater pressure above the throttle pressure
TTD, DCA, PIPE_LOSS = -1.7, 5.6, 0.03  # K, K, fraction (HEI closed-heater practice)

VALVE_ARCS = [0.16, 0.16, 0.16, 0.16, 0.13, 0.13]
# The unit's valve management: GV1-5 open together (below THA they throttle alike, p_valve =
# min(0.97 p0, p_cs / (p_cs/p_valve at THA))), GV6 is the overload valve, open only towards VWO.
VALVE_OPENING_ORDER = [1, 1, 1, 1, 1, 2]
VALVE_NAMES = ["GV1", "GV2", "GV3", "GV4", "GV5", "GV6"]

WIDE_OPEN_DROP, THA_DROP = 0.03, 0.04  # governing-valve pressure drop, fraction of p0

# label, load (MW; None: from the flow), main-steam T (degC), reheat T (degC), control-stage
# efficiency, pressure-stage efficiency. VWO: every valve wide open (3 % drop). THA: GV5
# part-open (4 % drop). Below THA the same nozzle groups stay in service and the valves
# throttle the steam to the pressure that keeps the control stage at its THA pressure ratio
# (p_cs/p_valve), as the sliding line holds p0 above what the open nozzles need.
POINTS = [
    ("VWO", None, 537.0, 537.0, 0.740, 0.900),
    ("THA", 600.0, 537.0, 537.0, 0.720, 0.900),
    ("75 %", 450.0, 537.0, 537.0, 0.715, 0.895),
    ("50 %", 300.0, 537.0, 537.0, 0.705, 0.885),
    ("40 %", 240.0, 537.0, 530.0, 0.700, 0.877),
    ("30 %", 180.0, 532.0, 515.0, 0.690, 0.865),
]


def f(x: object) -> float:
    return float(x)  # the if97 functions return 0-d arrays


def expand(p_in: float, h_in: float, p_out: float, efficiency: float) -> float:
    """Enthalpy after expanding from (p_in, h_in) to p_out at ``efficiency``, J/kg."""
    h_s = f(if97.enthalpy_ps(p_out, if97.entropy_ph(p_in, h_in)))
    return h_in - efficiency * (h_in - h_s)


def cone_capacity(flow: float, p_in: float, h_in: float, p_out: float) -> float:
    """Stodola flow capacity K = m / sqrt((p_in² − p_out²)/(p_in·v_in)), m²."""
    v_in = f(if97.specific_volume_ph(p_in, h_in))
    return flow / math.sqrt((p_in**2 - p_out**2) / (p_in * v_in))


def cone_inlet_pressure(capacity: float, flow: float, h_in: float, p_out: float) -> float:
    """Inlet pressure at which the cone law passes ``flow`` (bisection), Pa."""
    lo, hi = p_out * 1.0001, p_out * 20.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if cone_capacity(flow, mid, h_in, p_out) > capacity else (lo, mid)
    return 0.5 * (lo + hi)


def main_pressure(load_fraction: float) -> float:
    share = min(max((load_fraction - SLIDE_LOW) / (SLIDE_HIGH - SLIDE_LOW), 0.0), 1.0)
    return SLIDE_LOW_PRESSURE + share * (RATED_PRESSURE - SLIDE_LOW_PRESSURE)


def heater_bleeds(flow: float, p0: float, p_bleed: float, h_bleed: float, p_exh: float,
                  h_exh: float) -> tuple[float, float, float]:
    """HP heater 1 and 2 bleed flows (kg/s) and the final feedwater temperature (K)."""
    p_fw = p0 + FEEDWATER_PRESSURE_RISE
    ratio = flow / THA_FLOW
    t3 = f(if97.saturation_temperature(THA_HEATER3_PRESSURE * ratio * (1 - PIPE_LOSS))) - TTD
    t2 = f(if97.saturation_temperature(p_exh * (1 - PIPE_LOSS))) - TTD
    t1 = f(if97.saturation_temperature(p_bleed * (1 - PIPE_LOSS))) - TTD
    h_fw3, h_fw2, h_fw1 = (f(if97.enthalpy_pt(p_fw, t)) for t in (t3, t2, t1))
    drain1 = f(if97.enthalpy_pt(p_bleed * (1 - PIPE_LOSS), t2 + DCA))
    drain2 = f(if97.enthalpy_pt(p_exh * (1 - PIPE_LOSS), t3 + DCA))
    bleed1 = flow * (h_fw1 - h_fw2) / (h_bleed - drain1)
    bleed2 = (flow * (h_fw2 - h_fw3) - bleed1 * (drain1 - drain2)) / (h_exh - drain2)
    return bleed1, bleed2, t1


def point(load: float, flow: float, t0: float, eta_cs: float, eta_ps: float,
          design: dict[str, float] | None) -> dict[str, float]:
    """One heat-balance point; ``design`` (the THA point's capacities and control-stage
    pressure ratio) None designs the THA point itself."""
    p0 = main_pressure(load / RATED_LOAD)
    h0 = f(if97.enthalpy_pt(p0, t0))
    p_exh = THA_EXHAUST_PRESSURE * flow / THA_FLOW
    stage_flow = flow * (1.0 - LEAKAGE)
    if design is None:
        p_valve = p0 * (1.0 - THA_DROP)
        dh_cs = 0.5 * (SPEED * CONTROL_DIAMETER / 2.0 / CONTROL_VELOCITY_RATIO) ** 2
        s_valve = f(if97.entropy_ph(p_valve, h0))
        lo, hi = 0.3 * p_valve, p_valve
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if h0 - f(if97.enthalpy_ps(mid, s_valve)) > dh_cs else (lo, mid)
        p_cs, p_bleed = 0.5 * (lo + hi), THA_BLEED_PRESSURE
    else:
        p_cs, p_bleed = p0 * 0.74, THA_BLEED_PRESSURE * flow / THA_FLOW
        p_valve = p0 * (1.0 - WIDE_OPEN_DROP)
    for _ in range(30):  # cone laws, valve throttle, expansion and heater balance converge
        h_cs = expand(p_valve, h0, p_cs, eta_cs)
        h_bleed = expand(p_cs, h_cs, p_bleed, eta_ps)
        h_exh = expand(p_bleed, h_bleed, p_exh, eta_ps)
        bleed1, bleed2, t_fw = heater_bleeds(flow, p0, p_bleed, h_bleed, p_exh, h_exh)
        if design is None:
            break
        previous = p_cs
        p_bleed = cone_inlet_pressure(design["k_b"], stage_flow - bleed1, h_bleed, p_exh)
        p_cs = cone_inlet_pressure(design["k_a"], stage_flow, h_cs, p_bleed)
        if flow <= THA_FLOW:
            p_valve = min(p0 * (1.0 - WIDE_OPEN_DROP), p_cs / design["ratio"])
        if abs(p_cs - previous) < 1e-8 * p_cs:
            break
    power = flow * (h0 - h_cs) + stage_flow * (h_cs - h_bleed) + (stage_flow - bleed1) * (
        h_bleed - h_exh)
    return {
        "load": load, "p0": p0, "t0": t0, "flow": flow, "p_valve": p_valve, "p_cs": p_cs,
        "t_cs": f(if97.temperature_ph(p_cs, h_cs)), "h_cs": h_cs, "p_bleed": p_bleed,
        "h_bleed": h_bleed, "p_exh": p_exh, "t_exh": f(if97.temperature_ph(p_exh, h_exh)),
        "exh_flow": stage_flow - bleed1, "bleed1": bleed1, "bleed2": bleed2, "t_fw": t_fw,
        "power": power, "stage_flow": stage_flow,
    }


def quoted(text: str) -> str:
    return f'"{text}"'


def line(key: str, value: str, comment: str = "") -> str:
    """``key = value`` with the comment aligned at column 46."""
    text = f"{key} = {value}"
    return f"{text:<45} # {comment}" if comment else text


def print_point(label: str, row: dict[str, float], t_rh_c: float, eta_cs: float,
                eta_ps: float) -> None:
    h0 = f(if97.enthalpy_pt(row["p0"], row["t0"]))
    h_exh_s = f(if97.enthalpy_ps(row["p_exh"], if97.entropy_pt(row["p0"], row["t0"])))
    h_exh = f(if97.enthalpy_pt(row["p_exh"], row["t_exh"]))
    drop = 100.0 * (1.0 - row["p_valve"] / row["p0"])
    print(f"\n[[points]]\n# {100 * row['flow'] / THA_FLOW:.1f} % of THA flow; governing-valve "
          f"drop {drop:.1f} %, control-stage efficiency {eta_cs:.3f},\n# pressure-stage "
          f"efficiency {eta_ps:.3f}: whole-HP isentropic efficiency "
          f"{(h0 - h_exh) / (h0 - h_exh_s):.3f}.")
    rows = [
        ("label", f'"{label}"', ""),
        ("load", f'"{row["load"] / 1e6:.1f} MW"', "generator output"),
        ("main_steam_pressure", f'"{row["p0"] / 1e6:.3f} MPa"', "sliding-pressure line"),
        ("main_steam_temperature", f'"{row["t0"] - 273.15:.1f} degC"', "boiler schedule"),
        ("main_steam_flow", f'"{row["flow"] * 3.6:.1f} t/h"', "(P/P_THA)^1.08"),
        ("control_stage_pressure", f'"{row["p_cs"] / 1e6:.3f} MPa"',
         f"cone law, stages 1-{BLEED_AFTER_STAGE}"),
        ("control_stage_temperature", f'"{row["t_cs"] - 273.15:.1f} degC"', ""),
        ("valve_outlet_pressure", f'"{row["p_valve"] / 1e6:.3f} MPa"',
         "after the governing valves (nozzle chest)"),
        ("hp_exhaust_pressure", f'"{row["p_exh"] / 1e6:.3f} MPa"', "proportional to flow"),
        ("hp_exhaust_temperature", f'"{row["t_exh"] - 273.15:.1f} degC"', ""),
        ("hp_exhaust_flow", f'"{row["exh_flow"] * 3.6:.1f} t/h"',
         f"less 1 % leakage, stage-{BLEED_AFTER_STAGE} bleed"),
        ("hp_power", f'"{row["power"] / 1e6:.1f} MW"', "HP blading power"),
        ("reheat_temperature", f'"{t_rh_c:.1f} degC"', "boiler schedule"),
        ("feedwater_temperature", f'"{row["t_fw"] - 273.15:.1f} degC"',
         "HP heater 1 outlet, TTD -1.7 K"),
    ]
    print("\n".join(line(*entry) for entry in rows))
    for name, flow, pressure, where in (
            ("HP heater 1", row["bleed1"], row["p_bleed"],
             f"after pressure stage {BLEED_AFTER_STAGE}"),
            ("HP heater 2", row["bleed2"], row["p_exh"], "cold reheat")):
        extraction = [("name", quoted(name), where),
                      ("flow", quoted(f"{flow * 3.6:.1f} t/h"), "heater balance"),
                      ("pressure", quoted(f"{pressure / 1e6:.3f} MPa"), "")]
        print("\n[[points.extractions]]\n" + "\n".join(line(*entry) for entry in extraction))


def main() -> None:
    _, _, t0, _, eta_cs, eta_ps = POINTS[1]
    tha = point(RATED_LOAD, THA_FLOW, t0 + 273.15, eta_cs, eta_ps, None)
    design = {
        "k_a": cone_capacity(tha["stage_flow"], tha["p_cs"], tha["h_cs"], tha["p_bleed"]),
        "k_b": cone_capacity(tha["stage_flow"] - tha["bleed1"], tha["p_bleed"], tha["h_bleed"],
                             tha["p_exh"]),
        "ratio": tha["p_cs"] / tha["p_valve"],
    }
    print(HEADER)
    machine = [
        ("pressure_stages", str(PRESSURE_STAGES), "HP pressure stages after the control stage"),
        ("rotational_speed", f'"{SPEED_RPM:.0f} rpm"', "50 Hz grid, two-pole generator"),
        ("control_stage_mean_diameter", f'"{CONTROL_DIAMETER:.2f} m"',
         f"u = {SPEED * CONTROL_DIAMETER / 2:.1f} m/s"),
        ("valve_arcs", f"[{', '.join(f'{a:.2f}' for a in VALVE_ARCS)}]", "90 % of the circle"),
        ("valve_opening_order", f"[{', '.join(map(str, VALVE_OPENING_ORDER))}]",
         "GV1-5 together, then GV6"),
        ("valve_names", f"[{', '.join(map(quoted, VALVE_NAMES))}]", ""),
        ("rated_load", f'"{RATED_LOAD / 1e6:.0f} MW"', "THA rating"),
    ]
    print("[machine]\n" + "\n".join(line(*entry) for entry in machine))
    for label, load_mw, t0_c, t_rh_c, eta_cs, eta_ps in POINTS:
        if label == "THA":
            row = tha
        elif load_mw is None:
            row = point(RATED_LOAD * VWO_FLOW_RATIO ** (1.0 / FLOW_EXPONENT),
                        VWO_FLOW_RATIO * THA_FLOW, t0_c + 273.15, eta_cs, eta_ps, design)
        else:
            row = point(load_mw * 1e6, THA_FLOW * (load_mw * 1e6 / RATED_LOAD) ** FLOW_EXPONENT,
                        t0_c + 273.15, eta_cs, eta_ps, design)
        print_point(label, row, t_rh_c, eta_cs, eta_ps)


HEADER = """\
# Example thermal kit of an independent 600 MW subcritical single-reheat unit (NOT the built-in
# reference unit): 16.67 MPa / 537 °C / 537 °C, 1750 t/h at THA, nozzle governing with six
# governing valves, sliding pressure between 30 % and 90 % load.
# Every figure is the project's own engineering estimate, computed with IAPWS-IF97 by
# tools/make_example_heat_balance.py (regenerate this file with it; its docstring gives the
# method and sources). Per point: the throttle flow follows m/m_THA = (P/P_THA)^1.08; the
# control-stage and bleed pressures follow Stodola's cone law of the two pressure-stage groups
# (K fixed at THA); the HP-exhaust pressure is proportional to the throttle flow; the expansion
# uses the stated valve drop and stage efficiencies; the bleeds come from a heater balance.
# The format is described in docs/heat-balance.md.

name = "Example 600 MW subcritical unit, thermal kit"
description = "steamtwin example (not a real unit): 600 MW subcritical, six GVs, 11 HP stages"
"""


if __name__ == "__main__":
    main()
