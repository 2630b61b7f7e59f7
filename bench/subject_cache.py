"""Build a bench's subjects once and keep them in a file (``--subjects PATH``).

Building needs anny (and warp-lang), which a lent GPU machine lacks and which would not fit in
what travels there; posing and rendering need neither. So a bench builds its subjects here,
writes them lzma-compressed (about 2 MB a subject with hair), and on the device reads them back.
"""
from __future__ import annotations

import lzma
import os
import pickle


def cached(path: str | None, build):
    """``build()``'s result, read from ``path`` when it exists, else built and written there."""
    if path and os.path.exists(path):
        with lzma.open(path, "rb") as fh:
            return pickle.load(fh)
    value = build()
    if path:
        with lzma.open(path + ".part", "wb") as fh:
            pickle.dump(value, fh, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(path + ".part", path)
    return value
