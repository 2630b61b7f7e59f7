"""Clips and the motion library: 30 fps, 2-second windows, label and duration filters, and
an index over the procedural motions plus any folders of BVH files users add."""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from synmitsuba.errors import ConfigError
from synmitsuba.motion.motion import Motion

CLIP_FPS = 30
CLIP_SECONDS = 2.0
# in the spirit of the paper (BABEL-based): no object interaction, no non-ground motion
EXCLUDED_LABELS = ("sit", "lie", "swim", "fall", "crawl", "climb", "interact", "object", "chair", "stairs",
                   "ladder", "ride", "bike", "throw", "catch", "carry", "push", "pull", "lift", "kick ball", "dance with")


def is_allowed(labels, excluded=EXCLUDED_LABELS) -> bool:
    """False when any label contains an excluded word."""
    text = " ".join(labels).lower()
    return not any(word in text for word in excluded)


def random_window(motion: Motion, rng: np.random.Generator, seconds: float = CLIP_SECONDS,
                  fps: float = CLIP_FPS) -> Motion:
    """A random ``seconds`` window (``seconds * fps`` frames) of the motion resampled to ``fps``."""
    m = motion.resample(fps)
    n = int(round(seconds * fps))
    if m.n_frames < n:
        raise ConfigError("motion duration", round(motion.duration, 3), f"needs at least {seconds} s for a clip")
    start = int(rng.integers(0, m.n_frames - n + 1))
    return m.clip(start / fps, seconds)


@dataclass
class LibraryEntry:
    name: str
    kind: str               # "procedural" or "bvh" (or "amass")
    path: str = ""          # file for bvh/amass; the procedural kind otherwise
    labels: tuple = ()
    seconds: float = 0.0

    def load(self, rng: np.random.Generator, seconds: float = CLIP_SECONDS) -> Motion:
        from synmitsuba.motion.sources import load_motion
        return load_motion(self.path, rng, seconds=max(seconds, 2.0) + 0.5, labels=self.labels)


@dataclass
class MotionLibrary:
    """The motions a generator samples from. Starts with the procedural kinds; ``add_folder``
    indexes BVH (and AMASS .npz) files, labels from a ``labels.json`` beside them
    ({file name: [labels]}) or else from the file name."""

    entries: list[LibraryEntry] = field(default_factory=list)

    @classmethod
    def default(cls) -> "MotionLibrary":
        from synmitsuba.motion.procedural import KINDS
        return cls([LibraryEntry(k, "procedural", k, (k,), float("inf")) for k in KINDS])

    def add_folder(self, folder: str) -> int:
        from synmitsuba.motion.bvh import load_bvh
        from synmitsuba.motion.sources import motion_files
        if not os.path.isdir(folder):
            raise ConfigError("motion folder", folder, "no such folder")
        labels_file = os.path.join(folder, "labels.json")
        given: dict = {}
        if os.path.isfile(labels_file):
            with open(labels_file) as fh:
                given = json.load(fh)
        added = 0
        for path in motion_files(folder):
            f = os.path.basename(path)
            stem = os.path.splitext(f)[0]
            labels = tuple(given.get(f, given.get(stem, [stem.replace("_", " ")])))
            if f.lower().endswith(".bvh"):
                self.entries.append(LibraryEntry(stem, "bvh", path, labels, load_bvh(path).duration))
            else:
                with np.load(path) as d:
                    fps = float(d["mocap_frame_rate"]) if "mocap_frame_rate" in d else 120.0
                    seconds = len(d["trans"]) / fps
                self.entries.append(LibraryEntry(stem, "amass", path, labels, seconds))
            added += 1
        return added

    def filter(self, min_seconds: float = CLIP_SECONDS, excluded=EXCLUDED_LABELS) -> "MotionLibrary":
        return MotionLibrary([e for e in self.entries if e.seconds >= min_seconds and is_allowed(e.labels, excluded)])
