"""Steam-side boundary conditions of the control-stage rotor blade, from the FOM's state.

**Velocity triangles** (mean line; Dixon & Hall, *Fluid Mechanics and Thermodynamics of
Turbomachinery*, 7th ed., 2014, ch. 4). The wide-open nozzle groups expand from the valve outlet
p_v = p0·(1 − valve loss) at the throttle enthalpy h0 to the control-stage pressure p1 (the FOM's
state); isentropic drop Δh_s = h0 − h(p1, s(p_v, h0)). The nozzle takes the share (1 − R):
c1 = φ·sqrt(2·(1 − R)·Δh_s), nozzle velocity coefficient φ = 0.97 (0.95–0.98 for steam nozzles,
Traupel, *Thermische Turbomaschinen* Bd. 1, 2001, §3). With α1 measured from the plane of
rotation (as the FOM's ν_opt = cos α1/2): w1 = sqrt(c1² + u² − 2·u·c1·cos α1), u = ω·d/2; the
blade exit velocity w2 = ψ·sqrt(w1² + 2·R·Δh_s), rotor velocity coefficient ψ = 0.90 (0.85–0.95
for impulse blading, Traupel §3; Kang et al., *Principles of Steam Turbines*, §1). The
relative total enthalpy h_w = h0 − c1²/2 + w1²/2 is constant through the row at constant radius
(rothalpy).

**Recovery temperature.** The wall sees the adiabatic-wall temperature h_aw = h_w − (1 − r)·w²/2,
r = 1 at the stagnation line, r = Pr^(1/3) under a turbulent boundary layer (Schlichting &
Gersten, *Boundary-Layer Theory*, 8th ed., 2000, §22.3; Kays & Crawford, *Convective Heat and
Mass Transfer*, 3rd ed., 1993, ch. 16); w = w1 on the leading edge, the mean (w1 + w2)/2
elsewhere. (Incropera & DeWitt below: *Fundamentals of Heat and Mass Transfer*, 6th ed., 2007.)

**Heat-transfer coefficients**, properties at the free-stream static state (IAPWS, via
``steamtwin.steam.if97``), multiplied by the calibrated ``heat_transfer_coefficient``:

* leading edge, Frössling's cylinder stagnation solution (Hiemenz flow):
  Nu_D = 1.14·Re_D^0.5·Pr^0.4·(1 − (θ/90°)³), θ ≤ 80° from the stagnation line (Frössling,
  NACA TM 1432, 1958; in this form Kreith, Manglik & Bohn, *Principles of Heat Transfer*,
  7th ed., 2011, ch. 7, cylinder in cross flow). D = 2·s/π from the LE region's arc length s
  (its area over its span) — a semicircular leading edge; θ between a facet's outward normal and
  the LE's mean normal (stagnation on the mean-line LE, zero incidence assumed);
* pressure and suction sides, trailing edge and tip: turbulent flat plate from the stagnation
  line, Nu_x = 0.0296·Re_x^0.8·Pr^(1/3) (Incropera & DeWitt eq. 7.36, 0.6 < Pr < 60), turbulent
  from the leading edge since free-stream turbulence of a governing stage bypasses transition
  (Mayle, J. Turbomach. 113 (1991) 509–537); x = π·D/4 (stagnation line to the LE shoulder) plus
  the distance to the nearest LE point. Past the shoulder the turbulent layer's h exceeds the
  stagnation value, as on a cylinder above Re_D ≈ 2e5 (Incropera & DeWitt Fig. 7.9).

**Partial admission.** A control-stage blade runs through the admitting arc (share e, the FOM's
``active_admission_arc``) and the idle arc once per revolution (50 Hz). The periodic penetration
depth sqrt(2·a/ω) = 0.2 mm (a = k/(ρc) ≈ 7e-6 m²/s) is far below the blade thickness (Carslaw &
Jaeger 1959, ch. II, periodic surface temperature), so the blade feels the cycle-averaged condition:
h = e·h_a + (1 − e)·h_i, T_f = (e·h_a·T_a + (1 − e)·h_i·T_i)/h. In the idle arc the blade stirs
wheel-chamber steam at the FOM's control-stage state, relative velocity (1 − 0.5)·u (core swirl
ratio 0.5, as ``steamtwin.model.metal``).

**Root.** The root conducts into the rotor rim: a contact conductance h_c = 1.0e4 W/(m²·K)
(metal interfaces at ~10 MPa contact pressure: R″ = 0.7–4.0e-4 m²·K/W, Incropera & DeWitt
Table 3.1, steam in the gaps improving on vacuum) to the rim, whose temperature is the
wheel-chamber steam temperature (the FOM's control-stage temperature): the rotor has no other
heat sink, so at steady state its rim sits at the surrounding steam temperature. In transients
the rim follows that temperature at once (the rim's lag is not modelled).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pandas as pd
from scipy.spatial import cKDTree

from steamtwin.blade.conduction import BladeConduction, Convection
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters
from steamtwin.spec import TurbineSpec
from steamtwin.steam import if97

NOZZLE_VELOCITY_COEFFICIENT = 0.97  # φ, Traupel §3
ROTOR_VELOCITY_COEFFICIENT = 0.90  # ψ, Traupel §3; Kang et al.
FROESSLING_CONSTANT = 1.14  # Frössling; Kreith, Manglik & Bohn ch. 7
FROESSLING_MAX_ANGLE = 80.0  # deg, validity of the (1 − (θ/90)³) law
FLAT_PLATE_CONSTANT = 0.0296  # Incropera & DeWitt eq. 7.36
IDLE_SWIRL_RATIO = 0.5  # core swirl of the wheel chamber (Owen & Rogers 1989)
ROOT_CONTACT_CONDUCTANCE = 1.0e4  # W/(m²·K), Incropera & DeWitt Table 3.1

STATE_FIELDS = ("main_steam_pressure", "main_steam_temperature", "main_steam_flow",
                "hp_exhaust_pressure", "control_stage_pressure", "control_stage_temperature",
                "active_admission_arc")


@dataclass(frozen=True)
class ControlStageState:
    """The FOM's state at the governing stage for one condition (SI: Pa, K, kg/s, -)."""

    main_steam_pressure: float
    main_steam_temperature: float
    main_steam_flow: float
    hp_exhaust_pressure: float
    control_stage_pressure: float
    control_stage_temperature: float
    active_admission_arc: float


