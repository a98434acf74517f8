"""Validation of the twin against plant data: metrics, tables, figures, HTML report.

Modules: ``tables`` (Table 5 operating conditions, Table 8 deviations, ROM provenance),
``figures`` (Figure 10 HP-exhaust tracking), ``html`` (the report writer: HTML + CSV + JSON),
``labels`` (readable column names, units and rounding), ``summary`` (the headline figures),
``monitor`` (ROM replay over windows and :func:`validate`, used by ``steamtwin validate`` and
the demo), ``replay`` (one continuous run of the model over a whole file, the windows taken
from it), ``sensitivity`` (Sobol sensitivity) and ``noise`` (noise propagation).
"""

from steamtwin.validation.figures import exhaust_tracking_figure
from steamtwin.validation.html import (
    FigureSection,
    NotesSection,
    ReportError,
    TableSection,
    ValidationReport,
)
from steamtwin.validation.monitor import COMPARED_SIGNALS, monitor_windows, validate
from steamtwin.validation.noise import noise_figure, noise_propagation
from steamtwin.validation.sensitivity import SobolResult, sobol_indices
from steamtwin.validation.tables import (
    deviation_table,
    operating_table,
    quality_section,
    rom_provenance_table,
)

__all__ = [
    "COMPARED_SIGNALS",
    "FigureSection",
    "NotesSection",
    "ReportError",
    "SobolResult",
    "TableSection",
    "ValidationReport",
    "deviation_table",
    "exhaust_tracking_figure",
    "monitor_windows",
    "noise_figure",
    "noise_propagation",
    "operating_table",
    "quality_section",
    "rom_provenance_table",
    "sobol_indices",
    "validate",
]
