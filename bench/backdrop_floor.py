"""Where an HDRI's floor is open, for a backdrop's ``floor_m`` and ``floor_sectors``: twelve
views of the panorama from where it was shot (every 30 degrees of panorama azimuth, looking
down), with rings on the ground at 2, 4, 6 (magenta), 8 and 12 m and lines every 10 degrees
of azimuth (red every 30). Read off how far the floor stays open before walls, fences, water
or furniture, per sector. Prints JSON (the sheet's path).

    python bench/backdrop_floor.py scenes/hdri/forest.exr --height 1.7 --out out/forest_floor.png
"""
import argparse
import json

import numpy as np

RINGS_M = (2, 4, 6, 8, 12)


def floor_view(pixels: np.ndarray, azimuth: float, height: float, size=(240, 180)) -> np.ndarray:
    """The panorama seen from its shooting point along panorama ``azimuth`` (degrees), 20
    degrees down, with the distance rings and azimuth lines drawn on the ground."""
    import synmitsuba as sm
    from synmitsuba.scene.panorama import azimuth_deg, lookup
    phi = np.radians(azimuth)
    eye = np.array([0.0, height, 0.0])
    cam = sm.Camera.look_at(eye, eye + [10 * np.sin(phi), -3.5, -10 * np.cos(phi)], fov_y_deg=50,
                            width=size[0], height=size[1])
    rays = cam.pixel_rays()
    img = lookup(pixels, rays) / (np.percentile(pixels, 90) / 0.6)
    down = rays[..., 1] < 0
    dist = np.where(down, height / np.maximum(-rays[..., 1], 1e-9) * np.hypot(rays[..., 0], rays[..., 2]), np.inf)
    for r in RINGS_M:
        img[np.abs(dist - r) < 0.02 * r] = [1, 0, 1] if r == 6 else [0, 1, 1]
    az = azimuth_deg(rays)
    for k in range(0, 360, 10):
        img[(np.abs((az - k + 180) % 360 - 180) < 0.25) & down] = [1, 0, 0] if k % 30 == 0 else [1, 1, 0]
    return np.clip(img, 0, 1)


def main(argv=None):
    import synmitsuba as sm
    from synmitsuba.io.preview import contact_sheet, to_srgb8, write_png
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("hdri", help="an equirectangular .exr or .hdr")
    ap.add_argument("--height", type=float, default=1.7, help="metres above its ground it was shot (backdrop.height_m)")
    ap.add_argument("--out", default="out/backdrop_floor.png")
    args = ap.parse_args(argv)
    pixels = sm.EnvMap(source=args.hdri).pixels()
    tiles = [to_srgb8(floor_view(pixels, az, args.height)) for az in range(0, 360, 30)]
    write_png(args.out, contact_sheet(tiles, 4))
    print(json.dumps({"sheet": args.out, "azimuths_deg": list(range(0, 360, 30)), "rings_m": list(RINGS_M)}))


if __name__ == "__main__":
    main()