def control_stage_states(model: FullOrderModel, inputs: pd.DataFrame,
                         params: ModelParameters | None = None
                         ) -> tuple[list[ControlStageState], pd.DataFrame]:
    """Run the FOM on ``inputs`` (SI); the governing-stage state and the sensor outputs per row."""
    result = model.simulate_detailed(inputs, params, stages=False)
    diagnostics = result.diagnostics
    states = [
        ControlStageState(
            main_steam_pressure=float(inputs["main_steam_pressure"].iloc[i]),
            main_steam_temperature=float(inputs["main_steam_temperature"].iloc[i]),
            main_steam_flow=float(inputs["main_steam_flow"].iloc[i]),
            hp_exhaust_pressure=float(inputs["hp_exhaust_pressure"].iloc[i]),
            control_stage_pressure=float(diagnostics["control_stage_pressure"].iloc[i]),
            control_stage_temperature=float(diagnostics["control_stage_temperature"].iloc[i]),
            active_admission_arc=float(diagnostics["active_admission_arc"].iloc[i]),
        )
        for i in range(len(inputs))
    ]
    return states, result.outputs


@dataclass(frozen=True)
class VelocityTriangles:
    """Mean-line velocities (m/s), enthalpies (J/kg) and states of the control-stage rotor."""

    blade_speed: float
    nozzle_velocity: float  # c1
    inlet_relative_velocity: float  # w1
    exit_relative_velocity: float  # w2
    inlet_relative_angle: float  # β1, rad from the plane of rotation
    static_enthalpy: float  # h1 at the rotor inlet
    relative_total_enthalpy: float  # h_w


