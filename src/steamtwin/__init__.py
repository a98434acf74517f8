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

from steamtwin.lazy import lazy_exports

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


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
