"""Scan uncertainty → throat area → flow capacity → HP-exhaust temperature.

Monte Carlo over the scanner's error: the exact blade sections at several radii are sampled like
a scan (0.2 mm spacing), every point is moved along its normal by a uniform error within the
scanner's ±0.05 mm, each section is rebuilt by a periodic smoothing spline (Dierckx's
``splprep``, smoothing set to the expected sum of squared errors n·b²/3) and its throat measured
(:func:`~steamtwin.geometry.fidelity.section_throat`). The row's throat area is N·∫o(r)dr; its
ratio to the exact one is the flow-capacity multiplier of the row's own stage — the Stodola
constant of a stage scales with its throat area (Cooke 1985) — so each row's error goes through
its own stage only: row hpK scales ``stages[K−1].flow_capacity`` (:func:`as_built_model`).

The control-stage rotor hp1 is not propagated: in the model the governing stage's flow is set by
its nozzle groups (throat area × discharge coefficient, ``model.design``: with nozzle
governing the admitted nozzle area sets the flow, Traupel, *Thermische Turbomaschinen*, vol. 2)
and its efficiency by the velocity ratio; no constant depends on the rotor throat. In a
real impulse stage a rotor throat error shifts the stage's reaction a little, which the model
does not represent, so the study reports hp1's throat-area spread and no temperature.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import splev, splprep

from steamtwin.geometry.fidelity import section_pitch, section_throat
from steamtwin.geometry.pritchard import GeometryError
from steamtwin.geometry.profile import Blade
from steamtwin.geometry.row_sizing import HP_ROWS
from steamtwin.model.design import DesignConstants
from steamtwin.model.fom import FullOrderModel
from steamtwin.progress import ProgressCallback

SCAN_SPACING = 0.2e-3  # m, point spacing of the simulated section scans
#: Why the control-stage rotor's throat error is not propagated (see the module docstring).
CONTROL_STAGE_ROTOR = ("not propagated: hp1 is the control-stage rotor; the model's governing "
                       "stage passes the flow through its nozzle groups and has no constant "
                       "set by the rotor throat")


def propagated_stage(row: str) -> int | None:
    """1-based pressure stage whose ``flow_capacity`` the throat of ``row`` scales: K − 1 for
    hpK (K = 2…13); None for the control-stage rotor hp1. Raises
    :class:`~steamtwin.geometry.pritchard.GeometryError` for rows outside the HP model (ip…)."""
    if row not in HP_ROWS:
        raise GeometryError(f"row {row!r} is not in the HP model (rows {HP_ROWS[0]}…"
                            f"{HP_ROWS[-1]}): its throat has no flow capacity to scale")
    index = HP_ROWS.index(row)
    return index if index > 0 else None


def as_built_model(model: object, stage: int, ratio: float) -> object:
    """``model`` (a :class:`~steamtwin.model.fom.FullOrderModel`) with the flow capacity of
    pressure stage ``stage`` (1-based) scaled by ``ratio`` and every other design constant
    kept — the efficiency scale and the nozzle area the design step found for the unmodified
    spec. Rebuilding the model from the modified spec would re-solve the efficiency scale and
    meet the design exhaust temperature again, hiding the change at the design point."""
    stages = list(model.spec.stages)
    if not 1 <= stage <= len(stages):
        raise GeometryError(f"pressure stage {stage} is not in turbine {model.spec.name!r} "
                            f"(stages 1…{len(stages)})")
    stages[stage - 1] = dataclasses.replace(
        stages[stage - 1], flow_capacity=stages[stage - 1].flow_capacity * ratio)
    design = model.design_
    capacity = design.kernel.stage_capacity.copy()
    capacity[stage - 1] *= ratio
    constants = DesignConstants(kernel=design.kernel._replace(stage_capacity=capacity),
                                efficiency_scale=design.efficiency_scale)

    class AsBuiltModel(FullOrderModel):
        """The modified spec run with the unmodified spec's design constants."""

        @property
        def design_(self) -> DesignConstants:
            return constants

    return AsBuiltModel(dataclasses.replace(model.spec, stages=tuple(stages)),
                        pressure_tolerance=model.pressure_tolerance,
                        enthalpy_tolerance=model.enthalpy_tolerance)


@dataclass(frozen=True)
class UncertaintyResult:
    """Throat-area multipliers and HP-exhaust temperatures (K) of the Monte Carlo samples.

    ``stage`` is the 1-based pressure stage the row's throat scales and ``propagation`` says so;
    for the control-stage rotor (``stage`` None) ``hp_exhaust_temperature`` is None and
    ``propagation`` gives the reason (:data:`CONTROL_STAGE_ROTOR`).
    """

    row: str
    bound: float  # m
    throat_area_ratio: np.ndarray
    hp_exhaust_temperature: np.ndarray | None
    nominal_hp_exhaust_temperature: float
    stage: int | None
    propagation: str

    @property
    def temperature_spread(self) -> float | None:
        """max − min of the HP-exhaust temperature over the samples (K); None if the row's
        throat is not propagated."""
        if self.hp_exhaust_temperature is None:
            return None
        return float(np.ptp(self.hp_exhaust_temperature))

    @property
    def max_deviation(self) -> float | None:
        """Largest |T − T_nominal| of the HP-exhaust temperature over the samples (K): the
        error a scan of this quality puts on the model's prediction through this row's stage,
        the figure the method reports (< 0.3 °C for ±0.05 mm); None if not propagated."""
        if self.hp_exhaust_temperature is None:
            return None
        return float(np.abs(self.hp_exhaust_temperature
                            - self.nominal_hp_exhaust_temperature).max())

    def as_dict(self) -> dict:
        temperatures = self.hp_exhaust_temperature
        return {"row": self.row, "stage": self.stage, "propagation": self.propagation,
                "bound_mm": self.bound * 1e3,
                "samples": len(self.throat_area_ratio),
                "throat_area_ratio_min": float(self.throat_area_ratio.min()),
                "throat_area_ratio_max": float(self.throat_area_ratio.max()),
                "throat_area_ratio_std": float(self.throat_area_ratio.std()),
                "hp_exhaust_temperature_spread_K": self.temperature_spread,
                "hp_exhaust_temperature_max_deviation_K": self.max_deviation,
                "hp_exhaust_temperature_std_K":
                    None if temperatures is None else float(temperatures.std()),
                "nominal_hp_exhaust_temperature_degC":
                    self.nominal_hp_exhaust_temperature - 273.15}


