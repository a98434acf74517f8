"""One unit's model as the live twin runs it: the turbine spec, read through the tag map's
sensors (thermocouple lags and depths) and the calibration's sensor offsets, at the
calibration's coefficients — shared by the service (:mod:`~steamtwin.live.runner`) and the
monitor fit (:mod:`~steamtwin.live.monitor_file`), so both see the same twin."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from steamtwin.dcs.tagmap import TagMap, load_tag_map
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters, sensor_offsets_from_json
from steamtwin.model.sensor_setup import sensor_setup
from steamtwin.spec import TurbineSpec, load_spec

__all__ = ["UnitModel", "unit_model"]


@dataclass(frozen=True)
class UnitModel:
    """``spec``, ``tag_map`` and ``model`` (the FOM read through the unit's sensors)."""

    spec: TurbineSpec
    tag_map: TagMap
    model: FullOrderModel


def unit_model(turbine: str | Path, tags: str | Path | TagMap, params: str | Path | None = None
               ) -> tuple[UnitModel, ModelParameters]:
    """The unit's model and live coefficients (``params``: a params JSON with coefficients and
    sensor offsets; None: the design values, no offsets)."""
    spec = load_spec(turbine)
    tag_map = tags if isinstance(tags, TagMap) else load_tag_map(tags)
    coefficients, offsets = ModelParameters(), {}
    if params is not None:
        coefficients = ModelParameters.from_json(params)
        offsets = sensor_offsets_from_json(params)
    setup = dataclasses.replace(sensor_setup(spec, tag_map), offsets=offsets)
    return UnitModel(spec, tag_map, setup.model(spec)), coefficients
