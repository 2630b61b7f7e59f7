"""Per-subject labels of a rendered view: keypoints (world, camera, image) with visibility
classes and visible fractions, amodal masks, boxes, body parameters in camera space, and
SMPL-X / SMPL fits of the layered subjects (``fit_smplx``, on the user's model files).
``Annotator(subjects).annotate(sample, scene, frame)`` fills ``sample.subjects``."""
from synmitsuba._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {
    "Annotator": "synmitsuba.annotate.records", "VISIBILITY": "synmitsuba.annotate.keypoints",
    "keypoint_visibility": "synmitsuba.annotate.keypoints", "body_params_in_camera": "synmitsuba.annotate.bodyparams",
    "layer_masks": "synmitsuba.annotate.records", "exact_flow": "synmitsuba.annotate.flow",
    "fit_smplx": "synmitsuba.annotate.smplx_fit", "SMPLXFit": "synmitsuba.annotate.smplx_fit",
    "SMPLXOptions": "synmitsuba.annotate.smplx_fit", "write_anny_model": "synmitsuba.annotate.smplx_synthetic"})
__all__ = ["Annotator", "SMPLXFit", "SMPLXOptions", "VISIBILITY", "body_params_in_camera", "exact_flow", "fit_smplx",
           "keypoint_visibility", "layer_masks", "write_anny_model"]
