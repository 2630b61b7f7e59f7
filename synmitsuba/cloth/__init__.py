"""The cloth stage, between posing and rendering: garments simulated over a subject's clip
against its posed body (Newton's VBD solver on Warp, on the CPU), instead of skinned with it."""
from synmitsuba.cloth.air import Air
from synmitsuba.cloth.fabrics import FABRICS, Fabric
from synmitsuba.cloth.kinds import CLOTH_KINDS, ClothKind
from synmitsuba.cloth.simulate import ClothError, ClothPiece, ClothSettings, ClothTrack, Collider, drape, simulate_cloth

__all__ = ["Air", "CLOTH_KINDS", "ClothError", "ClothKind", "ClothPiece", "ClothSettings", "ClothTrack", "Collider",
           "FABRICS", "Fabric", "drape", "simulate_cloth"]
