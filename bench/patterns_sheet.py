"""docs/patterns.png: patterned garments on their panels (``body.panels``), front, side and back:
checks, stripes and plaid on tops, trousers, a skirt, a dress and a jumpsuit (each garment's
drawn texture with its pattern, scale (per metre) and colours set so the grain shows).

    python bench/patterns_sheet.py [--out docs/patterns.png] [--spp 24] [--size 1024]
"""
from __future__ import annotations

import argparse
import dataclasses

import numpy as np

# (outfit, {garment kind: pattern}) per row
ROWS = ((("tshirt", "trousers", "sneakers"), {"tshirt": "checks", "trousers": "stripes"}),
        (("longsleeve", "skirt", "boots"), {"longsleeve": "stripes", "skirt": "checks"}),
        (("dress", "sandals"), {"dress": "plaid"}),
        (("shirt", "chinos", "dress_shoes"), {"shirt": "plaid", "chinos": "checks"}),
        (("hoodie", "joggers", "sneakers"), {"hoodie": "checks", "joggers": "plaid"}),
        (("jumpsuit", "sneakers"), {"jumpsuit": "checks"}))
YAWS = (20.0, 90.0, 160.0, 200.0)


def patterned(recipe, patterns: dict):
    """``recipe`` with each named garment's texture in its pattern: light base, dark pattern."""
    garments = []
    for g in recipe.garments:
        if g.kind in patterns:
            g = dataclasses.replace(g, texture=dataclasses.replace(
                g.texture, pattern=patterns[g.kind], pattern_scale=7.0, pattern_width=0.25, pattern_alpha=1.0,
                uv_rotation_deg=0.0, base_lab=[82.0, 0.0, 5.0], pattern_lab=[30.0, 15.0, -40.0], bump="none",
                decal="none"))
        garments.append(g)
    return dataclasses.replace(recipe, garments=garments)


def main() -> int:
    import synmitsuba as sm
    from synmitsuba.compose.backdrop import centre_backdrop
    from synmitsuba.compose.stage import preview_stage
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/patterns.png")
    ap.add_argument("--spp", type=int, default=24)
    ap.add_argument("--size", type=int, default=1024, help="garment texture side")
    args = ap.parse_args()
    sm.set_variant()
    images = []
    for k, (outfit, patterns) in enumerate(ROWS):
        recipe = sm.sample_subject(np.random.default_rng(40 + k), {"outfit": list(outfit), "jacket": False,
                                                                    "accessories": [], "texture_size": args.size})
        human = sm.build_subject(patterned(recipe, patterns))
        scene = preview_stage()
        rot, root = human.standing()
        human.add_to(scene, rot, root, instance=1)
        for yaw in YAWS:
            a, centre = np.radians(yaw), np.array([0.0, 0.92, 0.0])
            cam = sm.Camera.look_at(eye=centre + [3.2 * np.sin(a), 0.1, 3.2 * np.cos(a)], target=centre,
                                    fov_y_deg=36, width=240, height=400)
            centre_backdrop(scene, cam.center)
            images.append(sm.to_srgb8(sm.render(scene, cam, spp=args.spp, seed=k).rgb))
    print(sm.write_png(args.out, sm.contact_sheet(images, columns=len(YAWS))))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
