"""The cloth stage on a lent GPU (issue 34's CUDA figures): the same drapes on ``cuda`` as here.

The device machine cannot build subjects (anny does not fit what it carries), so ``pack`` (here)
records, per clip, what the cloth stage's collider gives the solver: the cloth pieces, the body's
faces and, per frame and per step of the arms' lead, the closed posed body and the skinned
garments' particles (float32, replayed as such on both machines), the waist seals and the
slippery hands; it also drapes each clip on this CPU and keeps the result and the seconds.
``run`` (on the device: Warp, Newton, trimesh and pykdtree carried) drapes each clip twice and
prints, as JSON: seconds per simulated frame (settle included), the first run's seconds, the
distances of its vertices from the CPU's and between its two runs, and whether those agree bit
for bit. Newton's kernels are built forward-only, as the CLI builds them (``--full-kernels``:
with their backward passes).

    python bench/cloth_device.py pack [--subjects 2] [--motions walk,run] [--seconds 1.0]
    python bench/cloth_device.py warm [--arch 90]   # here: Newton's CUDA kernels, compiled ahead
    python bench/cloth_device.py run [--precompile] [--cache DIR] [--vertex-contact] [--device cpu]
                                               # on the device (PYTHONPATH with the carried packages)

``run --precompile`` compiles before it drapes: a dry run finds every module a drape loads on
CUDA (with the device's own launch block sizes: Newton's SDF contact kernels take 128 threads on
CUDA, its tiled cloth solve exists there only), then 16 threads compile them at once (forward-
only: 11 s on an H200; with backward passes the full-surface contacts alone took 468 s). ``warm``
(here) compiles for ``sm_<arch>`` the modules a CPU drape loads, at the block sizes
``CUDA_BLOCK_DIMS`` knows a CUDA launch uses; ``--cache`` is where ``run`` finds and leaves
CUBINs. bench/RESULTS.md (2026-12-04) says how the packages travel and what was measured.
"""
import argparse
import json
import lzma
import os
import pickle
import sys
import time
from types import SimpleNamespace

import numpy as np

INPUTS = ".device/cloth_inputs.pkl.xz"
CACHE = ".device/warpcache"  # carried to the device beside INPUTS


def _recorded(fn, store: dict):
    """``fn`` whose answers are rounded to float32 (as both machines replay them) and kept in
    ``store`` under their argument: the frames and the arms' lead the drape asks for."""
    def call(x):
        if x not in store:
            store[x] = tuple(a.astype(np.float32) for a in fn(x))
        return tuple(a.astype(np.float64) for a in store[x])
    return call


def pack(args) -> dict:
    _forward_only(args)
    import synmitsuba as sm
    from synmitsuba.cloth.simulate import _seals, cloth_inputs
    s = sm.ClothSettings()
    clips = []
    for i in range(args.subjects):
        garment = ("skirt", "dress")[i % 2]
        outfit = ["tshirt", "skirt"] if garment == "skirt" else ["dress"]
        human = sm.build_subject(sm.sample_subject(np.random.default_rng(100 + i), {
            "outfit": outfit, "jacket": False, "shoes": True, "cloth": "simulated", "texture_size": 64}))
        for motion in args.motions.split(","):
            clip = sm.retarget(sm.procedural_motion(motion, np.random.default_rng(0), seconds=args.seconds), human.skeleton)
            garments, collider = cloth_inputs(human, clip, s)
            frames, lead = {}, {}
            frames_at, lead_at = _recorded(collider.at, frames), _recorded(collider.lead, lead)
            for f in range(clip.n_frames):
                frames_at(f)
            clip_in = {"name": f"subject {i} {garment} {motion}", "pieces": [g.piece for g in garments],
                       "names": [g.name for g in garments], "faces": human.body.faces, "fps": clip.fps,
                       "frames": [frames[f] for f in range(clip.n_frames)], "lead": lead,
                       "seals": _seals(human, garments), "slippery": collider.slippery,
                       "incidence": human._incidence, "around": human._around}
            t = time.perf_counter()
            q = drape_clip(clip_in, s, lead=lead_at)  # records the lead's steps as it goes
            clip_in["cpu_q"], clip_in["cpu_s"] = q.astype(np.float32), time.perf_counter() - t
            clips.append(clip_in)
            print(clip_in["name"], f"{clip_in['cpu_s']:.1f} s on this CPU", file=sys.stderr, flush=True)
    os.makedirs(os.path.dirname(INPUTS), exist_ok=True)
    with lzma.open(INPUTS, "wb", preset=6) as f:
        pickle.dump(clips, f)
    return {"packed": len(clips), "bytes": os.path.getsize(INPUTS)}


