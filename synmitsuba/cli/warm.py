"""``synmitsuba warm``: build, once per machine, what a first run would otherwise wait for."""
from __future__ import annotations

import time
from typing import Callable


def _kernels() -> None:
    """The cloth stage's kernels, without Warp's banner and module log (as after the body model
    loads, which quiets them)."""
    from synmitsuba.body.anny_model import _quiet_warp, _without_warp_banner
    from synmitsuba.cloth.warm import compile_kernels
    with _without_warp_banner():
        import warp
        warp.init()
    _quiet_warp()
    compile_kernels()


def run(args) -> int:
    from synmitsuba.body.anny_model import load_anny
    steps: dict[str, Callable[[], object]] = {"model": load_anny, "kernels": _kernels}
    for name in args.only or list(steps):
        t = time.perf_counter()
        steps[name]()
        print(f"{name}: ready in {time.perf_counter() - t:.1f} s", flush=True)
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("warm", help="build anny's model cache and compile the cloth stage's kernels, once per machine",
                       description="Build what a first run would otherwise wait for, once per machine: anny's "
                                   "processed body model (about 790 MB in ANNY_CACHE_DIR or ~/.cache/anny; about a "
                                   "minute) and the cloth stage's Warp kernels (WARP_CACHE_PATH or Warp's cache; about "
                                   "a minute). Run it in a machine image or a cluster's setup step, so that workers "
                                   "start at once; `make test` runs it beside the linters. Each is skipped, or "
                                   "loaded in seconds, when already there.")
    p.add_argument("--only", nargs="+", choices=("model", "kernels"), help="just these (default: both)")
    p.set_defaults(func=run)