def velocity_triangles(spec: TurbineSpec, state: ControlStageState) -> VelocityTriangles:
    """Velocity triangles of the admitting arc from the spec's blading and the FOM state."""
    blading = spec.control_stage.blading
    p_valve = state.main_steam_pressure * (1.0 - spec.design.valve_pressure_drop)
    h0 = float(if97.enthalpy_pt(state.main_steam_pressure, state.main_steam_temperature))
    s_valve = float(if97.entropy_ph(p_valve, h0))
    drop = max(h0 - float(if97.enthalpy_ps(state.control_stage_pressure, s_valve)), 0.0)
    c1 = NOZZLE_VELOCITY_COEFFICIENT * math.sqrt(2.0 * (1.0 - blading.reaction) * drop)
    u = spec.design.rotational_speed * blading.mean_diameter / 2.0
    alpha = blading.nozzle_exit_angle
    w1x, w1y = c1 * math.sin(alpha), c1 * math.cos(alpha) - u
    w1 = math.hypot(w1x, w1y)
    w2 = ROTOR_VELOCITY_COEFFICIENT * math.sqrt(w1 * w1 + 2.0 * blading.reaction * drop)
    h1 = h0 - 0.5 * c1 * c1
    return VelocityTriangles(
        blade_speed=u, nozzle_velocity=c1, inlet_relative_velocity=w1,
        exit_relative_velocity=w2, inlet_relative_angle=math.atan2(w1x, w1y),
        static_enthalpy=h1, relative_total_enthalpy=h1 + 0.5 * w1 * w1,
    )


@dataclass(frozen=True)
class SteamStream:
    """Free stream seen by the blade: static temperature K, velocity m/s, properties (SI)."""

    pressure: float
    static_temperature: float
    relative_total_temperature: float
    leading_edge_velocity: float
    surface_velocity: float
    density: float
    viscosity: float
    conductivity: float
    heat_capacity: float

    @property
    def prandtl(self) -> float:
        """Prandtl number (-)."""
        return self.heat_capacity * self.viscosity / self.conductivity

    def recovery_temperature(self, velocity: float) -> float:
        """Adiabatic-wall temperature (K) under a turbulent layer at ``velocity``: r = Pr^(1/3)."""
        recovery = self.prandtl ** (1.0 / 3.0)
        return self.static_temperature + recovery * velocity**2 / (2.0 * self.heat_capacity)


def _stream(pressure: float, static_temperature: float, relative_total_temperature: float,
            leading_edge_velocity: float, surface_velocity: float) -> SteamStream:
    return SteamStream(
        pressure=pressure, static_temperature=static_temperature,
        relative_total_temperature=relative_total_temperature,
        leading_edge_velocity=leading_edge_velocity, surface_velocity=surface_velocity,
        density=1.0 / float(if97.specific_volume_pt(pressure, static_temperature)),
        viscosity=float(if97.viscosity_pt(pressure, static_temperature)),
        conductivity=float(if97.thermal_conductivity_pt(pressure, static_temperature)),
        heat_capacity=float(if97.isobaric_heat_capacity_pt(pressure, static_temperature)),
    )


def admitting_stream(spec: TurbineSpec, state: ControlStageState) -> SteamStream:
    """Steam of the admitting arc in the blade frame (properties at p1 and the inlet static T)."""
    triangles = velocity_triangles(spec, state)
    p1 = state.control_stage_pressure
    static = float(if97.temperature_ph(p1, triangles.static_enthalpy))
    total = float(if97.temperature_ph(p1, triangles.relative_total_enthalpy))
    mean = 0.5 * (triangles.inlet_relative_velocity + triangles.exit_relative_velocity)
    return _stream(p1, static, total, triangles.inlet_relative_velocity, mean)


def idle_stream(spec: TurbineSpec, state: ControlStageState) -> SteamStream:
    """Wheel-chamber steam of the idle arc, stirred at (1 − swirl ratio)·u."""
    u = spec.design.rotational_speed * spec.control_stage.blading.mean_diameter / 2.0
    velocity = (1.0 - IDLE_SWIRL_RATIO) * u
    static = state.control_stage_temperature
    p1 = state.control_stage_pressure
    cp = float(if97.isobaric_heat_capacity_pt(p1, static))
    return _stream(p1, static, static + velocity**2 / (2.0 * cp), velocity, velocity)


def froessling_htc(stream: SteamStream, diameter: float, angle_deg: np.ndarray) -> np.ndarray:
    """Cylinder stagnation-region h (W/(m²·K)) at ``angle_deg`` from the stagnation line."""
    theta = np.minimum(np.asarray(angle_deg, dtype=float), FROESSLING_MAX_ANGLE)
    reynolds = stream.density * stream.leading_edge_velocity * diameter / stream.viscosity
    nusselt = (FROESSLING_CONSTANT * math.sqrt(reynolds) * stream.prandtl**0.4
               * (1.0 - (theta / 90.0) ** 3))
    return nusselt * stream.conductivity / diameter


