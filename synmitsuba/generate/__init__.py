"""Dataset generation: configs, one task per sequence on a local process pool or Ray, a
manifest of complete sequences, resumable runs."""
from synmitsuba._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {
    "GenerateConfig": "synmitsuba.generate.config", "load_generate_config": "synmitsuba.generate.config",
    "generate": "synmitsuba.generate.run", "run_sequence": "synmitsuba.generate.run",
    "sequence_spec": "synmitsuba.generate.run", "write_sequence": "synmitsuba.generate.run",
    "add_body_model_fits": "synmitsuba.generate.body_models"})
__all__ = ["GenerateConfig", "add_body_model_fits", "generate", "load_generate_config", "run_sequence", "sequence_spec",
           "write_sequence"]
