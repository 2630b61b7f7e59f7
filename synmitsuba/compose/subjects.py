"""Subjects in a scene, built, retargeted and placed in one place for composed scenes and scene
files alike. A ``SubjectSpec`` is a subject as data (recipe, where its clip comes from, where
it stands); ``placed_subject`` turns one into a posable ``PlacedSubject``. A subject entry
(scene files' ``subjects:`` list) reads ``{seed: 3, position: [x, z], yaw_deg: 30, motion:
walk, frame: 20, recipe: file.json, instance: 5, config: {...}}``; every key is optional."""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field, replace

import numpy as np

from synmitsuba.body.expressions import FACE_UNITS
from synmitsuba.body.eyes import GazeTarget, aim_eyes, eye_look_weights
from synmitsuba.body.recipe import SubjectConfig, SubjectRecipe, sample_subject
from synmitsuba.body.subject import LayeredHuman, PosedLayer, build_subject
from synmitsuba.cloth.simulate import ClothTrack, simulate_cloth
from synmitsuba.compose.instances import first_subject_instance, scene_instances
from synmitsuba.compose.placement import envelope, frame_boxes, frame_hulls
from synmitsuba.errors import ConfigError
from synmitsuba.motion.faces import EXPRESSIONS, FaceTrack, fixed_face, sample_face, with_face
from synmitsuba.body.shoes import pitch_feet
from synmitsuba.motion.hands import BEHAVIOURS, HandKey, HandTrack, sample_hands, with_hands
from synmitsuba.motion.motion import Motion
from synmitsuba.motion.sources import check_motion_source
from synmitsuba.schema import AnyOf, Choice, Nested, Number, Params, Text, Vector, optional, spec


@dataclass
class SubjectEntry(Params):
    seed: int | None = spec(None, optional(Number(0, 2 ** 31, integer=True)), doc="picks the sampled subject")
    position: list = spec(factory=lambda: [0.0, 0.0], check=AnyOf((Vector(2), Vector(3)), "give [x, z] (or [x, 0, z]) metres"))
    yaw_deg: float = spec(0.0, Number(-360, 360))
    motion: str = spec("idle", Text(), doc="a procedural kind, a .bvh or an AMASS .npz")
    frame: int | None = spec(None, optional(Number(0, integer=True)), doc="clip frame shown first (default: the middle)")
    recipe: str | None = spec(None, optional(Text()), doc="a recipe JSON file instead of a sampled subject")
    instance: int | None = spec(None, optional(Number(1, 2 ** 31 - 1, integer=True)), doc="default: 100 + index")
    config: SubjectConfig | None = spec(None, optional(Nested(SubjectConfig)), doc="what the sampled subject fixes")
    hands: str = spec("auto", Choice(("auto", *BEHAVIOURS)), doc="both hands' behaviour (auto: drawn for the motion)")
    expression: str = spec("auto", Choice(("auto", *EXPRESSIONS)), doc="the face's expression (auto: drawn for the "
                           "motion, with blinks)")

    def check_files(self, where: str, base: str) -> None:
        """Fail now (before any subject is built) on a bad motion or a missing file."""
        check_motion_source(self.motion, base, f"{where}.motion")
        if self.recipe is not None and not os.path.isfile(os.path.join(base, self.recipe)):
            raise ConfigError(f"{where}.recipe", self.recipe, "no such recipe file; paths are relative to the scene file")


@dataclass
class ClipSettings(Params):
    seconds: float = spec(2.0, Number(0.1, 60), doc="clip length: a random window of a motion file")
    fps: float = spec(30.0, Number(1, 240), doc="the clip's frame rate (files are resampled)")


@dataclass
class MotionSpec:
    """Where a subject's clip comes from: a procedural kind drawn with ``seed`` or a random
    ``seconds`` window (from ``seed``) of a .bvh / AMASS file at ``fps``, relative paths from
    ``base``; the scene's frame 0 shows clip frame ``start`` (the clip wraps round)."""

    source: str
    seed: int
    seconds: float
    fps: float
    base: str = ""
    start: int = 0

    def clip(self, where: str = "motion", roll: float = 1.0) -> Motion:
        """The clip (a procedural one with its feet's roll scaled by ``roll``)."""
        from synmitsuba.motion.library import random_window
        from synmitsuba.motion.sources import load_motion
        rng = np.random.default_rng(self.seed)
        m = load_motion(self.source, rng, seconds=self.seconds, base=self.base, field=where, roll=roll)
        return random_window(m, rng, self.seconds, self.fps)

    def to_dict(self) -> dict:
        d = {"source": self.source, "seed": int(self.seed), "seconds": float(self.seconds), "fps": float(self.fps),
             "base": self.base}
        return {**d, "start": int(self.start)} if self.start else d

    @classmethod
    def from_dict(cls, d: dict) -> "MotionSpec":
        return cls(d["source"], d["seed"], d["seconds"], d["fps"], d.get("base", ""), d.get("start", 0))


