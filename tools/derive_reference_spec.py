"""Print the stage table of the built-in reference unit (src/steamtwin/spec/data/reference.toml).

The reference unit's table predates ``steamtwin turbine derive`` and was laid out with a fixed
HP drum root diameter (0.86 m) and a fixed stage efficiency (0.90), the common velocity ratio
solved so that the expansion ends at the HP-exhaust pressure. This script reproduces it with the
package's own expansion, :func:`steamtwin.spec.derive.expand_pressure_stages` (IAPWS-IF97,
Stodola capacities, blade heights from continuity). ``steamtwin turbine derive`` generalises it:
it solves the root diameter and the stage efficiency at a common u/c0 of 0.642 instead, and on a
heat balance written from this unit's figures gives the same table within 0.1 %
(tests/spec/test_derive.py). Run ``python tools/derive_reference_spec.py``.
"""

from __future__ import annotations

import math

from steamtwin.spec.derive import expand_pressure_stages
from steamtwin.steam import if97

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


def main() -> None:
    h0 = float(if97.enthalpy_pt(P0, T0))
    s0 = float(if97.entropy_ph(P0 * (1 - VALVE_DROP), h0))
    u_cs = SPEED * CONTROL_DIAMETER / 2
    dh_cs = 0.5 * (u_cs / CONTROL_VELOCITY_RATIO) ** 2
    lo, hi = 0.3 * P0, P0 * (1 - VALVE_DROP)
    for _ in range(60):  # control-stage pressure where the isentropic drop is dh_cs
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if h0 - float(if97.enthalpy_ps(mid, s0)) > dh_cs else (lo, mid)
    p1, h1 = 0.5 * (lo + hi), h0 - CONTROL_EFFICIENCY * dh_cs
    print(f"control stage: u={u_cs:.1f} m/s dh_s={dh_cs / 1e3:.1f} kJ/kg p1={p1 / 1e6:.4f} MPa "
          f"T1={float(if97.temperature_ph(p1, h1)) - 273.15:.1f} degC")
    flows = [M0 if stage <= EXTRACTION_AFTER else M0 - EXTRACTION_FLOW
             for stage in range(1, STAGES + 1)]
    lo, hi = 0.4, 1.0
    for _ in range(40):  # the common velocity ratio u/c0 ending the expansion at P_EXHAUST
        nu = 0.5 * (lo + hi)
        rows = expand_pressure_stages(p1, h1, flows, SPEED, ROOT_DIAMETER, nu, STAGE_EFFICIENCY,
                                      floor_pressure_pa=0.3 * P_EXHAUST)
        lo, hi = (nu, hi) if rows is not None and rows[-1].outlet_pressure_pa < P_EXHAUST \
            else (lo, nu)
    power = M0 * (h0 - h1)
    for stage, row in enumerate(rows or [], start=1):
        power += row.flow_kg_s * (row.inlet_enthalpy_j_kg - row.outlet_enthalpy_j_kg)
        print(f"stage {stage:2d}: p_in={row.inlet_pressure_pa / 1e6:.4f} MPa "
              f"K={row.flow_capacity_m2:.4g} m2 D={row.mean_diameter_m:.4f} m "
              f"l={row.blade_height_m * 1e3:.1f} mm u/c0={nu:.3f}")
    end = (rows or [])[-1]
    t_ex = float(if97.temperature_ph(end.outlet_pressure_pa, end.outlet_enthalpy_j_kg))
    print(f"exhaust: {end.outlet_pressure_pa / 1e6:.3f} MPa {t_ex - 273.15:.2f} degC, "
          f"HP power {power / 1e6:.2f} MW")


if __name__ == "__main__":
    main()
