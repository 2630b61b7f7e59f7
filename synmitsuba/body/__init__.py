"""Layered parametric humans: body models, garments, hair, accessories, textures."""
from synmitsuba._lazy import lazy_exports

_EXPORTS = {"SubjectRecipe": "synmitsuba.body.recipe", "sample_subject": "synmitsuba.body.recipe",
            "build_subject": "synmitsuba.body.subject", "LayeredHuman": "synmitsuba.body.subject",
            "PosedLayer": "synmitsuba.body.subject", "Skeleton": "synmitsuba.body.skeleton",
            "forward_kinematics": "synmitsuba.body.skeleton", "anny_uv_masks": "synmitsuba.body.anny_model",
            "GARMENT_KINDS": "synmitsuba.body.garments:GARMENTS",
            "ACCESSORY_KINDS": "synmitsuba.body.accessories:BUILDERS", "EyeParams": "synmitsuba.body.eyes",
            "GazeTarget": "synmitsuba.body.eyes", "aim_eyes": "synmitsuba.body.eyes",
            "BrowParams": "synmitsuba.body.brows", "FACE_UNITS": "synmitsuba.body.expressions",
            "HAND_KEYPOINTS": "synmitsuba.body.hand_points", "face_keypoint_names": "synmitsuba.body.face_points",
            "FACE68_VERTICES": "synmitsuba.body.face_points"}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = sorted(_EXPORTS)
