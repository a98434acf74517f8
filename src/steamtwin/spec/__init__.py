"""Turbine description: TOML in, validated SI dataclasses out."""

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
    "DesignPoint",
    "Extraction",
    "GoverningValve",
    "Material",
    "MetalGroup",
    "PressureStage",
    "SlidingPressureLine",
    "SpecError",
    "StageGeometry",
    "TurbineSpec",
    "load_spec",
    "parse_spec",
]
