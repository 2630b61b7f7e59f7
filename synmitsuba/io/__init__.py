"""Writers and readers: OpenEXR samples, PNG previews, scene files."""
from synmitsuba.io.dataset import SampleDataset, list_samples
from synmitsuba.io.exr import read_sample, write_sample
from synmitsuba.io.preview import contact_sheet, to_srgb8, write_png

__all__ = ["write_sample", "read_sample", "SampleDataset", "list_samples", "to_srgb8", "write_png", "contact_sheet"]
