"""The full-order model of the HP section and its parameters. The public objects, imported on
first use:"""

from steamtwin.lazy import lazy_exports

_EXPORTS = {
    "FullOrderModel": "steamtwin.model.fom",
    "ModelParameters": "steamtwin.model.parameters",
    "ParameterPrior": "steamtwin.model.parameters",
    "DEFAULT_PRIORS": "steamtwin.model.parameters",
    "Simulator": "steamtwin.model.simulator",
    "INPUT_SIGNALS": "steamtwin.model.simulator",
    "operating_point": "steamtwin.model.operating",
}

__all__ = [*_EXPORTS]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