@dataclass
class SubjectSpec:
    """A subject as data: ``placed_subject`` rebuilds it bit for bit."""

    recipe: SubjectRecipe
    motion: MotionSpec
    position: tuple        # (x, z) of the clip's mean root position
    yaw_deg: float
    instance: int
    footprint: np.ndarray  # (4,) whole-clip ground box (x_min, z_min, x_max, z_max)
    frames: np.ndarray     # (F, 4) per-frame ground boxes
    height: float          # tallest point over the clip, metres
    lift: float = 0.0      # metres the clip is raised so its lowest point over the clip is on the ground
    gaze: GazeTarget | None = None  # where the eyes look (None: straight ahead of the head)
    hands: HandTrack | None = None  # what the fingers do (None: the source's fingers, or anny's rest)
    face: FaceTrack | None = None   # expressions, speech and blinks (None: anny's neutral face)

    def to_dict(self) -> dict:
        gaze = {} if self.gaze is None else {"gaze": self.gaze.to_dict()}
        if self.hands is not None:
            gaze["hands"] = self.hands.to_dict()
        if self.face is not None:
            gaze["face"] = self.face.to_dict()
        return {"recipe": json.loads(self.recipe.to_json()), "motion": self.motion.to_dict(),
                "position": [float(v) for v in self.position], "yaw_deg": float(self.yaw_deg),
                "instance": int(self.instance), "footprint": self.footprint.tolist(),
                "frames": self.frames.tolist(), "height": float(self.height), "lift": float(self.lift), **gaze}

    @classmethod
    def from_dict(cls, d: dict) -> "SubjectSpec":
        gaze = GazeTarget.from_dict(d["gaze"]) if "gaze" in d else None
        hands = HandTrack.from_dict(d["hands"]) if "hands" in d else None
        face = FaceTrack.from_dict(d["face"]) if "face" in d else None
        return cls(SubjectRecipe.from_dict(d["recipe"]), MotionSpec.from_dict(d["motion"]), tuple(d["position"]),
                   d["yaw_deg"], d["instance"], np.asarray(d["footprint"], float), np.asarray(d["frames"], float),
                   d["height"], d["lift"], gaze, hands, face)


@dataclass
class PlacedSubject:
    """A subject in a scene: its layered human, its placed clip and the frame shown."""

    human: LayeredHuman
    motion: Motion
    frame: int
    instance: int
    prefix: str
    fits: dict = field(default_factory=dict)  # body-model fits by kind ("smplx", "smpl"): annotate.smplx_fit
    simulated: bool = False  # the recipe's cloth: simulated
    cloth_motion: Motion | None = None  # the clip before its eyes were aimed and before it was started at
    # ``cloth_start``: what the cloth hangs on, in one piece (rolled, a walk's root jumps back 0.58 m where it
    # wraps round, and a skirt simulated through the jump flew up to the waist)
    cloth_start: int = 0
    _cloth: ClothTrack | None = field(default=None, repr=False)

    @property
    def cloth(self) -> ClothTrack | None:
        """The simulated garments over the clip (None when skinned), simulated on first use
        (labels that need no render, e.g. body-model fits, never pay for it) against
        ``cloth_motion`` and started where the clip is: aiming the eyes (composition does it
        after building the scene) moves no cloth, and a subject rebuilt from its spec hangs the
        same cloth bit for bit."""
        if not self.simulated:
            return None
        if self._cloth is None:
            track = simulate_cloth(self.human, self.cloth_motion or self.motion)
            self._cloth = track.rolled(self.cloth_start) if track is not None and self.cloth_motion else track
        return self._cloth

    def garments_at(self, time: float) -> dict | None:
        """The simulated garments' vertices at (fractional) clip frame ``time``; None when skinned."""
        return None if self.cloth is None else self.cloth.at(time)

    def layers(self, frame: int) -> list[PosedLayer]:
        """The posed layers at clip frame ``frame`` (wrapping round), as ``pose_in`` puts them in a scene."""
        f = int(frame) % self.motion.n_frames
        return self.human.pose(*self.motion.frame(f), face=self.motion.face_at(f), garments=self.garments_at(f))

    def pose_in(self, scene, frame: int | None = None) -> None:
        """Pose the subject at ``frame`` (default its own) in ``scene``, moving it in place."""
        f = self.frame if frame is None else int(frame) % self.motion.n_frames
        self.human.add_to(scene, *self.motion.frame(f), instance=self.instance, prefix=self.prefix,
                          face=self.motion.face_at(f), garments=self.garments_at(f))

    def pose_at(self, scene, time: float) -> None:
        """Pose the subject at fractional frame ``time`` (a motion-blur sub-frame; clamped to
        the clip), moving it in place."""
        self.human.add_to(scene, *self.motion.at(time), instance=self.instance, prefix=self.prefix,
                          face=self.motion.face_at(time), garments=self.garments_at(time))


