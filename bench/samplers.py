"""Mitsuba's samplers per kind of scene (issue 39): raw PSNR at equal spp against a high-spp
reference, on render_quality.py's three scenes (sun + sky with subjects, HDRI with subjects,
sky only), and the same with OIDN; then the pixel filter (box, ours, against Mitsuba's gaussian
and tent, the kind Cycles' default Blackman-Harris 1.5 px is) at 16 spp ldsampler. Mean PSNR
of the sRGB image over ``--seeds`` seeds (each filter against its own reference) and the median
seconds of the RGB. Prints JSON.

    python bench/samplers.py [--res 256] [--ref-spp 2048] [--seeds 3] [--subjects FILE]
"""
import argparse
import json
import sys

import numpy as np
from render_quality import SCENES, build_scene, srgb


SAMPLERS = ("independent", "stratified", "multijitter", "ldsampler", "orthogonal")
SPPS = (1, 4, 16, 64)


def _keeps(sampler: str, spp: int) -> bool:
    """Whether Mitsuba's ``sampler`` takes ``spp`` as it is (what ``choose_sampler`` checks)."""
    from synmitsuba.engine.settings import choose_sampler
    from synmitsuba.errors import ConfigError
    try:
        return choose_sampler(sampler, spp) == sampler
    except ConfigError:
        return False


def psnr_of(img, ref) -> float:
    from synmitsuba.metrics import psnr
    return psnr(srgb(img), srgb(ref))


def mean_psnr(scene, camera, ref, seeds: int, **kw) -> list:
    """[mean PSNR, median seconds of the RGB (path tracing and denoising)] over the seeds."""
    import synmitsuba as sm
    sm.render(scene, camera, seed=99, **kw)  # kernels compiled before timing
    samples = [sm.render(scene, camera, seed=s, **kw) for s in range(seeds)]
    seconds = np.median([s.timings["rgb"] + s.timings["denoise"] for s in samples])
    return [round(float(np.mean([psnr_of(s.rgb, ref) for s in samples])), 2), round(float(seconds), 3)]


def reference(scene, camera, spp: int, rfilter: str = "box") -> np.ndarray:
    import synmitsuba as sm
    return np.mean([sm.render(scene, camera, spp=256, seed=1000 + k, rfilter=rfilter).rgb for k in range(spp // 256)], 0)


def study(scene, camera, ref_spp: int, seeds: int) -> dict:
    ref = reference(scene, camera, ref_spp)
    out: dict = {"raw": {}, "oidn": {}, "filter_16spp": {}}
    for sampler in SAMPLERS:
        out["raw"][sampler] = {spp: mean_psnr(scene, camera, ref, seeds, spp=spp, sampler=sampler)
                               for spp in SPPS if _keeps(sampler, spp)}
        out["oidn"][sampler] = {spp: mean_psnr(scene, camera, ref, seeds, spp=spp, sampler=sampler, denoise="oidn")
                                for spp in (1, 4, 16) if _keeps(sampler, spp)}
    for rfilter in ("box", "tent", "gaussian"):
        ref_f = ref if rfilter == "box" else reference(scene, camera, ref_spp, rfilter)  # each against its own
        out["filter_16spp"][rfilter] = mean_psnr(scene, camera, ref_f, seeds, spp=16, rfilter=rfilter)
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--subjects", help="file of built subjects (subject_cache.py)")
    args = ap.parse_args(argv)
    import synmitsuba as sm
    sm.set_variant()
    out = {"bench": "samplers", "res": args.res, "ref_spp": args.ref_spp, "seeds": args.seeds}
    for kind in args.scenes.split(","):
        out[kind] = study(*build_scene(args.res, args.subjects, kind), args.ref_spp, args.seeds)
        print(kind, json.dumps(out[kind]), file=sys.stderr, flush=True)
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
