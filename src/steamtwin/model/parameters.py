"""The three unmeasurable model parameters, their physical bounds and their empirical defaults.

All three are dimensionless multipliers on a design correlation:

* ``flow_coefficient`` scales every flow capacity of the steam path — the Stodola constants of the
  pressure stages and the nozzle area of the control stage. Deposits shrink and erosion widens
  throat areas; ±10 % brackets what is reported for HP blading in service (Cotton 1998, ch. 9 on
  deposits; Cooke 1985 on the cone-law constants).
* ``friction_coefficient`` scales the fluid-friction losses: blade-profile friction, disc friction
  and idle-arc windage (Kang et al., *Principles of Steam Turbines*, China Electric Power Press —
  the K1 and B_e loss set; Traupel 2001). 0.5–2.0 spans new, polished blading to rough, deposited
  blading.
* ``heat_transfer_coefficient`` scales the Dittus–Boelter steam-to-metal Nusselt correlation.
  Turbulent-pipe correlations scatter by ±25 % in their own range (Incropera & DeWitt) and by far
  more for rotor/casing surfaces (manufacturers' formulas "vary greatly", ASME POWER2014-32004
  abstract), hence 0.5–2.0.

The defaults (1, 1, 1) are the "empirical constants": the correlations as published, the values a
designer uses before any calibration.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, fields
from pathlib import Path

PARAMETER_BOUNDS: dict[str, tuple[float, float]] = {
    "flow_coefficient": (0.90, 1.10),
    "friction_coefficient": (0.5, 2.0),
    "heat_transfer_coefficient": (0.5, 2.0),
}


class ParameterError(ValueError):
    """A parameter value is missing, not a number or outside its physical bounds."""


@dataclass(frozen=True)
class ModelParameters:
    """Unmeasurable parameters of the full-order model (dimensionless multipliers, default 1)."""

    flow_coefficient: float = 1.0
    friction_coefficient: float = 1.0
    heat_transfer_coefficient: float = 1.0

    def __post_init__(self) -> None:
        for field in fields(self):
            value = getattr(self, field.name)
            low, high = PARAMETER_BOUNDS[field.name]
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ParameterError(f"{field.name} = {value!r}: expected a number")
            if not math.isfinite(value) or not low <= value <= high:
                raise ParameterError(
                    f"{field.name} = {value!r} is outside its physical bounds [{low}, {high}]"
                )

    @classmethod
    def from_json(cls, path: str | Path) -> ModelParameters:
        """Read a parameter set written by :meth:`to_json` (or by calibration)."""
        path = Path(path)
        try:
            document = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as error:
            raise ParameterError(f"{path}: cannot read parameters: {error}") from None
        values = document.get("parameters", document) if isinstance(document, dict) else None
        if not isinstance(values, dict):
            raise ParameterError(f"{path}: expected a JSON object of parameters")
        unknown = set(values) - set(PARAMETER_BOUNDS)
        if unknown:
            raise ParameterError(
                f"{path}: unknown parameter(s) {sorted(unknown)}; known: {list(PARAMETER_BOUNDS)}"
            )
        try:
            return cls(**values)
        except ParameterError as error:
            raise ParameterError(f"{path}: {error}") from None

    def to_json(self, path: str | Path) -> None:
        """Write the parameters (with their bounds, for the reader's benefit) as JSON."""
        document = {
            "parameters": asdict(self),
            "bounds": {name: list(bounds) for name, bounds in PARAMETER_BOUNDS.items()},
        }
        Path(path).write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
