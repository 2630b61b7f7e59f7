"""Per-subject labels of a rendered view: keypoints (world, camera, image) with visibility
classes and visible fractions, amodal masks, boxes, body parameters in camera space.
``Annotator(subjects).annotate(sample, scene, frame)`` fills ``sample.subjects``."""
from synmitsuba._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {
    "Annotator": "synmitsuba.annotate.records", "VISIBILITY": "synmitsuba.annotate.keypoints",
    "keypoint_visibility": "synmitsuba.annotate.keypoints", "body_params_in_camera": "synmitsuba.annotate.bodyparams",
    "layer_masks": "synmitsuba.annotate.records", "exact_flow": "synmitsuba.annotate.flow"})
__all__ = ["Annotator", "VISIBILITY", "body_params_in_camera", "exact_flow", "keypoint_visibility", "layer_masks"]
