"""Dataset generation: configs, one task per sequence on a local process pool or Ray, a
manifest of complete sequences, resumable runs."""
from synmitsuba._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {
    "GenerateConfig": "synmitsuba.generate.config", "load_generate_config": "synmitsuba.generate.config",
    "generate": "synmitsuba.generate.run", "run_sequence": "synmitsuba.generate.run"})
__all__ = ["GenerateConfig", "generate", "load_generate_config", "run_sequence"]
