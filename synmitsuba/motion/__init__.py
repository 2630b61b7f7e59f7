"""Motion: procedural motions, BVH/AMASS import, retargeting, clips."""
from synmitsuba._lazy import lazy_exports

_EXPORTS = {"Motion": "synmitsuba.motion.motion", "load_bvh": "synmitsuba.motion.bvh",
            "parse_bvh": "synmitsuba.motion.bvh", "BVHError": "synmitsuba.motion.bvh",
            "load_amass": "synmitsuba.motion.amass", "smplx_skeleton": "synmitsuba.motion.amass",
            "procedural_motion": "synmitsuba.motion.procedural", "MOTION_KINDS": "synmitsuba.motion.procedural:KINDS",
            "foot_sliding": "synmitsuba.motion.procedural", "retarget": "synmitsuba.motion.retargeting",
            "humanoid_skeleton": "synmitsuba.motion.humanoid", "MotionLibrary": "synmitsuba.motion.library",
            "random_window": "synmitsuba.motion.library", "is_allowed": "synmitsuba.motion.library",
            "load_motion": "synmitsuba.motion.sources", "HandTrack": "synmitsuba.motion.hands",
            "HandKey": "synmitsuba.motion.hands", "sample_hands": "synmitsuba.motion.hands",
            "with_hands": "synmitsuba.motion.hands", "HAND_BEHAVIOURS": "synmitsuba.motion.hands:BEHAVIOURS",
            "FaceTrack": "synmitsuba.motion.faces", "FaceKey": "synmitsuba.motion.faces",
            "sample_face": "synmitsuba.motion.faces", "with_face": "synmitsuba.motion.faces",
            "EXPRESSIONS": "synmitsuba.motion.faces"}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = sorted(_EXPORTS)
