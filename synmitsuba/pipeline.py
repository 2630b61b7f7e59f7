"""Glue from descriptions to scenes: subjects (recipe + motion + placement) into a Scene.

A subject entry (scene files' ``subjects:`` list) reads:
``{seed: 3, position: [x, z], yaw_deg: 30, motion: walk, frame: 20, recipe: file.json, instance: 5}``;
every key is optional. ``motion`` is a procedural kind, a .bvh or an AMASS .npz.
"""
from __future__ import annotations

import os

import numpy as np

from synmitsuba.errors import ConfigError

SUBJECT_KEYS = {"seed", "position", "yaw_deg", "motion", "frame", "recipe", "instance", "config"}


def subject_motion(entry: dict, human, rng: np.random.Generator, base: str = ""):
    """The entry's motion retargeted to the subject and placed (yaw, position)."""
    import synmitsuba as sm
    kind = entry.get("motion", "idle")
    if kind in sm.MOTION_KINDS:
        motion = sm.procedural_motion(kind, rng, seconds=2.0)
    elif str(kind).lower().endswith(".bvh"):
        motion = sm.load_bvh(os.path.join(base, kind))
    elif str(kind).lower().endswith(".npz"):
        motion = sm.load_amass(os.path.join(base, kind))
    else:
        raise ConfigError("subjects[].motion", kind, f"use a .bvh/.npz file or one of {', '.join(sm.MOTION_KINDS)}")
    motion = sm.retarget(motion, human.skeleton)
    pos = np.asarray(entry.get("position", [0.0, 0.0]), dtype=np.float64)
    if pos.shape not in ((2,), (3,)):
        raise ConfigError("subjects[].position", entry.get("position"), "give [x, z] (or [x, 0, z]) metres")
    offset = np.array([pos[0], 0.0, pos[-1]])
    centre = motion.joint_positions()[:, 0].mean(0)  # the clip's mean ground position goes to the spot
    centred = motion.moved(0.0, [-centre[0], 0.0, -centre[2]])
    return centred.moved(float(entry.get("yaw_deg", 0.0)), offset)


def add_subjects(scene, entries: list, seed: int = 0, base: str = "") -> list:
    """Build, pose and add every subject entry to ``scene``; returns [(human, motion, frame)]."""
    import synmitsuba as sm
    placed = []
    for i, entry in enumerate(entries):
        if not isinstance(entry, dict):
            raise ConfigError(f"subjects[{i}]", entry, "give a mapping like {seed: 3, position: [x, z], motion: walk}")
        unknown = sorted(set(entry) - SUBJECT_KEYS)
        if unknown:
            raise ConfigError(f"subjects[{i}].{unknown[0]}", entry[unknown[0]], f"keys: {', '.join(sorted(SUBJECT_KEYS))}")
        rng = np.random.default_rng([seed, i, int(entry.get("seed", i))])
        if "recipe" in entry:
            path = os.path.join(base, entry["recipe"])
            if not os.path.isfile(path):
                raise ConfigError(f"subjects[{i}].recipe", entry["recipe"], "no such recipe file")
            recipe = sm.SubjectRecipe.from_json(open(path).read())
        else:
            recipe = sm.sample_subject(np.random.default_rng(int(entry.get("seed", i))), entry.get("config"))
        human = sm.build_subject(recipe)
        motion = subject_motion(entry, human, rng, base)
        frame = int(entry.get("frame", motion.n_frames // 2)) % motion.n_frames
        instance = int(entry.get("instance", 100 + i))
        human.add_to(scene, *motion.frame(frame), instance=instance, prefix=f"subject{i}")
        placed.append((human, motion, frame))
    return placed
