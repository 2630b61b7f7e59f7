"""docs/styles.png: one subject in each garment style drawn in place of a base kind
(``body.garments.GARMENT_STYLES``) and in heels, standing in its shoes, front and back.

    python bench/styles_sheet.py [--out docs/styles.png] [--spp 24]
"""
from __future__ import annotations

import argparse

import numpy as np

OUTFITS = (("tank", "jeans", "sneakers"), ("sweater", "trousers", "boots"), ("tshirt", "jeans", "coat", "dress_shoes"),
           ("shift", "heels"), ("wrap", "sandals"), ("jumpsuit", "sneakers"), ("tshirt", "skirt", "heels"),
           ("shirt", "chinos", "blazer", "dress_shoes"), ("tshirt", "joggers", "sneakers"),
           ("shirt", "jeans", "boots"), ("hoodie", "joggers", "sneakers"))


def main() -> int:
    import synmitsuba as sm
    from synmitsuba.compose.backdrop import centre_backdrop
    from synmitsuba.compose.stage import preview_stage
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/styles.png")
    ap.add_argument("--spp", type=int, default=24)
    args = ap.parse_args()
    sm.set_variant()
    images = []
    for k, outfit in enumerate(OUTFITS):
        recipe = sm.sample_subject(np.random.default_rng(20 + k), {"outfit": list(outfit), "jacket": False,
                                                                    "accessories": []})
        human = sm.build_subject(recipe)
        scene = preview_stage()
        rot, root = human.standing()
        human.add_to(scene, rot, root, instance=1)
        for yaw in (20.0, 160.0):
            a, centre = np.radians(yaw), np.array([0.0, 0.92, 0.0])
            cam = sm.Camera.look_at(eye=centre + [3.2 * np.sin(a), 0.1, 3.2 * np.cos(a)], target=centre,
                                    fov_y_deg=36, width=200, height=340)
            centre_backdrop(scene, cam.center)
            images.append(sm.to_srgb8(sm.render(scene, cam, spp=args.spp, seed=k).rgb))
    print(sm.write_png(args.out, sm.contact_sheet(images, columns=6)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
