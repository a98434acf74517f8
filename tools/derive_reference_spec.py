"""Derive the stage figures of the built-in reference unit (src/steamtwin/spec/data/reference.toml).

Reasoning, not a model run: the design heat balance (chosen figures, see the TOML comments) is
expanded stage by stage with IAPWS-IF97 (CoolProp) at an assumed stage efficiency; the control
stage takes the drop that puts it near its optimum velocity ratio; the pressure stages share the
remaining pressure ratio equally; each stage's Stodola flow capacity K = m/sqrt((p_in²−p_out²)/
(p_in·v_in)), its mean diameter (constant root diameter + blade height) and its blade height from
continuity follow. Run ``python tools/derive_reference_spec.py`` to print the table pasted into the
TOML (rounded there to 4 significant figures).
"""

from __future__ import annotations

import math

import CoolProp.CoolProp as CP

FLUID = "IF97::Water"
SPEED = 2 * math.pi * 50.0  # rad/s, 3000 rpm (50 Hz grid, 2-pole generator)
P0, T0, M0 = 16.7e6, 538.0 + 273.15, 1800.0 / 3.6  # Pa, K, kg/s (heat balance, see TOML)
VALVE_DROP = 0.03
P_EXHAUST = 3.90e6
STAGES = 12
EXTRACTION_AFTER, EXTRACTION_FLOW = 8, 120.0 / 3.6  # HP heater 1 bleed, kg/s
CONTROL_DIAMETER = 1.10  # m
CONTROL_VELOCITY_RATIO = 0.46  # u/c0 slightly below the impulse optimum (~0.50)
CONTROL_EFFICIENCY = 0.74  # partial-admission impulse stage at rated load (Cotton 1998, ch. 6)
STAGE_EFFICIENCY = 0.90  # HP reaction stages (Cotton 1998; Traupel 2001)
ROOT_DIAMETER = 0.86  # m, HP drum root diameter
REACTION, ALPHA1 = 0.3, math.radians(16.0)


def prop(out: str, a: str, x: float, b: str, y: float) -> float:
    return CP.PropsSI(out, a, x, b, y, FLUID)


def expand(p1: float, h1: float, nu: float, heights: list[float]) -> list[dict[str, float]]:
    """March the pressure stages at a common velocity ratio ``nu`` with the given blade heights."""
    rows, p_in, h_in, flow = [], p1, h1, M0
    for stage, height in enumerate(heights, start=1):
        diameter = ROOT_DIAMETER + height
        dh_s = 0.5 * (SPEED * diameter / 2 / nu) ** 2
        s_in = prop("S", "P", p_in, "H", h_in)
        lo, hi = 0.2 * p_in, p_in
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if h_in - prop("H", "P", mid, "S", s_in) > dh_s else (lo, mid)
        p_out = 0.5 * (lo + hi)
        h_out = h_in - STAGE_EFFICIENCY * dh_s
        v_in = 1 / prop("D", "P", p_in, "H", h_in)
        v_out = 1 / prop("D", "P", p_out, "H", h_out)
        c1 = math.sqrt(2 * (1 - REACTION) * dh_s)
        rows.append({
            "p_in": p_in, "p_out": p_out, "h_out": h_out, "flow": flow, "dh": h_in - h_out,
            "capacity": flow / math.sqrt((p_in**2 - p_out**2) / (p_in * v_in)),
            "diameter": diameter, "T_out": prop("T", "P", p_out, "H", h_out),
            "height": flow * v_out / (math.pi * diameter * c1 * math.sin(ALPHA1)),
        })
        if stage == EXTRACTION_AFTER:
            flow -= EXTRACTION_FLOW
        p_in, h_in = p_out, h_out
    return rows


def main() -> None:
    h0 = prop("H", "P", P0, "T", T0)
    pv = P0 * (1 - VALVE_DROP)
    s0 = prop("S", "P", pv, "H", h0)
    u_cs = SPEED * CONTROL_DIAMETER / 2
    dh_cs = 0.5 * (u_cs / CONTROL_VELOCITY_RATIO) ** 2
    # control-stage outlet pressure where the isentropic drop equals dh_cs (bisection)
    lo, hi = 0.3 * pv, pv
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        drop = h0 - prop("H", "P", mid, "S", s0)
        lo, hi = (mid, hi) if drop > dh_cs else (lo, mid)
    p1 = 0.5 * (lo + hi)
    h1 = h0 - CONTROL_EFFICIENCY * dh_cs
    print(f"control stage: u={u_cs:.1f} m/s dh_s={dh_cs / 1e3:.1f} kJ/kg p1={p1 / 1e6:.4f} MPa "
          f"T1={prop('T', 'P', p1, 'H', h1) - 273.15:.1f} degC")
    heights = [0.10] * STAGES
    for _ in range(6):  # blade heights and the common velocity ratio converge together
        lo, hi = 0.3, 1.2
        for _ in range(60):  # bisection on the common velocity ratio u/c0 of the pressure stages
            nu = 0.5 * (lo + hi)
            p_end = expand(p1, h1, nu, heights)[-1]["p_out"]
            lo, hi = (nu, hi) if p_end < P_EXHAUST else (lo, nu)
        rows = expand(p1, h1, nu, heights)
        heights = [row["height"] for row in rows]
    power = M0 * (h0 - h1)
    for stage, row in enumerate(rows, start=1):
        power += row["flow"] * row["dh"]
        print(f"stage {stage:2d}: p_in={row['p_in'] / 1e6:.4f} MPa K={row['capacity']:.4g} m2 "
              f"D={row['diameter']:.4f} m l={row['height'] * 1e3:.1f} mm u/c0={nu:.3f} "
              f"T_out={row['T_out'] - 273.15:.1f} degC")
        if stage == EXTRACTION_AFTER:
            print(f"  extraction at {row['p_out'] / 1e6:.4f} MPa")
    p_in, h_in = rows[-1]["p_out"], rows[-1]["h_out"]
    t_ex = prop("T", "P", p_in, "H", h_in)
    print(f"exhaust: {p_in / 1e6:.3f} MPa {t_ex - 273.15:.2f} degC, HP power {power / 1e6:.2f} MW")


if __name__ == "__main__":
    main()