def drape_clip(c: dict, s, lead=None) -> np.ndarray:
    """The cloth stage's drape of a packed clip under settings ``s``: the collider of
    ``cloth_inputs`` (frames, the arms' lead, the waist seals, slippery hands) replayed."""
    from synmitsuba.cloth.simulate import Collider, drape, out_of_body
    human = SimpleNamespace(body=SimpleNamespace(faces=c["faces"]), _incidence=c["incidence"], _around=c["around"])

    def at(frame: int) -> tuple[np.ndarray, np.ndarray]:
        body, q = c["frames"][frame]
        return body.astype(np.float64), q.astype(np.float64)

    def replay(w: float) -> tuple[np.ndarray, np.ndarray]:
        body, q = c["lead"][w]
        return body.astype(np.float64), q.astype(np.float64)

    def project(body: np.ndarray, q: np.ndarray) -> np.ndarray:  # as cloth_inputs' own
        for seal in c["seals"]:
            q = seal.apply(body, q)
        return out_of_body(human, body, q, s.particle_radius / 2)

    collider = Collider(c["faces"], at, c["fps"], len(c["frames"]), project, lead or replay, slippery=c["slippery"])
    return drape(c["pieces"], collider, s, names=c["names"])


# the block sizes Newton 1.8 launches these modules with on CUDA (a module named by a part of its
# name), where they differ from its default: the device's dry runs (bench/RESULTS.md 2026-11-27,
# 2026-12-04); VBD's tiled solve (32) loads on CUDA only, so it is compiled there
CUDA_BLOCK_DIMS = {"soft_face_contacts_False": (128,), "soft_edge_contacts_False": (128,),
                   "soft_contacts_mesh": (64, 256), "narrow_phase_primitive_write_contact": (128,)}


def warm(args) -> dict:
    """Compile, here, the CUDA binary of every Warp module a drape loads (see the module doc),
    with the block size a CUDA launch uses where ``CUDA_BLOCK_DIMS`` knows it."""
    import warp as wp
    wp.config.kernel_cache_dir = os.path.abspath(args.cache or CACHE)
    _forward_only(args)
    wp.init()
    from warp._src.context import Module

    from synmitsuba.cloth import ClothSettings
    load, done, rows = Module.load, set(), []

    def load_and_compile(self, device, block_dim=None, *a, **k):
        out = load(self, device, block_dim, *a, **k)
        dims = next((b for name, b in CUDA_BLOCK_DIMS.items() if name in self.name), (self.options["block_dim"],))
        for bd in dims:
            if (self.name, bd, self.get_module_hash(bd)) in done:
                continue
            done.add((self.name, bd, self.get_module_hash(bd)))
            t = time.perf_counter()
            try:
                self._compile(None, output_arch=args.arch, use_ptx=False,
                              options=self.resolve_options(wp.config, block_dim=bd))
            except RuntimeError as e:  # a module of generic kernels with no overload yet
                print(self.name, "skipped:", e, file=sys.stderr)
            rows.append({"module": self.get_module_identifier(bd), "block_dim": bd,
                         "compile_s": round(time.perf_counter() - t, 1)})
            print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
        return out

    with lzma.open(INPUTS, "rb") as f:
        clips = pickle.load(f)
    s = ClothSettings()
    Module.load = load_and_compile
    try:
        for c in clips:
            drape_clip(dict(c, frames=c["frames"][:args.frames]), s)
    finally:
        Module.load = load
    return {"warmed": rows, "arch": args.arch, "cache": args.cache or CACHE,
            "compile_s": round(sum(r["compile_s"] for r in rows), 1)}


