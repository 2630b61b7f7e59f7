"""Motion: procedural motions, BVH/AMASS import, retargeting, clips."""
from synmitsuba.motion.amass import load_amass, smplx_skeleton
from synmitsuba.motion.bvh import BVHError, load_bvh, parse_bvh
from synmitsuba.motion.humanoid import humanoid_skeleton
from synmitsuba.motion.library import MotionLibrary, is_allowed, random_window
from synmitsuba.motion.motion import Motion
from synmitsuba.motion.procedural import KINDS as MOTION_KINDS
from synmitsuba.motion.procedural import foot_sliding, procedural_motion
from synmitsuba.motion.retarget import retarget

__all__ = ["Motion", "load_bvh", "parse_bvh", "BVHError", "load_amass", "smplx_skeleton", "procedural_motion",
           "MOTION_KINDS", "foot_sliding", "retarget", "humanoid_skeleton", "MotionLibrary", "random_window",
           "is_allowed"]