def place_motion(motion: Motion, position, yaw_deg: float, lift: float = 0.0) -> Motion:
    """The clip turned by ``yaw_deg`` and moved so its mean ground position is ``position``
    ([x, z] or [x, y, z] metres), raised by ``lift`` metres."""
    pos = np.asarray(position, dtype=np.float64)
    centre = motion.joint_positions()[:, 0].mean(0)
    centred = motion.moved(0.0, [-centre[0], 0.0, -centre[2]])
    return centred.moved(float(yaw_deg), [pos[0], float(lift), pos[-1]])


HEELED_ROLL_MIN = 0.25  # the least share of the foot roll a walk in heels keeps


def retargeted_clip(human: LayeredHuman, motion: MotionSpec, where: str = "motion") -> Motion:
    """The subject's clip on its skeleton (``retarget_to_subject``), a procedural one rolling its
    feet as the subject's shoes let it (``heeled_roll``)."""
    return retarget_to_subject(motion.clip(where, heeled_roll(human.heels)), human)


def heeled_roll(heels) -> float:
    """The share of a barefoot walk's heel-strike and toe-off pitches a walk in ``heels`` keeps
    (1 in flat shoes): a heel already bends the toes up against the foot by its pitch, and at
    toe-off they bend no further than a bare foot's do (``procedural.ROLL``), at least a
    quarter of the roll left."""
    from synmitsuba.geometry import matrix_to_axis_angle
    from synmitsuba.motion.procedural import ROLL
    if not heels:
        return 1.0
    pitch = max(float(np.linalg.norm(matrix_to_axis_angle(h.rotation))) for h in heels)
    return max(HEELED_ROLL_MIN, 1.0 - pitch / ROLL["walk"][1])


def retarget_to_subject(source: Motion, human: LayeredHuman) -> Motion:
    """``source`` on the subject's skeleton, its feet held as its shoes hold them and planted."""
    from synmitsuba.motion.retargeting import retarget
    return planted(with_heels(retarget(source, human.skeleton), human.heels), human, source)


def planted(clip: Motion, human: LayeredHuman, source: Motion) -> Motion:
    """The clip with its root moved at each frame so that the subject's feet stand where the
    source's do, whatever the new legs' and feet's lengths: up or down until its lowest sole
    point is as high as the source's (scaled as retargeting scales the root), and across so that
    the sole points on the ground hold still while they are on it (``held_still``). The source's
    soles: the procedural humanoid's exactly (``humanoid.sole_clearance``), a mocap skeleton's
    from its ankles and toes (``contacts.foot_clearance``); a source whose feet are not known
    stays as it is (``clip_bounds`` then lifts the whole clip onto the ground)."""
    if clip.skeleton.names == source.skeleton.names:
        return clip
    clearance = source_clearance(source)
    if clearance is None:
        return clip
    wanted = clip.meta.get("pelvis_ratio", 1.0) * clearance
    root = clip.root_translation.copy()
    points = human.sole_points(clip.rotations, root)
    rise = wanted - points[..., 1].min(1)
    root[:, 1] += rise
    root[:, [0, 2]] += held_still(points[..., [0, 2]], points[..., 1] + rise[:, None], human.sole_sides)
    return replace(clip, root_translation=root)


def source_clearance(source: Motion) -> np.ndarray | None:
    """The source clip's sole clearance per frame (F,), or None when its feet are not known."""
    from synmitsuba.motion.contacts import foot_clearance
    from synmitsuba.motion.humanoid import humanoid_skeleton, sole_clearance
    if source.skeleton.names == humanoid_skeleton().names:
        return sole_clearance(source.rotations, source.root_translation)
    return foot_clearance(source)


