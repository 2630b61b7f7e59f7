"""Cost of motion blur: the same frames of a composed sequence with and without a shutter, at
equal total spp (sub-frames share it), labelled or not. Prints JSON: seconds per frame (the
first frame, with its kernel compiles, left out) and the blurred / sharp ratio.

    python bench/motion_blur.py [--config configs/demo.yaml] [--spp 32] [--res 320x240] [--subframes 8] [--denoise oidn]
                                [--frames 5] [--what both|rgb|labelled]
"""
import argparse
import json
import time


def frame_times(spec, frames, spp, shutter, subframes, annotate, denoise):
    from synmitsuba.pipeline import render_sequence
    out, t0 = [], time.perf_counter()
    for _ in render_sequence(spec, frames=frames, spp=spp, seed=7, shutter=shutter, subframes=subframes,
                             annotate=annotate, denoise=denoise):
        out.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
    return out[1:]


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", default="configs/demo.yaml")
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--res", default="320x240")
    ap.add_argument("--subframes", type=int, default=8)
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--denoise", default="none", help="none or oidn (guides traced per sub-frame too)")
    ap.add_argument("--what", default="both", choices=["both", "rgb", "labelled"],
                    help="RGB and exact passes, with labels and flow, or both (large frames: one at a time)")
    args = ap.parse_args(argv)
    import synmitsuba as sm
    from synmitsuba.generate.config import load_generate_config
    from synmitsuba.generate.run import sequence_spec
    variant = sm.set_variant()
    w, h = (int(x) for x in args.res.split("x"))
    spec = sequence_spec(load_generate_config(args.config), 0)
    spec.views = spec.views[:1]
    spec.views[0].cameras = [c.resized(w, h) for c in spec.views[0].cameras]
    frames = list(range(0, 2 * args.frames, 2))
    result = {"variant": variant, "denoise": args.denoise, "spp": args.spp, "res": args.res, "subframes": args.subframes, "subjects": len(spec.subjects)}
    for annotate in {"both": (False, True), "rgb": (False,), "labelled": (True,)}[args.what]:
        sharp = frame_times(spec, frames, args.spp, 0.0, args.subframes, annotate, args.denoise)
        blur = frame_times(spec, frames, args.spp, 0.5, args.subframes, annotate, args.denoise)
        key = "labelled" if annotate else "rgb_and_passes"
        result[key] = {"sharp_s": sum(sharp) / len(sharp), "blurred_s": sum(blur) / len(blur),
                       "ratio": sum(blur) / sum(sharp)}
    print(json.dumps(result, indent=1))
    return result


if __name__ == "__main__":
    main()
