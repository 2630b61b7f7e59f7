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
