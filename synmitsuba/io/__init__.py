"""Writers and readers of samples: OpenEXR + JSON sidecar, PNG previews, label panels, COCO and
HumanData exports."""
from synmitsuba._lazy import lazy_exports

_EXPORTS = {"write_sample": "synmitsuba.io.exr", "read_sample": "synmitsuba.io.exr",
            "list_samples": "synmitsuba.io.listing",
            "to_srgb8": "synmitsuba.io.preview", "write_png": "synmitsuba.io.preview",
            "contact_sheet": "synmitsuba.io.preview", "export_coco": "synmitsuba.io.coco",
            "export_humandata": "synmitsuba.io.humandata",
            "sample_panel": "synmitsuba.io.overlay"}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = sorted(_EXPORTS)
