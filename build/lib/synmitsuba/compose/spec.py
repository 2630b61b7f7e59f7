"""``SceneSpec``: a composed scene as data — environment and its drawn lighting, subjects
(recipe, motion source, placement, per-frame footprints) and views (a camera per frame,
occlusion, validity). ``to_json`` / ``from_json`` round-trip it exactly (floats are written
with Python's shortest exact repr), and ``build`` rebuilds the same scene bit for bit: the
subjects and their clips are regenerated from their recipes and motion seeds, which are
deterministic."""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from synmitsuba.body.recipe import SubjectRecipe
from synmitsuba.compose.environments import SCENES_DIR, add_environment, load_environment
from synmitsuba.compose.subjects import PlacedSubject, place_motion
from synmitsuba.errors import ConfigError
from synmitsuba.scene.camera import Camera
from synmitsuba.scene.scene import Scene

FORMAT = "synmitsuba.scenespec/1"


def clip_motion(source: str, seed: int, seconds: float, fps: float, base: str = "", field_: str = "motion"):
    """The clip a motion entry names: a procedural kind drawn with ``seed``, or a random
    ``seconds`` window (from ``seed``) of a .bvh / AMASS file, at ``fps``."""
    from synmitsuba.motion.library import random_window
    from synmitsuba.motion.sources import load_motion
    rng = np.random.default_rng(seed)
    m = load_motion(source, rng, seconds=seconds, base=base, field=field_)
    return random_window(m, rng, seconds, fps)


@dataclass
class SubjectSpec:
    recipe: SubjectRecipe
    motion: dict           # {"source", "seed", "seconds", "fps", "base"}
    position: tuple        # (x, z) of the clip's mean root position
    yaw_deg: float
    instance: int
    footprint: np.ndarray  # (4,) whole-clip ground box (x_min, z_min, x_max, z_max)
    frames: np.ndarray     # (F, 4) per-frame ground boxes
    height: float          # tallest point over the clip, metres
    lift: float = 0.0      # metres the clip is raised so its lowest point over the clip is on the ground

    def to_dict(self) -> dict:
        return {"recipe": json.loads(self.recipe.to_json()), "motion": dict(self.motion),
                "position": [float(v) for v in self.position], "yaw_deg": float(self.yaw_deg),
                "instance": int(self.instance), "footprint": self.footprint.tolist(),
                "frames": self.frames.tolist(), "height": float(self.height), "lift": float(self.lift)}

    @classmethod
    def from_dict(cls, d: dict) -> "SubjectSpec":
        return cls(SubjectRecipe.from_dict(d["recipe"]), dict(d["motion"]), tuple(d["position"]), d["yaw_deg"],
                   d["instance"], np.asarray(d["footprint"], float), np.asarray(d["frames"], float), d["height"], d["lift"])


@dataclass
class ViewSpec:
    name: str
    kind: str                  # static, tracking, orbit, dolly_zoom or handheld
    cameras: list              # one Camera per frame
    occlusion: np.ndarray      # (S,) mean over the scored frames
    in_view: np.ndarray        # (S,) share of body points inside the image, mean over scored frames
    valid: np.ndarray          # (S,) bool

    def to_dict(self) -> dict:
        return {"name": self.name, "kind": self.kind, "cameras": [c.to_dict() for c in self.cameras],
                "occlusion": self.occlusion.tolist(), "in_view": self.in_view.tolist(),
                "valid": [bool(v) for v in self.valid]}

    @classmethod
    def from_dict(cls, d: dict) -> "ViewSpec":
        return cls(d["name"], d["kind"], [Camera.from_dict(c) for c in d["cameras"]], np.asarray(d["occlusion"], float),
                   np.asarray(d["in_view"], float), np.asarray(d["valid"], bool))


@dataclass
class SceneSpec:
    """A composed scene; ``build()`` gives the ``Scene`` and its posable subjects."""

    environment: str           # a name in scenes/environments or a path
    lighting: dict             # from environments.sample_lighting
    ground_seed: int
    subjects: list             # SubjectSpec
    views: list                # ViewSpec
    n_frames: int
    fps: float
    scored_frames: list
    seed: int | None = None
    config: dict = field(default_factory=dict)
    _built: tuple | None = field(default=None, repr=False, compare=False)

    # -- data ----------------------------------------------------------------------------
    def to_json(self, indent: int | None = None) -> str:
        return json.dumps({"format": FORMAT, "seed": self.seed, "environment": self.environment,
                           "lighting": self.lighting, "ground_seed": int(self.ground_seed),
                           "n_frames": int(self.n_frames), "fps": float(self.fps),
                           "scored_frames": [int(f) for f in self.scored_frames], "config": self.config,
                           "subjects": [s.to_dict() for s in self.subjects],
                           "views": [v.to_dict() for v in self.views]}, indent=indent)

    @classmethod
    def from_json(cls, text: str) -> "SceneSpec":
        d = json.loads(text)
        if d.get("format") != FORMAT:
            raise ConfigError("scene spec format", d.get("format"), f"this synmitsuba reads {FORMAT}")
        return cls(d["environment"], d["lighting"], d["ground_seed"], [SubjectSpec.from_dict(s) for s in d["subjects"]],
                   [ViewSpec.from_dict(v) for v in d["views"]], d["n_frames"], d["fps"], d["scored_frames"],
                   d.get("seed"), d.get("config", {}))

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
            env = load_environment(self.environment)
            scene = Scene()
            add_environment(scene, env, self.lighting, np.random.default_rng(self.ground_seed))
            placed = self.placed_subjects(humans)
            for subject in placed:
                subject.pose_in(scene, 0)
            self._built = (scene, placed)
        return self._built

    def placed_subjects(self, humans: list | None = None) -> list[PlacedSubject]:
        """The subjects with their placed clips, without building a scene (labels computed
        after the fact, e.g. body-model fits, need no renderer)."""
        from synmitsuba.body.subject import build_subject
        from synmitsuba.motion.retargeting import retarget
        placed = []
        for i, s in enumerate(self.subjects):
            human = humans[i] if humans is not None else build_subject(s.recipe)
            m = s.motion
            clip = clip_motion(m["source"], m["seed"], m["seconds"], m["fps"], m.get("base", ""), f"subjects[{i}].motion")
            motion = place_motion(retarget(clip, human.skeleton), s.position, s.yaw_deg, s.lift)
            placed.append(PlacedSubject(human, motion, 0, s.instance, f"subject{i}"))
        return placed

    @property
    def motions(self) -> list:
        """The subjects' placed, retargeted clips."""
        return [p.motion for p in self.build()[1]]


def resolve_environment(name: str) -> str:
    """How a spec names an environment: its bare name when it lives in scenes/environments."""
    path = os.path.abspath(name) if os.path.isfile(name) else None
    if path and os.path.dirname(path) == os.path.join(SCENES_DIR, "environments"):
        return os.path.splitext(os.path.basename(path))[0]
    return path or name