def _forward_only(args) -> None:
    """Newton's kernels without their backward passes, as the CLI and generation workers make
    them (``configure_process``); ``--full-kernels``: with them."""
    from synmitsuba.process import SETTINGS
    SETTINGS.forward_only_kernels = not args.full_kernels


def precompile(clips: list, s, frames: int = 3, workers: int = 16, passthrough=lambda module: False) -> dict:
    """Compile, in parallel, every module variant a drape of ``clips`` loads on ``s.device``.

    NVRTC compiles one module at a time as a drape first launches it (Newton's take 8+ minutes
    in a row). A dry run finds them first: while it drapes a few frames, each load of a module on
    the target device is recorded (module, block size, hash) and answered with nothing, which
    makes Warp skip the launch; then the variants whose hash is still the module's are compiled
    by ``workers`` threads (NVRTC runs outside the GIL), and the real drape finds them cached.
    Variants a later overload made stale (their module changed during the dry run) are counted
    and left to compile in the real run. ``passthrough(module)`` true: load it for real (a test on
    the CPU passes Warp's own modules, graph colouring among them)."""
    import dataclasses
    import warp as wp
    from warp._src.context import Module
    target = wp.get_device(s.device)
    load, seen = Module.load, {}

    def record(self, device, block_dim=None, *a, **k):
        if wp.get_device(device) != target or passthrough(self):
            return load(self, device, block_dim, *a, **k)
        seen.setdefault((self.name, block_dim, self.get_module_hash(block_dim)), (self, block_dim))
        return None  # Warp's launch returns without running the kernel

    t = time.perf_counter()
    dry = dataclasses.replace(s, max_drift=1e9)  # no drift stops a dry run (kernels skipped)
    Module.load = record
    try:
        for c in clips:
            try:
                drape_clip(dict(c, frames=c["frames"][:frames]), dry)
            except Exception as e:  # the kernels did not run: what was recorded still counts
                print("dry run stopped:", repr(e)[:200], file=sys.stderr, flush=True)
    finally:
        Module.load = load
    dry_s = time.perf_counter() - t
    current = {k: v for k, v in seen.items() if v[0].get_module_hash(v[1]) == k[2]}

    def compile_one(item):
        module, block_dim = item
        t0 = time.perf_counter()
        load(module, target, block_dim)
        return {"module": module.name, "block_dim": block_dim, "s": round(time.perf_counter() - t0, 1)}

    from concurrent.futures import ThreadPoolExecutor
    t = time.perf_counter()
    with ThreadPoolExecutor(max_workers=workers) as pool:
        rows = []
        for r in pool.map(compile_one, current.values()):
            rows.append(r)
            print(json.dumps(r), file=sys.stderr, flush=True)
    return {"dry_run_s": round(dry_s, 1), "variants": len(seen), "stale": len(seen) - len(current),
            "parallel_compile_s": round(time.perf_counter() - t, 1), "modules": rows}


