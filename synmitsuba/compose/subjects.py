"""Subjects in a scene: a recipe (sampled or from a file), a motion retargeted onto it, a
placement (position, yaw) and a frame. A subject entry (scene files' ``subjects:`` list) reads
``{seed: 3, position: [x, z], yaw_deg: 30, motion: walk, frame: 20, recipe: file.json,
instance: 5, config: {...}}``; every key is optional."""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from synmitsuba.body.recipe import SubjectConfig, SubjectRecipe, sample_subject
from synmitsuba.body.subject import LayeredHuman, build_subject
from synmitsuba.compose.instances import first_subject_instance, scene_instances
from synmitsuba.errors import ConfigError
from synmitsuba.motion.motion import Motion
from synmitsuba.motion.retargeting import retarget
from synmitsuba.motion.sources import check_motion_source, load_motion
from synmitsuba.schema import AnyOf, Nested, Number, Params, Text, Vector, optional, spec


@dataclass
class SubjectEntry(Params):
    seed: int | None = spec(None, optional(Number(0, 2 ** 31, integer=True)), doc="picks the sampled subject")
    position: list = spec(factory=lambda: [0.0, 0.0], check=AnyOf((Vector(2), Vector(3)), "give [x, z] (or [x, 0, z]) metres"))
    yaw_deg: float = spec(0.0, Number(-360, 360))
    motion: str = spec("idle", Text(), doc="a procedural kind, a .bvh or an AMASS .npz")
    frame: int | None = spec(None, optional(Number(0, integer=True)), doc="default: the clip's middle frame")
    recipe: str | None = spec(None, optional(Text()), doc="a recipe JSON file instead of a sampled subject")
    instance: int | None = spec(None, optional(Number(1, 2 ** 31 - 1, integer=True)), doc="default: 100 + index")
    config: SubjectConfig | None = spec(None, optional(Nested(SubjectConfig)), doc="what the sampled subject fixes")

    def check_files(self, where: str, base: str) -> None:
        """Fail now (before any subject is built) on a bad motion or a missing file."""
        check_motion_source(self.motion, base, f"{where}.motion")
        if self.recipe is not None and not os.path.isfile(os.path.join(base, self.recipe)):
            raise ConfigError(f"{where}.recipe", self.recipe, "no such recipe file; paths are relative to the scene file")


@dataclass
class PlacedSubject:
    """A subject in a scene: its layered human, its placed clip and the frame shown."""

    human: LayeredHuman
    motion: Motion
    frame: int
    instance: int
    prefix: str
    fits: dict = field(default_factory=dict)  # body-model fits by kind ("smplx", "smpl"): annotate.smplx_fit

    def pose_in(self, scene, frame: int | None = None) -> None:
        """Pose the subject at ``frame`` (default its own) in ``scene``, moving it in place."""
        f = self.frame if frame is None else int(frame) % self.motion.n_frames
        self.human.add_to(scene, *self.motion.frame(f), instance=self.instance, prefix=self.prefix)


def place_motion(motion: Motion, position, yaw_deg: float, lift: float = 0.0) -> Motion:
    """The clip turned by ``yaw_deg`` and moved so its mean ground position is ``position``
    ([x, z] or [x, y, z] metres), raised by ``lift`` metres."""
    pos = np.asarray(position, dtype=np.float64)
    centre = motion.joint_positions()[:, 0].mean(0)
    centred = motion.moved(0.0, [-centre[0], 0.0, -centre[2]])
    return centred.moved(float(yaw_deg), [pos[0], float(lift), pos[-1]])


def add_subjects(scene, entries: list, seed: int = 0, base: str = "", where: str = "subjects") -> list[PlacedSubject]:
    """Build, pose and add every subject entry (``SubjectEntry`` or its dict) to ``scene``.
    Every entry is checked before the first subject is built."""
    parsed = [e if isinstance(e, SubjectEntry) else SubjectEntry.from_dict(e, f"{where}[{i}]") for i, e in enumerate(entries)]
    for i, e in enumerate(parsed):
        e.check_files(f"{where}[{i}]", base)
    ids = subject_instances(parsed, scene_instances(scene), where)
    placed = []
    for i, e in enumerate(parsed):
        pick = i if e.seed is None else e.seed
        rng = np.random.default_rng([seed, i, pick])
        if e.recipe is not None:
            with open(os.path.join(base, e.recipe)) as fh:
                recipe = SubjectRecipe.from_json(fh.read())
        else:
            recipe = sample_subject(np.random.default_rng(pick), e.config)
        human = build_subject(recipe)
        motion = load_motion(e.motion, rng, seconds=2.0, base=base, field=f"{where}[{i}].motion")
        motion = place_motion(retarget(motion, human.skeleton), e.position, e.yaw_deg)
        frame = (motion.n_frames // 2 if e.frame is None else e.frame) % motion.n_frames
        subject = PlacedSubject(human, motion, frame, ids[i], f"subject{i}")
        subject.pose_in(scene)
        placed.append(subject)
    return placed


def subject_instances(entries: list, taken: set[int], where: str = "subjects") -> list[int]:
    """Each entry's id: its own, or ``first_subject_instance`` (100 above ids up to 99 in
    ``taken``) + its index. An id another subject or an object has is an error."""
    first = first_subject_instance(max(taken, default=0))
    ids = [first + i if e.instance is None else int(e.instance) for i, e in enumerate(entries)]
    for i, e in enumerate(entries):
        if ids[i] in taken or ids[i] in ids[:i]:
            raise ConfigError(f"{where}[{i}].instance", ids[i], "another subject or an object has this id; give "
                              "each subject its own (default ids: 100 + index)")
    return ids
