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
from steamtwin.spec.loader import SpecError, load_spec, parse_spec
from steamtwin.spec.turbine import (
    ControlStage,
    DesignPoint,
    Extraction,
    GoverningValve,
    Material,
    MetalGroup,
    PressureStage,
    SlidingPressureLine,
    StageGeometry,
    TurbineSpec,
)

__all__ = [
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
    "MetalGroup",
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
