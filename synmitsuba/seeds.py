"""Every seed of a sequence, from (global seed, sequence index) alone: generation, ``synmitsuba
render`` and the library all derive them here, so a sequence is the same whoever renders it,
in whatever order."""
from __future__ import annotations

import numpy as np


def sequence_rng(seed: int, index: int) -> np.random.Generator:
    """The generator that composes sequence ``index``: subjects, motions, placement, cameras."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), int(index)]))


def render_seed(seed: int, index: int) -> int:
    """The render seed of sequence ``index``'s frame 0 (frame f renders with this + f)."""
    return int(np.random.SeedSequence([int(seed), int(index), 1]).generate_state(1)[0] % 2 ** 30)


def effects_rng(seed: int, index: int) -> np.random.Generator:
    """The generator of sequence ``index``'s camera effects (shutter, ...): apart from the
    composition's, so turning an effect on leaves the scene as it was."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), int(index), 2]))


def subframe_seed(frame_seed: int, k: int) -> int:
    """The render seed of motion-blur sub-frame ``k`` of the frame rendered with ``frame_seed``:
    hashed, because Mitsuba's ldsampler with consecutive seeds correlates neighbouring pixels
    (their sum showed horizontal streaks: neighbour correlation 0.73 against 0.003 hashed)."""
    return int(np.random.SeedSequence([int(frame_seed), int(k)]).generate_state(1)[0])


def photo_rng(frame_seed: int, view: int) -> np.random.Generator:
    """The sensor noise of view ``view`` (its index) of the frame rendered with ``frame_seed``."""
    return np.random.default_rng(np.random.SeedSequence([int(frame_seed), int(view), 3]))