def held_still(xz: np.ndarray, y: np.ndarray, sides: np.ndarray, touch: float = 0.002) -> np.ndarray:
    """Root offsets (F, 2) that keep the sole points on the ground (``y`` under ``touch``) from
    sliding: at each frame, the mean move since the frame before of the points on the ground at
    both, on the foot with more of them, is taken back (and kept: the clip goes as far as its
    feet carry it). ``xz`` (F, V, 2) and ``y`` (F, V) are the points' ground positions and
    heights; ``sides`` (V,) their feet."""
    off = np.zeros((len(xz), 2))
    for t in range(1, len(xz)):
        off[t] = off[t - 1]
        down = (y[t] < touch) & (y[t - 1] < touch)
        counts = {s: int((down & (sides == s)).sum()) for s in (1, -1)}
        side = max(counts, key=lambda s: counts[s])
        if counts[side]:
            held = down & (sides == side)
            off[t] -= (xz[t, held] - xz[t - 1, held]).mean(0)
    return off


def with_heels(motion: Motion, heels) -> Motion:
    """The clip with each foot pitched on its heel (``body.shoes.HeelPitch``, one per foot) at
    every frame, the toes turned back flat; unchanged for none. The pitch is in the clip's
    rotations, so the pose labels hold the feet as they are rendered."""
    return replace(motion, rotations=pitch_feet(motion.rotations, heels)) if heels else motion


def placed_subject(s: SubjectSpec, i: int, human: LayeredHuman | None = None) -> PlacedSubject:
    """Subject ``i`` of a scene: built from its recipe (or ``human``, built from it already),
    its clip retargeted, placed, started at ``s.motion.start``, its hands, face and eyes set."""
    human = build_subject(s.recipe) if human is None else human
    clip = with_face(with_hands(retargeted_clip(human, s.motion, f"subjects[{i}].motion"), s.hands), s.face)
    placed = place_motion(clip, s.position, s.yaw_deg, s.lift)
    motion = placed.rolled(s.motion.start) if s.motion.start else placed
    return PlacedSubject(human, aimed(motion, s.gaze), 0, s.instance, f"subject{i}",
                         simulated=human.recipe.cloth == "simulated", cloth_motion=placed, cloth_start=s.motion.start)


def draw_hands(rng: np.random.Generator, motion: Motion) -> HandTrack:
    """A hand track for a clip, coupled to its kind (its first label) and its parameters."""
    kind = motion.labels[0] if motion.labels else ""
    return sample_hands(rng, kind, motion.meta.get("params"), motion.duration)


def draw_face(rng: np.random.Generator, motion: Motion) -> FaceTrack:
    """A face track for a clip, coupled to its kind (its first label) and its parameters."""
    kind = motion.labels[0] if motion.labels else ""
    return sample_face(rng, kind, motion.meta.get("params"), motion.duration)


def fixed_hands(behaviour: str, seed: int) -> HandTrack:
    """Both hands holding ``behaviour`` the whole clip."""
    return HandTrack([HandKey(0.0, behaviour, seed)], [HandKey(0.0, behaviour, seed + 1)], seed=seed)


def aimed(motion: Motion, gaze: GazeTarget | None) -> Motion:
    """The clip with both eyes turned towards ``gaze`` at every frame, and the lids following
    them: the ARKit eyeLook units set from the eyes' turn (``eyes.eye_look_weights``), which are
    the face label's gaze too (unchanged for None)."""
    if gaze is None:
        return motion
    rot = aim_eyes(motion.skeleton, motion.rotations, motion.root_translation, gaze, motion.fps)
    face = np.zeros((motion.n_frames, len(FACE_UNITS))) if motion.face is None else motion.face.copy()
    for unit, w in eye_look_weights(motion.skeleton, rot).items():
        face[:, FACE_UNITS.index(unit)] = w
    return replace(motion, rotations=rot, face=face)


