"""steamtwin: a digital twin of a steam turbine in deep peak-shaving operation.

The handful of objects a user needs, imported on first use (``import steamtwin`` stays light):

* :class:`Twin` — spec, parameters, blade ROM and provenance; calibrate, simulate, build_rom,
  validate, save/load (:mod:`steamtwin.twin`);
* :func:`load_history`, :class:`History`, :class:`DataQualityError` — historian exports read,
  checked and cleaned through their tag map, with a window finder (:mod:`steamtwin.dcs.history`);
* :class:`ModelParameters` (:mod:`steamtwin.model.parameters`), :func:`load_spec` and
  :class:`TurbineSpec` (:mod:`steamtwin.spec`).

Everything else stays in its subpackage.
"""

from importlib import import_module
from typing import Any

__version__ = "0.1.0"

_EXPORTS = {
    "Twin": "steamtwin.twin",
    "TwinError": "steamtwin.twin",
    "load_history": "steamtwin.dcs.history",
    "History": "steamtwin.dcs.history",
    "DataQualityError": "steamtwin.dcs.history",
    "ModelParameters": "steamtwin.model.parameters",
    "load_spec": "steamtwin.spec",
    "TurbineSpec": "steamtwin.spec",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str) -> Any:
    """The re-exported objects, imported when first asked for (PEP 562)."""
    if name in _EXPORTS:
        value = getattr(import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'steamtwin' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])
