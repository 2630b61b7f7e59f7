"""``SceneSpec``: a scene as data — its stage (a composed environment with its drawn lighting,
or a scene file's objects and lights), subjects (recipe, motion source, placement, per-frame
footprints) and views (a camera per frame, occlusion, validity); a scene file's static camera
is a view whose cameras are all the same. ``to_json`` / ``from_json`` round-trip it exactly (floats are written
with Python's shortest exact repr), and ``build`` rebuilds the same scene bit for bit: the
subjects and their clips are regenerated from their recipes and motion seeds, which are
deterministic."""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Callable

import numpy as np


from synmitsuba.compose.environments import (SCENES_DIR, EnvmapLighting, SunskyLighting, add_environment,
                                             lighting_from_dict, lighting_to_dict, load_environment)
from synmitsuba.compose.subjects import PlacedSubject, SubjectSpec, placed_subject
from synmitsuba.errors import ConfigError
from synmitsuba.scene.camera import Camera
from synmitsuba.scene.scene import Scene

FORMAT = "synmitsuba.scenespec/1"


@dataclass
class ViewSpec:
    name: str
    kind: str                  # static, tracking, orbit, dolly_zoom or handheld
    cameras: list              # one Camera per frame
    occlusion: np.ndarray      # (S,) mean over the scored frames
    in_view: np.ndarray        # (S,) share of body points inside the image, mean over scored frames
    valid: np.ndarray          # (S,) bool
    visible_min: float = 0.0   # a record whose visible fraction is below it is not valid (1 - occlusion_max)

    def to_dict(self) -> dict:
        return {"name": self.name, "kind": self.kind, "cameras": [c.to_dict() for c in self.cameras],
                "occlusion": self.occlusion.tolist(), "in_view": self.in_view.tolist(),
                "valid": [bool(v) for v in self.valid], "visible_min": float(self.visible_min)}

    @classmethod
    def from_dict(cls, d: dict) -> "ViewSpec":
        return cls(d["name"], d["kind"], [Camera.from_dict(c) for c in d["cameras"]], np.asarray(d["occlusion"], float),
                   np.asarray(d["in_view"], float), np.asarray(d["valid"], bool), float(d.get("visible_min", 0.0)))


@dataclass
class SceneSpec:
    """A composed scene; ``build()`` gives the ``Scene`` and its posable subjects."""

    environment: str           # stage "environment": a name in scenes/environments or a path; "scene_file": its path
    lighting: SunskyLighting | EnvmapLighting | None  # environments.sample_lighting's draw (None: a scene file's own)
    ground_seed: int
    subjects: list             # SubjectSpec
    views: list                # ViewSpec
    n_frames: int
    fps: float
    scored_frames: list
    seed: int | None = None
    config: dict = field(default_factory=dict)
    stage: str = "environment"  # a name in STAGES: what builds the scene around the subjects
    _built: tuple | None = field(default=None, repr=False, compare=False)

    # -- data ----------------------------------------------------------------------------
    def to_json(self, indent: int | None = None) -> str:
        stage = {} if self.stage == "environment" else {"stage": self.stage}
        return json.dumps({"format": FORMAT, "seed": self.seed, **stage, "environment": self.environment,
                           "lighting": lighting_to_dict(self.lighting), "ground_seed": int(self.ground_seed),
                           "n_frames": int(self.n_frames), "fps": float(self.fps),
                           "scored_frames": [int(f) for f in self.scored_frames], "config": self.config,
                           "subjects": [s.to_dict() for s in self.subjects],
                           "views": [v.to_dict() for v in self.views]}, indent=indent)

    @classmethod
    def from_json(cls, text: str) -> "SceneSpec":
        d = json.loads(text)
        if d.get("format") != FORMAT:
            raise ConfigError("scene spec format", d.get("format"), f"this synmitsuba reads {FORMAT}")
        return cls(d["environment"], lighting_from_dict(d["lighting"]), d["ground_seed"],
                   [SubjectSpec.from_dict(s) for s in d["subjects"]],
                   [ViewSpec.from_dict(v) for v in d["views"]], d["n_frames"], d["fps"], d["scored_frames"],
                   d.get("seed"), d.get("config", {}), d.get("stage", "environment"))

    def view(self, name: str) -> ViewSpec:
        for v in self.views:
            if v.name == name:
                return v
        raise ConfigError("view", name, f"no such view; views: {', '.join(v.name for v in self.views)}")

    # -- building ------------------------------------------------------------------------
    def build(self, humans: list | None = None) -> tuple[Scene, list[PlacedSubject]]:
        """The Scene (environment, objects, lighting, subjects at frame 0) and the placed
        subjects (``pose_in(scene, frame)`` moves one in place). Built once, then reused;
        ``humans`` (one ``LayeredHuman`` per subject, built from the same recipes) saves
        building them again."""
        if self._built is None:
            scene = STAGES[self.stage](self)
            placed = self.placed_subjects(humans)
            for subject in placed:
                subject.pose_in(scene, 0)
            self._built = (scene, placed)
        return self._built

    def placed_subjects(self, humans: list | None = None) -> list[PlacedSubject]:
        """The subjects with their placed clips, without building a scene (labels computed
        after the fact, e.g. body-model fits, need no renderer)."""
        return [placed_subject(s, i, None if humans is None else humans[i]) for i, s in enumerate(self.subjects)]

    @property
    def motions(self) -> list:
        """The subjects' placed, retargeted clips."""
        return [p.motion for p in self.build()[1]]


def _environment_stage(spec: SceneSpec) -> Scene:
    """A composed scene's environment: ground, objects and the drawn lighting."""
    scene = Scene()
    if spec.lighting is None:
        raise ConfigError("scene spec lighting", None, "a composed scene needs its drawn lighting")
    add_environment(scene, load_environment(spec.environment), spec.lighting, np.random.default_rng(spec.ground_seed))
    return scene


def _scene_file_stage(spec: SceneSpec) -> Scene:
    """A scene file's objects, environment and lights (its subjects are the spec's)."""
    from synmitsuba.compose.scenefile import read_scene_doc, static_scene
    return static_scene(read_scene_doc(spec.environment), spec.environment)


STAGES: dict[str, Callable[[SceneSpec], Scene]] = {"environment": _environment_stage, "scene_file": _scene_file_stage}


def resolve_environment(name: str) -> str:
    """How a spec names an environment: its bare name when it lives in scenes/environments."""
    path = os.path.abspath(name) if os.path.isfile(name) else None
    if path and os.path.dirname(path) == os.path.join(SCENES_DIR, "environments"):
        return os.path.splitext(os.path.basename(path))[0]
    return path or name
