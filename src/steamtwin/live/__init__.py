"""The live twin (issue 21): a DCS stream — OPC UA or a replayed historian — through the
streaming quality gate, the full-order model advanced sample by sample, the ROM's probes,
residual alarms and online recalibration into one DuckDB historian per service; and the
virtual plant served over OPC UA for demos and tests. The public objects, imported on first
use:"""

from steamtwin.lazy import lazy_exports

_EXPORTS = {
    "LiveTwin": "steamtwin.live.service",
    "LiveSummary": "steamtwin.live.service",
    "StreamGate": "steamtwin.live.gate",
    "gate_options": "steamtwin.live.gate",
    "LiveHistorian": "steamtwin.live.historian",
    "export_history": "steamtwin.live.historian",
    "ReplaySource": "steamtwin.live.sources",
    "OpcUaSource": "steamtwin.live.sources",
    "OpcUaSecurity": "steamtwin.live.sources",
    "ResidualMonitor": "steamtwin.live.residuals",
    "MonitorSettings": "steamtwin.live.residuals",
    "LiveRecalibration": "steamtwin.live.recalibration",
    "SensitivityCache": "steamtwin.live.sensitivity",
    "fit_monitor": "steamtwin.live.monitor_file",
    "load_monitor": "steamtwin.live.monitor_file",
    "save_monitor": "steamtwin.live.monitor_file",
    "load_config": "steamtwin.live.config",
    "run_service": "steamtwin.live.runner",
    "PlantServer": "steamtwin.live.plant_server",
}

__all__ = [*_EXPORTS]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
