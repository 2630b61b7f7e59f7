"""Reading generated datasets: ``SynDataset`` (PyTorch), whole images or person crops."""
from synmitsuba._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {"SynDataset": "synmitsuba.data.dataset"})
__all__ = ["SynDataset"]
