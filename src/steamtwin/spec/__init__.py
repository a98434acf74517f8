"""Turbine description: TOML in, validated SI dataclasses out."""

from steamtwin.spec.derive import DerivedSpec, DeriveError, derive_spec
from steamtwin.spec.heat_balance import (
    HeatBalance,
    HeatBalanceError,
    HeatBalanceExtraction,
    HeatBalancePoint,
    MachineDescription,
    load_heat_balance,
    parse_heat_balance,
)
from steamtwin.spec.loader import BUILT_IN, SpecError, load_spec, parse_spec
from steamtwin.spec.turbine import (
    ControlStage,
    DesignPoint,
    Extraction,
    GoverningValve,
    Material,
    MetalGeometry,
    MetalGroup,
    PartLoad,
    PressureStage,
    SlidingPressureLine,
    StageGeometry,
    TurbineSpec,
)

__all__ = [
    "BUILT_IN",
    "ControlStage",
    "DeriveError",
    "DerivedSpec",
    "DesignPoint",
    "Extraction",
    "GoverningValve",
    "HeatBalance",
    "HeatBalanceError",
    "HeatBalanceExtraction",
    "HeatBalancePoint",
    "MachineDescription",
    "Material",
    "MetalGeometry",
    "MetalGroup",
    "PartLoad",
    "PressureStage",
    "SlidingPressureLine",
    "SpecError",
    "StageGeometry",
    "TurbineSpec",
    "derive_spec",
    "load_heat_balance",
    "load_spec",
    "parse_heat_balance",
    "parse_spec",
]
