"""Layered parametric humans: body models, garments, hair, accessories, textures."""
from synmitsuba.body.recipe import SubjectRecipe, sample_subject
from synmitsuba.body.skeleton import Skeleton, forward_kinematics
from synmitsuba.body.subject import LayeredHuman, PosedLayer, build_subject

__all__ = ["SubjectRecipe", "sample_subject", "build_subject", "LayeredHuman", "PosedLayer", "Skeleton",
           "forward_kinematics"]