def exact_sections(blade: Blade, count: int
                   ) -> tuple[np.ndarray, list[np.ndarray], list[np.ndarray]]:
    """``count`` radii (m) evenly inside the span, the exact section points there (0.2 mm
    spacing, m) and their outward unit normals."""
    outline, _ = blade.profile.sample(SCAN_SPACING)
    radii = np.linspace(blade.design.hub_radius, blade.design.tip_radius, count + 2)[1:-1]
    points, normals = [], []
    for radius in radii:
        section = blade.place(outline, float(radius))[:, :2]
        tangent = np.roll(section, -1, axis=0) - np.roll(section, 1, axis=0)
        normal = np.column_stack([tangent[:, 1], -tangent[:, 0]])  # clockwise outline: outward
        points.append(section)
        normals.append(normal / np.linalg.norm(normal, axis=1, keepdims=True))
    return radii, points, normals


def rebuilt_throat(section: np.ndarray, pitch: float, bound: float) -> float:
    """Throat (m) of a section rebuilt from noisy points by a periodic smoothing spline."""
    closed = np.vstack([section, section[:1]])
    smoothing = len(section) * bound**2 / 3.0  # uniform error on [−b, b] has variance b²/3
    tck, _ = splprep([closed[:, 0], closed[:, 1]], s=smoothing, per=1, k=3)
    x, y = splev(np.linspace(0.0, 1.0, 20 * len(section), endpoint=False), tck)
    return section_throat(np.column_stack([x, y]), pitch)


def throat_area(blade: Blade, radii: np.ndarray, throats: np.ndarray) -> float:
    """Row throat area N·∫o(r)dr (m²) from throats at ``radii`` (trapezoid, ends extrapolated
    flat to hub and tip)."""
    r = np.concatenate([[blade.design.hub_radius], radii, [blade.design.tip_radius]])
    o = np.concatenate([throats[:1], throats, throats[-1:]])
    return blade.profile.params.blade_count * float(np.trapezoid(o, r))


def scan_uncertainty(blade: Blade, model: object, samples: int = 20, bound: float = 0.05e-3,
                     sections: int = 3, random_state: np.random.Generator | int | None = 0,
                     progress: ProgressCallback | None = None) -> UncertaintyResult:
    """Monte Carlo of the throat area of ``blade``'s row under ±``bound`` (m) scan errors,
    each sample's ratio propagated through the row's own stage of ``model`` (a
    :class:`~steamtwin.model.fom.FullOrderModel`, :func:`as_built_model`) at its design point.
    The control-stage rotor hp1 gets the throat areas only (module docstring). Raises
    :class:`~steamtwin.geometry.pritchard.GeometryError` for a row outside the HP model."""
    stage = propagated_stage(blade.row)
    rng = np.random.default_rng(random_state)
    radii, points, normals = exact_sections(blade, sections)
    pitches = [section_pitch(blade, float(r)) for r in radii]
    exact = np.array([rebuilt_throat(p, s, 0.0) for p, s in zip(points, pitches, strict=True)])
    area = throat_area(blade, radii, exact)
    inputs = model.design_inputs()
    nominal = float(model.simulate(inputs)["hp_exhaust_temperature"].iloc[0])
    ratios, temperatures = [], []
    for k in range(samples):
        throats = np.array([
            rebuilt_throat(p + rng.uniform(-bound, bound, len(p))[:, None] * n, s, bound)
            for p, n, s in zip(points, normals, pitches, strict=True)])
        ratio = throat_area(blade, radii, throats) / area
        ratios.append(ratio)
        if stage is not None:
            outputs = as_built_model(model, stage, float(ratio)).simulate(inputs)
            temperatures.append(float(outputs["hp_exhaust_temperature"].iloc[0]))
        if progress is not None:
            progress((k + 1) / samples, f"sample {k + 1}/{samples}")
    propagation = (CONTROL_STAGE_ROTOR if stage is None
                   else f"stages[{stage}].flow_capacity scaled by the row's throat-area ratio")
    return UncertaintyResult(row=blade.row, bound=bound, throat_area_ratio=np.array(ratios),
                             hp_exhaust_temperature=None if stage is None
                             else np.array(temperatures),
                             nominal_hp_exhaust_temperature=nominal, stage=stage,
                             propagation=propagation)
