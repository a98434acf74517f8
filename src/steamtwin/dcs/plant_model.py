"""The virtual plant as a model: its hidden truth, its own structure and its steady states.

Kept as one module because the truth and the structure it sets refer to each other:
:attr:`PlantTruth.twin_equivalent` runs the plant's own model (:class:`PlantModel`, built from
the truth's structure) to its steady states. The run through a scenario and the instruments,
and the historian files, are in :mod:`steamtwin.dcs.plant`.

Demos and tests need DCS data that look like a real unit's, but data made by the twin's own model
structure would let calibration rediscover its own assumptions. The virtual plant therefore runs
the full-order model (FOM) with hidden parameters *and* a deliberately different structure, then
records the result through the instrument models of :mod:`steamtwin.dcs.sensors`.

Hidden truth (:class:`PlantTruth`, written to ``truth/`` only, never to the historian files):
``flow_coefficient`` 0.965 (deposits), ``friction_coefficient`` 1.3 (rough blading),
``heat_transfer_coefficient`` 1.4 (better than the Dittus–Boelter correlation).

Structural differences from the twin (items 3 and 4, the boiler dynamics and the instruments,
are applied by :func:`steamtwin.dcs.plant.run_plant`)
    1. **Finer metal discretisation.** One metal group per stage (the control stage alone; each
       reference group's casing and rotor mass and wetted area split evenly over its stages)
       and 16 finite volumes per conduction chain instead of 8 (:class:`PlantModel`).
    2. **HP front gland leakage.** A share λ of the measured main-steam flow leaks from the
       control-stage chamber past the HP front-gland labyrinth to the cold-reheat line and never
       reaches the pressure stages: the plant runs the FOM with the stage flow m·(1 − λ) while
       the DCS measures m. The leakage follows Martin's labyrinth formula
       ``m_leak = A·sqrt(p1/v1)·sqrt((1 − (p2/p1)²)/(z − ln(p2/p1)))`` (Martin 1908; Traupel,
       *Thermische Turbomaschinen* Bd. 1, §9 Labyrinthdichtungen; Stodola 1927), i.e. ∝ p1/√T1
       at a given pressure ratio, with p1, T1 the control-stage state, p2 the HP-exhaust
       pressure and z = :data:`GLAND_TEETH` throttlings; the area A is set so that λ =
       :attr:`PlantTruth.gland_leakage_rated` (1.5 %) at the rated point. λ depends on the
       plant's own p1, so the FOM runs twice (fixed-point pass; the second pass changes λ by
       well under 0.1 % of flow).
    3.–4. Boiler dynamics and instruments: :mod:`steamtwin.dcs.plant`.
    5. **Tip leakage over the blade shrouds** of every pressure stage, from a radial clearance
       per group of stages (:attr:`PlantTruth.tip_clearances`), by the shrouded-blade leakage
       of Traupel (*Thermische Turbomaschinen* Bd. 1, §8.5; also Denton, J. Turbomach. 115
       (1993) 621–656, §7): the rotor's share r·Δh of the stage drop drives steam through the
       shroud labyrinth (z = :data:`TIP_SEAL_STRIPS` strips, discharge coefficient μ =
       :data:`TIP_DISCHARGE_COEFFICIENT`), the stage's own flow through its nozzle exit area
       π·D·ℓ·sin α₁ at c₁ = sqrt(2(1 − r)Δh), so that the bypassed share is
       ``λ = μ·(D + ℓ)·δ/(D·ℓ·sin α₁)·sqrt(r/(z·(1 − r)))`` (:func:`tip_leakage_fractions`),
       independent of load at equal densities; it does no work in the blading. The design
       efficiency scale is solved *without* it: the heat balance is the as-designed unit, the
       clearances the as-found ones, so the plant's HP efficiency sits below its heat balance.
    6. **Governing valves with overlap and a poppet-valve characteristic.** The next valve starts
       to lift when the previous is :attr:`PlantTruth.valve_overlap` short of full lift; each
       valve's flow share follows its curtain area π·d·L and seat area π·d²/4 in series
       (:func:`poppet_valve_characteristic`), a quick-opening, non-linear law (the twin's spec
       stays sequential and linear). The control stage's lift schedule is the kernel's.
    7. **Boiler temperature schedule.** Main-steam and hot-reheat temperatures hold their rated
       538 °C down to a control point and fall below it (:attr:`PlantTruth.main_steam_schedule`,
       :attr:`PlantTruth.reheat_schedule`; Cotton, *Evaluating and Improving Steam Turbine
       Performance*, 1998, ch. 2): 520 °C main steam at 30 %; the lower reheat temperature
       lowers the HP-exhaust pressure by sqrt(T_rh/T_rh,rated) (Stodola's cone law of the IP).
    8. **Casing thermocouple depth** :attr:`PlantTruth.casing_thermocouple_depth` (20 mm) in a
       casing wall graded from the bore (first volume ≈ 2.6 mm, growth
       :data:`PLANT_GRID_STRETCH`), against the twin's 14 mm in uniform volumes.
    9. **Rotor conduction with a bore.** Each rotor is a hollow cylinder with a central bore of
       radius :attr:`PlantTruth.rotor_bore_radius` (adiabatic), the same mass and wetted area
       as the spec's solid rotor (so a larger outer radius), in radially graded volumes with the
       exact conductances of cylindrical shells, 2πkL/ln(r₁/r₂) (Incropera & DeWitt,
       *Fundamentals of Heat and Mass Transfer*, §3.3), against the twin's uniform solid chain.

Generator output (``load``, W) is an approximation from the HP blading power:
``load = P_HP / s − P_loss`` with a constant HP share ``s = P_HP,rated / (P_gen,rated + P_loss)``
of the internal power (reference heat balance: 177.3 MW HP of 600 MW) and a load-independent
mechanical plus generator loss ``P_loss`` = :data:`FIXED_LOSS_W` (6 MW, 1 % of rating: bearings,
windage, generator iron losses; Cotton 1998 ch. 2). With sliding pressure the HP pressure ratio
stays nearly constant, so a constant HP share is a fair first approximation; it is not a heat
balance of the IP/LP sections.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from functools import cached_property, lru_cache
from itertools import pairwise
from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from steamtwin.dcs.sensors import (
    FaultConfig,
)
from steamtwin.model.design import DesignConstants, kernel_constants
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.kernel import KernelConstants
from steamtwin.model.operating import operating_point
from steamtwin.model.parameters import PARAMETER_BOUNDS, ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.progress import ProgressCallback
from steamtwin.spec import ControlStage, Material, MetalGroup, TurbineSpec, load_spec
from steamtwin.spec.turbine import DEFAULT_CASING_THERMOCOUPLE_DEPTH

__all__ = [
    "FIXED_LOSS_W",
    "GLAND_TEETH",
    "PLANT_GRID_STRETCH",
    "PLANT_METAL_NODES",
    "START",
    "TIP_DISCHARGE_COEFFICIENT",
    "TIP_SEAL_STRIPS",
    "TWIN_EQUIVALENT_LOADS",
    "ParameterDrift",
    "PlantModel",
    "PlantTruth",
    "boiler_temperature",
    "bored_rotor",
    "casing_reading_position",
    "generator_power",
    "gland_leakage_fraction",
    "graded_wall",
    "plant_constants",
    "plant_model",
    "plant_spec",
    "plant_steady_states",
    "poppet_valve_characteristic",
    "rated_state",
    "run_leaking",
    "steady_boundary",
    "tip_leakage_fractions",
    "twin_equivalent_parameters",
]

PLANT_METAL_NODES = 16
"""Finite volumes per metal conduction chain in the plant (the twin uses 8)."""
GLAND_TEETH = 24
"""Throttlings z of the HP front-gland labyrinth (Martin's formula)."""
FIXED_LOSS_W = 6.0e6
"""Load-independent mechanical and generator losses (W) of the load relation."""
TIP_SEAL_STRIPS = 3
"""Sealing strips z over each pressure stage's shroud (2–4 usual in HP blading; Traupel §8.5)."""
TIP_DISCHARGE_COEFFICIENT = 0.7
"""Discharge coefficient μ of a sharp sealing strip (0.6–0.8; Egli, Trans. ASME 57 (1935) 115)."""
PLANT_GRID_STRETCH = 1.2
"""Growth ratio of the plant's metal volumes from the steam-side surface inward."""
START = "2026-03-01T00:00:00Z"
"""First timestamp of every scenario (UTC)."""
TWIN_EQUIVALENT_LOADS = (0.3, 0.5, 0.75, 1.0)
"""Load fractions of the steady states that define :attr:`PlantTruth.twin_equivalent`."""


@dataclass(frozen=True)
class ParameterDrift:
    """A change of the true parameters during a run: from the run's parameters to ``target``,
    linearly over ``over_hours`` starting ``at_hours`` after the start (e.g. deposits building up
    and lowering the flow coefficient; accelerated to hours so that one day can show it)."""

    at_hours: float
    over_hours: float
    target: ModelParameters

    def __post_init__(self) -> None:
        if not (math.isfinite(self.at_hours) and self.at_hours >= 0.0
                and math.isfinite(self.over_hours) and self.over_hours >= 0.0):
            raise ValueError("at_hours and over_hours must be finite and ≥ 0")

    def schedule(self, start: ModelParameters, seconds: np.ndarray) -> pd.DataFrame:
        """Parameters (columns of ModelParameters) at each time ``seconds`` after the start."""
        begin, duration = self.at_hours * 3600.0, self.over_hours * 3600.0
        share = (np.clip((seconds - begin) / duration, 0.0, 1.0) if duration > 0.0
                 else (seconds >= begin).astype(float))
        before, after = asdict(start), asdict(self.target)
        return pd.DataFrame({name: before[name] + share * (after[name] - before[name])
                             for name in before})


@dataclass(frozen=True)
class PlantTruth:
    """Hidden truth of the virtual plant.

    ``parameters``: the FOM parameters of the real unit; ``gland_leakage_rated``: HP front-gland
    leakage as a fraction of main-steam flow at rated load; ``faults``: fault injection of the
    instruments (:class:`~steamtwin.dcs.sensors.FaultConfig`); ``drift``: an optional change
    of the parameters during the run (:class:`ParameterDrift`). The plant's structure (module
    doc, items 5–9): ``tip_clearances`` (m, per group of pressure stages), ``valve_overlap``
    (lift share) and ``valve_lift_ratio`` (full lift over seat diameter) of the governing valves,
    ``main_steam_schedule``/``reheat_schedule`` ((load fraction, K) points; None: rated at every
    load), ``casing_thermocouple_depth`` (m) and ``casing_sheath_time_constant`` (s),
    ``rotor_bore_radius`` (m; 0: solid) and ``graded_metal`` (the plant's own graded chains;
    False: the twin's uniform ones, finer). :meth:`simple` is the plant before it had them.
    """

    parameters: ModelParameters = field(default_factory=lambda: ModelParameters(
        flow_coefficient=0.965, friction_coefficient=1.3, heat_transfer_coefficient=1.4))
    gland_leakage_rated: float = 0.015
    faults: FaultConfig = field(default_factory=FaultConfig)
    drift: ParameterDrift | None = None
    tip_clearances: tuple[float, ...] = (0.0006, 0.0008, 0.0009)
    valve_overlap: float = 0.1
    valve_lift_ratio: float = 0.3
    main_steam_schedule: tuple[tuple[float, float], ...] | None = (
        (0.3, 793.15), (0.5, 811.15), (1.0, 811.15))
    reheat_schedule: tuple[tuple[float, float], ...] | None = (
        (0.3, 788.15), (0.6, 811.15), (1.0, 811.15))
    casing_thermocouple_depth: float = 0.020
    casing_sheath_time_constant: float = 8.0
    rotor_bore_radius: float = 0.05
    graded_metal: bool = True

    def __post_init__(self) -> None:
        if not 0.0 <= self.gland_leakage_rated < 0.1:
            raise ValueError("gland_leakage_rated must lie within [0, 0.1)")
        if not self.tip_clearances or not all(0.0 <= c < 0.005 for c in self.tip_clearances):
            raise ValueError("tip_clearances must be one or more radial clearances in [0, 5 mm) "
                             f"(m; got {self.tip_clearances!r})")
        if not 0.0 <= self.valve_overlap < 1.0 or not 0.05 <= self.valve_lift_ratio <= 1.0:
            raise ValueError("valve_overlap must lie within [0, 1) and valve_lift_ratio (full "
                             "lift over seat diameter) within [0.05, 1]")
        for name in ("main_steam_schedule", "reheat_schedule"):
            schedule = getattr(self, name)
            if schedule is not None and (
                    len(schedule) < 2 or any(b[0] <= a[0] for a, b in pairwise(schedule))
                    or any(not 573.15 <= t <= 913.15 for _, t in schedule)):
                raise ValueError(f"{name} must be two or more (load fraction, K) points with "
                                 "rising loads and temperatures in 573.15…913.15 K")
        if not 0.001 <= self.casing_thermocouple_depth <= 0.1:
            raise ValueError("casing_thermocouple_depth must lie within 1…100 mm (in m)")
        if not 0.0 <= self.casing_sheath_time_constant <= 120.0:
            raise ValueError("casing_sheath_time_constant must lie within 0…120 s")
        if not 0.0 <= self.rotor_bore_radius <= 0.2:
            raise ValueError("rotor_bore_radius must lie within 0…0.2 m (0: solid rotor)")
        if self.rotor_bore_radius > 0.0 and not self.graded_metal:
            raise ValueError("a rotor_bore_radius needs graded_metal (the plant's own chains)")

    @classmethod
    def simple(cls, **changes: object) -> PlantTruth:
        """The plant as it was before it grew its own physics (issue 18): gland leakage only,
        no tip leakage, sequential linear valves, rated temperatures at every load, the twin's
        thermocouple depth and sheath, a solid rotor; the metal still finer than the twin's.
        ``changes`` override fields as in :func:`dataclasses.replace`."""
        simple = cls(tip_clearances=(0.0,), valve_overlap=0.0, main_steam_schedule=None,
                     reheat_schedule=None,
                     casing_thermocouple_depth=DEFAULT_CASING_THERMOCOUPLE_DEPTH,
                     casing_sheath_time_constant=5.0, rotor_bore_radius=0.0,
                     graded_metal=False)
        return replace(simple, **changes)

    @property
    def twin_equivalent(self) -> ModelParameters:
        """The parameters with which the twin, of its own structure, best matches this plant.

        With the plant's structure no longer a re-parametrisation of the twin's (tip leakage,
        valve overlap, gland leakage varying with load, its own metal), no closed form maps the
        truth onto the twin's coefficients. They are found as a perfect calibration would find
        them: a noise-free least-squares fit of the reference twin's flow and friction
        coefficients to the plant's steady states at :data:`TWIN_EQUIVALENT_LOADS`, the
        measured inputs fed to both (:func:`twin_equivalent_parameters`). The heat-transfer
        coefficient is carried over: steady states do not see it, and the plant's rotor with a
        bore, graded walls and deeper thermocouple have no exact counterpart in the twin. The
        drift and the instruments do not enter.
        """
        return twin_equivalent_parameters(replace(self, faults=FaultConfig(), drift=None))


def plant_spec(spec: TurbineSpec) -> TurbineSpec:
    """The plant's spec: one metal group per stage, each group's mass and area (and axial length
    when it is drawn) split evenly."""
    groups: list[MetalGroup] = []
    for group in spec.metal_groups:
        if len(group.stages) == 1:
            groups.append(group)
            continue
        share = 1.0 / len(group.stages)
        geometry = None if group.geometry is None else replace(
            group.geometry, axial_length=group.geometry.axial_length * share)
        for stage in group.stages:
            groups.append(replace(
                group, name=f"{group.name} / stage {stage}", stages=(stage,),
                casing_mass=group.casing_mass * share, casing_area=group.casing_area * share,
                rotor_mass=group.rotor_mass * share, rotor_area=group.rotor_area * share,
                geometry=geometry))
    # the design point is solved for sequential valves as before; the plant's own valve law
    # (PlantTruth.valve_overlap, its poppet characteristic) replaces them afterwards
    control = replace(spec.control_stage, valve_overlap=ControlStage.valve_overlap,
                      valve_characteristic=ControlStage.valve_characteristic)
    return replace(spec, metal_groups=tuple(groups), control_stage=control)


def tip_leakage_fractions(spec: TurbineSpec, clearances: tuple[float, ...]) -> np.ndarray:
    """Share of each pressure stage's flow bypassing its blading over the shroud (see module doc).

    ``clearances`` (m): radial clearances of consecutive groups of pressure stages, the stages
    split evenly between them in order. λ = μ·(D + ℓ)·δ/(D·ℓ·sin α₁)·sqrt(r/(z·(1 − r))) with D
    the mean diameter, ℓ the blade height, α₁ the nozzle exit angle and r the reaction
    (Traupel, *Thermische Turbomaschinen* Bd. 1, §8.5).
    """
    n = len(spec.stages)
    fractions = np.zeros(n)
    for i, stage in enumerate(spec.stages):
        blading = stage.blading
        clearance = clearances[min(i * len(clearances) // n, len(clearances) - 1)]
        reaction = blading.reaction
        if clearance <= 0.0 or not 0.0 < reaction < 1.0:
            continue
        fractions[i] = (TIP_DISCHARGE_COEFFICIENT
                        * (blading.mean_diameter + blading.blade_height) * clearance
                        / (blading.mean_diameter * blading.blade_height
                           * math.sin(blading.nozzle_exit_angle))
                        * math.sqrt(reaction / (TIP_SEAL_STRIPS * (1.0 - reaction))))
    return fractions


def poppet_valve_characteristic(lift_ratio: float, points: int = 21
                                ) -> tuple[np.ndarray, np.ndarray]:
    """(lift, flow share) of a poppet valve whose full lift is ``lift_ratio`` of its seat diameter.

    The curtain area π·d·L and the seat area π·d²/4 in series, 1/A² = 1/A_curtain² + 1/A_seat²
    (curtain and seat limits of a poppet valve: Heywood, *Internal Combustion Engine
    Fundamentals*, 1988, §6.3), flow in proportion to that effective area: quick opening.
    """
    lift = np.linspace(0.0, 1.0, points)
    curtain = 4.0 * lift_ratio * lift  # curtain over seat area
    effective = curtain / np.sqrt(1.0 + curtain**2)
    return lift, effective / effective[-1]


def _graded_widths(depth: float, nodes: int) -> np.ndarray:
    """Volume widths (m) summing to ``depth``, growing by :data:`PLANT_GRID_STRETCH` inward."""
    q = PLANT_GRID_STRETCH
    return depth * (q - 1.0) / (q**nodes - 1.0) * q ** np.arange(nodes)


def graded_wall(mass: float, area: float, material: Material, insulation: float, nodes: int
                ) -> tuple[np.ndarray, np.ndarray, float, float, np.ndarray]:
    """Plane casing wall in graded volumes: (capacity J/K, conductance W/K, half-cell m²·K/W,
    outer W/K, volume widths m). Wall depth mass/(ρ·area) as the twin's; conductance between
    centres k·A/Δx, lagging in series with the last half volume (Incropera & DeWitt §3.1)."""
    k = material.thermal_conductivity
    widths = _graded_widths(mass / (material.density * area), nodes)
    capacity = material.density * material.specific_heat * area * widths
    conductance = k * area / (0.5 * (widths[:-1] + widths[1:]))
    outer = area / (1.0 / insulation + widths[-1] / (2.0 * k)) if insulation > 0.0 else 0.0
    return capacity, conductance, widths[0] / (2.0 * k), outer, widths


def bored_rotor(mass: float, area: float, material: Material, nodes: int, bore_radius: float
                ) -> tuple[np.ndarray, np.ndarray, float, float, float]:
    """Hollow rotor with an adiabatic bore, same mass and wetted area as the solid one.

    Returns (capacity J/K, conductance W/K, half-cell m²·K/W, outer W/K = 0, outer radius m).
    Mass m = ρ·π(R² − b²)·L and area A = 2πR·L give R² − s·R − b² = 0 with s = 2m/(ρA) the
    solid radius; graded volumes from the surface, cylindrical-shell conductance
    2πkL/ln(r₁/r₂) between centres (Incropera & DeWitt §3.3).
    """
    solid_radius = 2.0 * mass / (material.density * area)
    radius = 0.5 * (solid_radius + math.sqrt(solid_radius**2 + 4.0 * bore_radius**2))
    length = area / (2.0 * math.pi * radius)
    edges = radius - np.concatenate(([0.0], np.cumsum(_graded_widths(radius - bore_radius,
                                                                      nodes))))
    edges[-1] = bore_radius
    capacity = (material.density * material.specific_heat * math.pi
                * (edges[:-1] ** 2 - edges[1:] ** 2) * length)
    centres = 0.5 * (edges[:-1] + edges[1:])
    k = material.thermal_conductivity
    conductance = 2.0 * math.pi * k * length / np.log(centres[:-1] / centres[1:])
    half_cell = radius * math.log(radius / centres[0]) / k
    return capacity, conductance, half_cell, 0.0, radius


def casing_reading_position(widths: np.ndarray, depth: float) -> tuple[int, float]:
    """(node, weight) of a thermocouple ``depth`` (m) under the bore of a wall of volume
    ``widths`` (m), in the kernel's convention: linear between node centres, node −1 the bore."""
    centres = np.cumsum(widths) - 0.5 * widths
    depth = min(depth, float(centres[-1]))
    if depth <= centres[0]:
        return -1, depth / float(centres[0])
    node = min(int(np.searchsorted(centres, depth, side="right")) - 1, widths.size - 2)
    return node, (depth - float(centres[node])) / float(centres[node + 1] - centres[node])


def plant_constants(spec: TurbineSpec, constants: KernelConstants, truth: PlantTruth
                    ) -> KernelConstants:
    """The twin's kernel constants of ``spec`` turned into the plant's (module doc, items 5–9)."""
    metal = constants.metal
    nodes = metal.capacity.shape[1]
    capacity, conductance = metal.capacity.copy(), metal.conductance.copy()
    half_cell, outer = metal.half_cell_resistance.copy(), metal.outer_conductance.copy()
    rotor_speed = metal.rotor_speed.copy()
    widths = [np.full(nodes, group.casing_mass / (spec.casing_material.density
                                                  * group.casing_area * nodes))
              for group in spec.metal_groups]
    for g, group in enumerate(spec.metal_groups):
        if not truth.graded_metal:
            continue
        wall = graded_wall(group.casing_mass, group.casing_area, spec.casing_material,
                           group.insulation_conductance, nodes)
        capacity[2 * g], conductance[2 * g], half_cell[2 * g], outer[2 * g] = wall[:4]
        widths[g] = wall[4]
        rotor = bored_rotor(group.rotor_mass, group.rotor_area, spec.rotor_material, nodes,
                            truth.rotor_bore_radius)
        (capacity[2 * g + 1], conductance[2 * g + 1], half_cell[2 * g + 1],
         outer[2 * g + 1]) = rotor[:4]
        rotor_speed[g] = spec.design.rotational_speed * rotor[4]
    node, weight = casing_reading_position(widths[constants.sensor_group],
                                           truth.casing_thermocouple_depth)
    lift, flow = poppet_valve_characteristic(truth.valve_lift_ratio)
    control = constants.control._replace(valve_overlap=truth.valve_overlap,
                                         characteristic_lift=lift, characteristic_flow=flow)
    return constants._replace(
        control=control,
        metal=metal._replace(capacity=capacity, conductance=conductance,
                             half_cell_resistance=half_cell, outer_conductance=outer,
                             rotor_speed=rotor_speed),
        sensor_node=node, sensor_weight=weight,
        stage_peak_efficiency=constants.stage_peak_efficiency
        * (1.0 - tip_leakage_fractions(spec, truth.tip_clearances)))


class PlantModel(FullOrderModel):
    """The FOM with :data:`PLANT_METAL_NODES` finite volumes per metal chain and, given a
    ``truth``, the plant's own structure (:func:`plant_constants`; module doc, items 5–9).

    The efficiency scale and the nozzles are solved as in :class:`FullOrderModel`, for the
    as-designed unit (at steady state the node count only changes the small heat loss through
    the lagging); the plant's structure is applied to the final constants. Without ``truth``
    (or with :meth:`PlantTruth.simple`'s uniform metal) the chains are the twin's, only finer.
    ``options`` go to :class:`FullOrderModel`.
    """

    metal_nodes = PLANT_METAL_NODES

    def __init__(self, spec: TurbineSpec, truth: PlantTruth | None = None,
                 **options: Any) -> None:
        super().__init__(spec, **options)
        self.truth = truth

    @cached_property
    def design_(self) -> DesignConstants:
        """Kernel constants with the finer metal chains and the plant's structure."""
        control_stage_pressure = self.spec.design.control_stage_pressure
        for _ in range(2):
            scale = self._solve_efficiency_scale(control_stage_pressure)
            constants = kernel_constants(self.spec, scale, control_stage_pressure,
                                         metal_nodes=self.metal_nodes)
            diagnostics = self._design_run(constants)
            control_stage_pressure = float(diagnostics["control_stage_pressure"].iloc[0])
        if self.truth is not None:
            constants = plant_constants(self.spec, constants, self.truth)
        return DesignConstants(kernel=constants, efficiency_scale=scale)


def _martin(p1: np.ndarray, t1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Martin's labyrinth flow per unit area and per sqrt(R): ∝ p1/√T1 · ψ(p2/p1, z)."""
    ratio = np.clip(p2 / p1, 1e-6, 0.999)
    return p1 / np.sqrt(t1) * np.sqrt((1.0 - ratio**2) / (GLAND_TEETH - np.log(ratio)))


def gland_leakage_fraction(p1: np.ndarray, t1: np.ndarray, p_exhaust: np.ndarray,
                           flow: np.ndarray, rated: dict[str, float],
                           leakage_rated: float) -> np.ndarray:
    """Leakage share λ of main-steam ``flow`` (kg/s) by Martin's formula (see module doc).

    ``p1``/``t1`` control-stage pressure (Pa) and temperature (K), ``p_exhaust`` (Pa); ``rated``
    holds the same four quantities at the rated point (keys ``p1``, ``t1``, ``p_exhaust``,
    ``flow``), where λ equals ``leakage_rated``.
    """
    reference = _martin(np.array([rated["p1"]]), np.array([rated["t1"]]),
                        np.array([rated["p_exhaust"]]))[0]
    leak = leakage_rated * rated["flow"] * _martin(p1, t1, p_exhaust) / reference
    return np.clip(leak / flow, 0.0, 0.1)


def generator_power(hp_power: np.ndarray | float, spec: TurbineSpec) -> np.ndarray:
    """Approximate generator output (W) from HP blading power (W); see the module doc."""
    design = spec.design
    share = design.hp_power / (design.generator_power + FIXED_LOSS_W)
    return np.asarray(hp_power, dtype=float) / share - FIXED_LOSS_W


def boiler_temperature(schedule: tuple[tuple[float, float], ...],
                       load_fraction: np.ndarray) -> np.ndarray:
    """Steam temperature (K) of a boiler ``schedule`` of (load fraction, K) points at
    ``load_fraction``: linear between the points, flat outside (module doc, item 7)."""
    loads, temperatures = zip(*schedule, strict=True)
    return np.interp(load_fraction, loads, temperatures)



def steady_boundary(spec: TurbineSpec, demand: np.ndarray, truth: PlantTruth
                    ) -> dict[str, np.ndarray]:
    """Boundary conditions (SI) the boiler settles at for load ``demand`` (fractions)."""
    point = operating_point(spec, demand)
    if truth.main_steam_schedule is not None:
        point["main_steam_temperature"] = boiler_temperature(truth.main_steam_schedule, demand)
    if truth.reheat_schedule is not None:  # IP cone law: p_in ∝ m·sqrt(T_rh) (Stodola 1927)
        rated = boiler_temperature(truth.reheat_schedule, np.array(1.0))
        point["hp_exhaust_pressure"] = point["hp_exhaust_pressure"] * np.sqrt(
            boiler_temperature(truth.reheat_schedule, demand) / rated)
    return point



def rated_state(model: PlantModel, truth: PlantTruth) -> dict[str, float]:
    """Control-stage state and exhaust pressure at the rated point (gland-leakage reference)."""
    rated = model.simulate(model.design_inputs(), truth.parameters).iloc[0]
    design = model.spec.design
    return {"p1": float(rated["control_stage_pressure"]),
            "t1": float(rated["control_stage_temperature"]),
            "p_exhaust": design.hp_exhaust_pressure, "flow": design.main_steam_flow}



def run_leaking(model: PlantModel, inputs: pd.DataFrame, truth: PlantTruth,
                schedule: pd.DataFrame | None = None, passes: int = 2,
                report: ProgressCallback | None = None) -> tuple[pd.DataFrame, np.ndarray]:
    """Plant outputs and gland-leakage share λ for measured ``inputs``: fixed point on λ,
    which depends on p1 and T1 (module doc, item 2)."""
    rated = rated_state(model, truth)
    flow = inputs["main_steam_flow"].to_numpy()
    leakage = np.full(flow.size, truth.gland_leakage_rated)
    outputs = pd.DataFrame()
    for k in range(passes):
        if report is not None:
            report(0.2 + 0.6 * k / passes, f"plant run, pass {k + 1} of {passes}")
        stage_inputs = inputs.assign(main_steam_flow=flow * (1.0 - leakage))
        if schedule is None:
            outputs = model.simulate(stage_inputs, truth.parameters)
        else:
            outputs = model.simulate_varying(stage_inputs, schedule).outputs
        leakage = gland_leakage_fraction(
            outputs["control_stage_pressure"].to_numpy(),
            outputs["control_stage_temperature"].to_numpy(),
            inputs["hp_exhaust_pressure"].to_numpy(), flow, rated,
            truth.gland_leakage_rated)
    return outputs, leakage



def plant_model(truth: PlantTruth = PlantTruth()) -> PlantModel:
    """The plant's model of the reference unit: :func:`plant_spec` and ``truth``'s structure."""
    return PlantModel(plant_spec(load_spec("reference")), truth)


def plant_steady_states(loads: tuple[float, ...], truth: PlantTruth = PlantTruth()
                        ) -> pd.DataFrame:
    """The plant settled at each load fraction in ``loads``, without instruments (SI).

    One row per load (index ``load``): the measured inputs (main-steam flow before the gland
    leakage), the true outputs and ``gland_leakage_fraction``. Each load is a steady start.
    """
    model = plant_model(truth)
    rows = []
    for load in loads:
        point = steady_boundary(model.spec, np.array([load]), truth)
        inputs = pd.DataFrame(point, index=pd.to_datetime([START]))
        outputs, leakage = run_leaking(model, inputs, truth, passes=3)
        rows.append(inputs.join(outputs).assign(load=load, gland_leakage_fraction=leakage))
    return pd.concat(rows).set_index("load")


@lru_cache(maxsize=8)
def twin_equivalent_parameters(truth: PlantTruth) -> ModelParameters:
    """Flow and friction coefficients of the reference twin fitted, noise-free, to
    :func:`plant_steady_states` at :data:`TWIN_EQUIVALENT_LOADS` (see
    :attr:`PlantTruth.twin_equivalent`); residuals weighted by the instruments' resolution
    (0.1 % of control-stage pressure, 0.5 K), every load alike."""
    states = plant_steady_states(TWIN_EQUIVALENT_LOADS, truth)
    twin = FullOrderModel(load_spec("reference"))
    frames = [states.loc[[load], list(INPUT_SIGNALS)].set_axis(pd.to_datetime([START]))
              for load in states.index]

    def residuals(x: np.ndarray) -> np.ndarray:
        params = replace(truth.parameters, flow_coefficient=float(x[0]),
                         friction_coefficient=float(x[1]))
        out = []
        for load, frame in zip(states.index, frames, strict=True):
            twin_row = twin.simulate(frame, params).iloc[0]
            plant_row = states.loc[load]
            out += [(twin_row["control_stage_pressure"] / plant_row["control_stage_pressure"]
                     - 1.0) / 1e-3,
                    (twin_row["control_stage_temperature"]
                     - plant_row["control_stage_temperature"]) / 0.5,
                    (twin_row["hp_exhaust_temperature"]
                     - plant_row["hp_exhaust_temperature"]) / 0.5]
        return np.array(out)

    bounds = [PARAMETER_BOUNDS["flow_coefficient"], PARAMETER_BOUNDS["friction_coefficient"]]
    start = [truth.parameters.flow_coefficient, truth.parameters.friction_coefficient]
    start = [min(max(value, low), high) for value, (low, high) in zip(start, bounds,
                                                                      strict=True)]
    fit = least_squares(residuals, start, bounds=tuple(zip(*bounds, strict=True)),
                        diff_step=1e-4, xtol=1e-10)
    return replace(truth.parameters, flow_coefficient=float(fit.x[0]),
                   friction_coefficient=float(fit.x[1]))

