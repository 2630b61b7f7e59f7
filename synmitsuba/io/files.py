"""Files that are complete or absent: writes go to a temporary name renamed at the end, and
an interrupt handler can remove every temporary still being written."""
from __future__ import annotations

import contextlib
import os


# temporaries being written now: an interrupt handler that must exit at once removes them
ACTIVE_TEMPORARIES: set = set()


@contextlib.contextmanager
def atomic_path(path: str):
    """A temporary name beside ``path`` (same extension) renamed to ``path`` when the block
    ends cleanly, removed when it does not (an error, Ctrl-C): a file is complete or absent.
    The file's folder is created."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    root, ext = os.path.splitext(os.fspath(path))
    tmp = f"{root}.tmp-{os.getpid()}{ext}"
    ACTIVE_TEMPORARIES.add(tmp)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        remove_temporaries({tmp})


def remove_temporaries(paths=None) -> None:
    """Remove temporaries still being written (all of them by default): files, and folders
    such as a generation's ``seq_XXXXXX.partial``."""
    import shutil
    for tmp in list(ACTIVE_TEMPORARIES if paths is None else paths):
        ACTIVE_TEMPORARIES.discard(tmp)
        if os.path.isdir(tmp):
            shutil.rmtree(tmp, ignore_errors=True)
        elif os.path.exists(tmp):
            os.remove(tmp)