def performed_clip(human: LayeredHuman, motion: MotionSpec, where: str = "motion", hands: str = "auto",
                   expression: str = "auto") -> tuple[Motion, HandTrack, FaceTrack]:
    """The subject's retargeted clip with its hands and face, and those tracks: ``hands`` (a
    behaviour) and ``expression`` as given, or for "auto" drawn for the clip from (its motion
    seed, ``HAND_STREAM`` / ``FACE_STREAM``), not from a scene's rng. The tracks are known before
    placement: open fingers and a dropped jaw are part of the clip's footprint."""
    clip = retargeted_clip(human, motion, where)
    handed = draw_hands(np.random.default_rng([motion.seed, HAND_STREAM]), clip) if hands == "auto" else \
        fixed_hands(hands, motion.seed)
    face = draw_face(np.random.default_rng([motion.seed, FACE_STREAM]), clip) if expression == "auto" else \
        fixed_face(expression, motion.seed)
    return with_face(with_hands(clip, handed), face), handed, face


HAND_STREAM, FACE_STREAM = 7, 8  # the streams a subject's hands and face are drawn from, with its motion seed


def clip_bounds(human: LayeredHuman, clip: Motion) -> tuple[list, float, float]:
    """The per-frame ground hulls of the subject's (retargeted, performed) clip centred on its
    mean root position, its tallest point over the clip and the lift that puts its lowest point
    over the clip on the ground (``planted`` puts a procedural clip's soles on it already; a
    mocap clip keeps its source's root height, not the new legs' contact)."""
    clip = place_motion(clip, (0.0, 0.0), 0.0)
    xz, height, low = [], -np.inf, np.inf
    for f in range(clip.n_frames):
        layers = human.pose(*clip.frame(f), resolve=False, face=clip.face_at(f))  # a few mm do not change a hull
        pts = np.concatenate([(lay.points.reshape(-1, 3) if lay.is_curves else lay.vertices) for lay in layers])
        xz.append(pts[:, [0, 2]])
        height = max(height, float(pts[:, 1].max()))
        low = min(low, min(float(lay.vertices[:, 1].min()) for lay in layers if not lay.is_curves))
    return frame_hulls(xz), height - low, -low


def _recipe(e: SubjectEntry, pick: int, base: str) -> SubjectRecipe:
    if e.recipe is None:
        return sample_subject(np.random.default_rng(pick), e.config)
    with open(os.path.join(base, e.recipe)) as fh:
        return SubjectRecipe.from_json(fh.read())


def subject_specs(entries: list, rng: np.random.Generator, taken: set[int], base: str = "",
                  clip: ClipSettings | None = None, where: str = "subjects") -> tuple[list[SubjectSpec], list]:
    """Subject entries (``SubjectEntry`` or their dicts) as ``SubjectSpec``s, with the humans
    built for them. Every entry is checked before the first is built; ``rng`` draws a recipe
    seed (for entries without one) and a motion seed per entry; ids avoid ``taken``."""
    clip = clip or ClipSettings()
    parsed = [e if isinstance(e, SubjectEntry) else SubjectEntry.from_dict(e, f"{where}[{i}]") for i, e in enumerate(entries)]
    for i, e in enumerate(parsed):
        e.check_files(f"{where}[{i}]", base)
    ids = subject_instances(parsed, taken, where)
    specs, humans = [], []
    for i, e in enumerate(parsed):
        draw, mseed = (int(v) for v in rng.integers(2 ** 31, size=2))
        recipe = _recipe(e, draw if e.seed is None else e.seed, base)
        human = build_subject(recipe)
        motion = MotionSpec(e.motion, mseed, clip.seconds, clip.fps, base)
        performed, hands, face = performed_clip(human, motion, f"{where}[{i}].motion", e.hands, e.expression)
        hulls, height, lift = clip_bounds(human, performed)
        start = (len(hulls) // 2 if e.frame is None else e.frame) % len(hulls)
        position, yaw = (float(e.position[0]), float(e.position[-1])), float(e.yaw_deg)
        frames = np.roll(frame_boxes(hulls, yaw, position), -start, 0)
        specs.append(SubjectSpec(recipe, replace(motion, start=start), position, yaw, ids[i], envelope(frames), frames,
                                 height, lift, hands=hands, face=face))
        humans.append(human)
    return specs, humans


def add_subjects(scene, entries: list, seed: int = 0, base: str = "", where: str = "subjects") -> list[PlacedSubject]:
    """Build, place and pose every subject entry (``SubjectEntry`` or its dict) in ``scene``,
    each at its first frame; every entry is checked before the first subject is built."""
    specs, humans = subject_specs(entries, np.random.default_rng(seed), scene_instances(scene), base, where=where)
    placed = [placed_subject(s, i, h) for i, (s, h) in enumerate(zip(specs, humans))]
    for p in placed:
        p.pose_in(scene)
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