def flat_plate_htc(stream: SteamStream, distance: np.ndarray) -> np.ndarray:
    """Local turbulent flat-plate h (W/(m²·K)) at ``distance`` (m) from the stagnation line."""
    x = np.asarray(distance, dtype=float)
    reynolds = stream.density * stream.surface_velocity * x / stream.viscosity
    nusselt = FLAT_PLATE_CONSTANT * reynolds**0.8 * stream.prandtl ** (1.0 / 3.0)
    return nusselt * stream.conductivity / x


class SteamBoundary:
    """Turns a :class:`ControlStageState` into the blade's convection ``{region: (h, T_f)}``.

    The geometric inputs of the correlations (LE diameter, stagnation angles, distances from
    the stagnation line) are derived from the mesh once, on first use.
    """

    def __init__(self, conduction: BladeConduction, spec: TurbineSpec) -> None:
        self.conduction = conduction
        self.spec = spec

    @cached_property
    def leading_edge_diameter(self) -> float:
        """D = 2·s/π (m), s = LE area / radial span: the LE as a semicircle."""
        quadrature = self.conduction.quadrature("leading_edge")
        area = float(quadrature.weights.sum())
        radial = quadrature.points[2]
        span = float(radial.max() - radial.min())
        if span <= 0.0:
            raise ValueError("the leading_edge region has no radial extent")
        return 2.0 * (area / span) / math.pi

    @cached_property
    def stagnation_angle(self) -> np.ndarray:
        """Angle (deg) of each LE quadrature point's normal from the LE's mean normal."""
        quadrature = self.conduction.quadrature("leading_edge")
        normals = quadrature.normals
        mean = np.einsum("cfq,fq->c", normals, quadrature.weights)
        mean /= np.linalg.norm(mean)
        cosine = np.clip(np.einsum("cfq,c->fq", normals, mean), -1.0, 1.0)
        return np.degrees(np.arccos(cosine))

    @cached_property
    def surface_distance(self) -> dict[str, np.ndarray]:
        """Distance (m) from the stagnation line of each non-LE, non-root quadrature point."""
        le_points = self.conduction.quadrature("leading_edge").points.reshape(3, -1).T
        tree = cKDTree(le_points)
        shoulder = math.pi * self.leading_edge_diameter / 4.0
        distances = {}
        for region in self.conduction.regions:
            if region in ("leading_edge", "root"):
                continue
            points = self.conduction.quadrature(region).points
            nearest, _ = tree.query(points.reshape(3, -1).T)
            distances[region] = shoulder + nearest.reshape(points.shape[1:])
        return distances

    def _arc(self, stream: SteamStream) -> Convection:
        diameter = self.leading_edge_diameter
        le_htc = froessling_htc(stream, diameter, self.stagnation_angle)
        # full recovery (r = 1) at the stagnation line: the relative total temperature
        le_temperature = np.full_like(le_htc, stream.relative_total_temperature)
        convection = {"leading_edge": (le_htc, le_temperature)}
        side_temperature = stream.recovery_temperature(stream.surface_velocity)
        for region, distance in self.surface_distance.items():
            htc = flat_plate_htc(stream, distance)
            convection[region] = (htc, np.full_like(htc, side_temperature))
        return convection

    def convection(self, state: ControlStageState, params: ModelParameters | None = None
                   ) -> Convection:
        """Cycle-averaged convection of all regions (h W/(m²·K), T_f K) for one state."""
        multiplier = (params or ModelParameters()).heat_transfer_coefficient
        arc = float(np.clip(state.active_admission_arc, 0.0, 1.0))
        active = self._arc(admitting_stream(self.spec, state))
        idle = self._arc(idle_stream(self.spec, state))
        convection: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for region, (h_a, t_a) in active.items():
            h_i, t_i = idle[region]
            htc = arc * h_a + (1.0 - arc) * h_i
            fluid = (arc * h_a * t_a + (1.0 - arc) * h_i * t_i) / htc
            convection[region] = (multiplier * htc, fluid)
        if "root" in self.conduction.regions:
            convection["root"] = (ROOT_CONTACT_CONDUCTANCE, state.control_stage_temperature)
        return convection
