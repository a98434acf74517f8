"""Steam-side boundary conditions of the rotor FEM per metal group, from the full-order model.

For each metal group and sample: the group's mean steam temperature (K) and the rotor
heat-transfer coefficient (W/(m²·K)) exactly as the FOM's kernel forms them for its 1-D rotor
(:mod:`steamtwin.model.metal`): Dittus–Boelter, Nu = 0.023·Re^0.8·Pr^n (Dittus & Boelter, Univ.
Calif. Publ. Eng. 2 (1930) 443; Incropera & DeWitt, eq. 8.60) on the blade-path annulus
(hydraulic diameter 2·blade height), with the velocity relative to the rotor — the vector sum
of the axial velocity m·v/(π·d·l) and the core swirl (half the rotor surface speed, Owen &
Rogers 1989) — times the calibrated multiplier ``ModelParameters.heat_transfer_coefficient``.
Annulus, hydraulic diameter and surface speed are the kernel's own constants
(``FullOrderModel.design_.kernel.metal``), so the rotor FEM sees the coefficient the
calibration tuned.

The group's steam state is the kernel's: the control stage's outlet state for the control
stage; for a group of pressure stages the state at the geometric-mean pressure of its inlet and
outlet and the mean of their enthalpies. The FOM reports stage-outlet states after the metal's
heat exchange (the kernel takes the outlet before it; the difference is the metal heat over the
flow, under 1 K at the reference unit's fastest ramps). The group's mass flow is the kernel's:
throttle flow less the bleeds and leakages that leave before the group's last stage; the
leakages' total (a FOM diagnostic) is shared among them by their design flows. Steam properties:
IAPWS-IF97 and the IAPWS 2008/2011 transport properties (:mod:`steamtwin.steam.if97`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from steamtwin.errors import RotorAreaError
from steamtwin.model.design import active_leakages
from steamtwin.model.fom import FullOrderModel, SimulationResult
from steamtwin.model.metal import dittus_boelter_htc, rotor_relative_velocity
from steamtwin.model.parameters import ModelParameters
from steamtwin.rotor.conduction import cooling_factor_column, htc_column, steam_temperature_column
from steamtwin.steam import if97


def group_flows(fom: FullOrderModel, inputs: pd.DataFrame, run: SimulationResult
                ) -> np.ndarray:
    """Mass flow (kg/s) past each metal group's rotor as the kernel takes it, (samples, groups)."""
    spec = fom.spec
    throttle = inputs["main_steam_flow"].to_numpy(dtype=float)
    leakages = active_leakages(spec)
    total_design = sum(leak.design_flow for leak in leakages)
    leak_total = (run.diagnostics["leakage_flow"].to_numpy(dtype=float)
                  if leakages and run.diagnostics is not None else np.zeros(throttle.size))
    flows = np.empty((throttle.size, len(spec.metal_groups)))
    for g, group in enumerate(spec.metal_groups):
        last = group.stages[-1]
        if last == 0:  # the control stage passes the throttle flow
            flows[:, g] = throttle
            continue
        bled = sum(e.design_flow for e in spec.extractions if e.after_stage < last)
        leaked = sum(leak.design_flow for leak in leakages if leak.from_stage < last)
        flows[:, g] = (throttle * (1.0 - bled / spec.design.main_steam_flow)
                       - (leak_total * leaked / total_design if leaked else 0.0))
    return flows


def group_steam_states(fom: FullOrderModel, run: SimulationResult
                       ) -> tuple[np.ndarray, np.ndarray]:
    """(pressure Pa, temperature K) of each metal group's mean steam, (samples, groups)."""
    if run.stage_pressures is None or run.stage_temperatures is None:
        raise RotorAreaError("the FOM run has no stage states: simulate_detailed(..., "
                             "stages=True)")
    p, t = run.stage_pressures.to_numpy(dtype=float), run.stage_temperatures.to_numpy(dtype=float)
    groups = fom.spec.metal_groups
    pressure, temperature = np.empty((p.shape[0], len(groups))), np.empty((p.shape[0], len(groups)))
    for g, group in enumerate(groups):
        first, last = group.stages[0], group.stages[-1]
        if first == 0:
            pressure[:, g], temperature[:, g] = p[:, 0], t[:, 0]
            continue
        inlet, outlet = first - 1, last
        pressure[:, g] = np.sqrt(p[:, inlet] * p[:, outlet])
        enthalpy = 0.5 * (if97.enthalpy_pt(p[:, inlet], t[:, inlet])
                          + if97.enthalpy_pt(p[:, outlet], t[:, outlet]))
        temperature[:, g] = if97.temperature_ph(pressure[:, g], enthalpy)
    return pressure, temperature


def steam_side(fom: FullOrderModel, inputs: pd.DataFrame, params: ModelParameters | None = None,
               groups: Sequence[str] | None = None, run: SimulationResult | None = None
               ) -> pd.DataFrame:
    """Per-group steam temperature (K) and rotor htc (W/(m²·K)) over ``inputs`` (the FOM's SI
    input frame), as :func:`~steamtwin.rotor.conduction.steam_temperature_column` and
    :func:`~steamtwin.rotor.conduction.htc_column` columns on the inputs' index.

    ``groups``: the metal groups to give (default all); ``run``: the FOM's
    ``simulate_detailed(inputs, params, stages=True)`` if already at hand. The htc is the one
    for steam heating the rotor (Dittus–Boelter's Prandtl exponent 0.3); the
    :func:`~steamtwin.rotor.conduction.cooling_factor_column` holds Pr^0.1, the factor to the
    exponent 0.4 of a rotor heating the steam, which the conduction solver applies per step
    from the rotor's surface temperature as the FOM's kernel does (1–4 % for superheated steam).
    """
    params = params or ModelParameters()
    names = [group.name for group in fom.spec.metal_groups]
    wanted = list(names if groups is None else groups)
    unknown = [name for name in wanted if name not in names]
    if unknown:
        raise RotorAreaError(f"metal groups {unknown} are not in the turbine spec "
                             f"(its groups: {names})")
    if run is None:
        run = fom.simulate_detailed(inputs, params, stages=True)
    pressure, temperature = group_steam_states(fom, run)
    flows = group_flows(fom, inputs, run)
    metal = fom.design_.kernel.metal
    columns: dict[str, np.ndarray] = {}
    for name in wanted:
        g = names.index(name)
        p, t = pressure[:, g], temperature[:, g]
        v = if97.specific_volume_pt(p, t)
        viscosity, conductivity = if97.viscosity_pt(p, t), if97.thermal_conductivity_pt(p, t)
        heat_capacity = if97.isobaric_heat_capacity_pt(p, t)
        axial = flows[:, g] * v / metal.flow_area[g]
        htc = np.array([dittus_boelter_htc(
            rotor_relative_velocity(axial[i], metal.rotor_speed[g]), metal.hydraulic_diameter[g],
            v[i], viscosity[i], conductivity[i], heat_capacity[i], False)
            for i in range(t.size)])
        columns[steam_temperature_column(name)] = t
        columns[htc_column(name)] = params.heat_transfer_coefficient * htc
        # Pr^(0.4 − 0.3): Dittus–Boelter with the rotor heating the steam over the steam heating it
        columns[cooling_factor_column(name)] = (heat_capacity * viscosity / conductivity) ** 0.1
    return pd.DataFrame(columns, index=inputs.index)