def run(args) -> dict:
    import dataclasses
    import warp as wp
    cache = args.cache or (CACHE if os.path.isdir(CACHE) else None)
    if cache:  # warmed ahead: CUBINs found there, new ones written there
        wp.config.kernel_cache_dir = os.path.abspath(cache)
        wp.config.cuda_output = "cubin"

    _forward_only(args)
    from synmitsuba.cloth import ClothError, ClothSettings
    with lzma.open(INPUTS, "rb") as f:
        clips = pickle.load(f)
    s = dataclasses.replace(ClothSettings(), device=args.device, full_contact=not args.vertex_contact)
    compiled = precompile(clips, s, workers=args.workers) if args.precompile else None
    if compiled:
        print(json.dumps({k: v for k, v in compiled.items() if k != "modules"}), file=sys.stderr, flush=True)
    settle = int(round(s.settle_s * clips[0]["fps"]))
    rows = []
    for k, c in enumerate(clips[:args.clips]):
        if args.frames_only:  # the drape is causal: its first frames are the whole clip's first frames
            n_full = len(c["frames"]) + settle
            c = dict(c, frames=c["frames"][:args.frames_only], cpu_q=c["cpu_q"][:args.frames_only],
                     cpu_s=c["cpu_s"] * (args.frames_only + settle) / n_full)
        times, qs = [], []
        try:
            for _ in range(2):
                t = time.perf_counter()
                qs.append(drape_clip(c, s))
                times.append(time.perf_counter() - t)
        except ClothError as e:  # the other clips still count
            rows.append({"clip": c["name"], "diverged": str(e)})
            print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
            continue
        n = len(c["frames"]) + settle
        rows.append({"clip": c["name"], "particles": int(qs[0].shape[1]), "frames": n,
                     "first_s": round(times[0], 2), "seconds_per_frame": round(times[1] / n, 4),
                     "cpu_here_seconds_per_frame": round(c["cpu_s"] / n, 4),
                     "max_dist_from_cpu_m": round(float(np.linalg.norm(qs[1] - c["cpu_q"], axis=2).max()), 4),
                     "median_dist_from_cpu_m": round(float(np.median(np.linalg.norm(qs[1] - c["cpu_q"], axis=2))), 5),
                     "runs_identical": bool(np.array_equal(qs[0], qs[1])),
                     "max_dist_between_runs_m": round(float(np.linalg.norm(qs[1] - qs[0], axis=2).max()), 5),
                     "median_dist_between_runs_m": round(float(np.median(np.linalg.norm(qs[1] - qs[0], axis=2))), 6)})
        print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    dev = wp.get_device(args.device)
    done = [r for r in rows if "diverged" not in r]
    return {"bench": "cloth_device", "device": f"{args.device}: {dev.name}", "warp": wp.config.version,
            "full_contact": s.full_contact, "forward_only": not args.full_kernels, "precompiled": compiled, "clips": rows,
            "seconds_per_frame_median": float(np.median([r["seconds_per_frame"] for r in done])) if done else None,
            "cpu_here_seconds_per_frame_median": float(np.median([r["cpu_here_seconds_per_frame"] for r in done[1:] or done]))
            if done else None}
    # the first clip packed here compiled Warp's CPU kernels: its CPU seconds are left out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("pack", "warm", "run"))
    ap.add_argument("--subjects", type=int, default=2)
    ap.add_argument("--motions", default="walk,run")
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--device", default="cuda", help="run: Warp's device (default cuda)")
    ap.add_argument("--arch", type=int, default=90, help="warm: the CUDA arch to compile for (90: H100, H200)")
    ap.add_argument("--frames", type=int, default=3, help="warm: frames of each clip to drape")
    ap.add_argument("--clips", type=int, default=None, help="run: the first N packed clips only")
    ap.add_argument("--precompile", action="store_true", help="run: compile every module in parallel first")
    ap.add_argument("--workers", type=int, default=16, help="run --precompile: compiling threads")
    ap.add_argument("--vertex-contact", action="store_true",
                    help="run: the body's vertices only (full_contact off; its CUDA modules compile in seconds)")
    ap.add_argument("--full-kernels", action="store_true", help="Newton's kernels with their backward passes")
    ap.add_argument("--frames-only", type=int, default=None, help="run: the first N frames of each clip")
    ap.add_argument("--cache", default=None, help="warm, run: Warp's kernel cache (default CACHE; run: when it exists)")
    args = ap.parse_args(argv)
    out = {"pack": pack, "warm": warm, "run": run}[args.what](args)
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
