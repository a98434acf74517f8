"""DCS data: tag maps, historian exports read and cleaned, the quality gate, and the virtual
plant that writes such exports. The public objects, imported on first use:"""

from steamtwin.lazy import lazy_exports

_EXPORTS = {
    "TagMap": "steamtwin.dcs.tagmap",
    "load_tag_map": "steamtwin.dcs.tagmap",
    "write_tag_map": "steamtwin.dcs.tagmap",
    "read_historian": "steamtwin.dcs.readers",
    "load_history": "steamtwin.dcs.history",
    "History": "steamtwin.dcs.history",
    "check_history": "steamtwin.dcs.history",
    "DataQualityError": "steamtwin.dcs.history",
    "QualityOptions": "steamtwin.dcs.quality",
    "check_quality": "steamtwin.dcs.quality",
    "clean": "steamtwin.dcs.quality",
    "run_plant": "steamtwin.dcs.plant",
    "write_plant": "steamtwin.dcs.plant",
    "plant_tag_map": "steamtwin.dcs.plant",
    "PlantTruth": "steamtwin.dcs.plant_model",
}

__all__ = [*_EXPORTS]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
