"""Instance ids in composed scenes and scene files, unique by construction.

0 is the background, 1 the composed ground; objects count up from 2 (composed) or 1 (scene
files, unless given); subjects count up from 100, or from the next hundred above the highest
id already in the scene when objects reach 100, so a subject never shares an object's id (its
pixels, masks and keypoint visibility are counted by id).
"""
from __future__ import annotations

GROUND_INSTANCE = 1
OBJECT_INSTANCE = 2
SUBJECT_INSTANCE = 100


def first_subject_instance(highest_taken: int) -> int:
    """The first subject id above every id up to ``highest_taken``: 100, or a higher hundred."""
    return max(SUBJECT_INSTANCE, (int(highest_taken) // 100 + 1) * 100)


def scene_instances(scene) -> set[int]:
    """Every id the scene's meshes and curves carry."""
    return {s.instance for s in (*scene.meshes.values(), *scene.curves.values())}
