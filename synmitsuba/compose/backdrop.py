"""HDRI backdrops projected onto the ground, as BEDLAM's HDRI scenes: people stand on the photo's
own ground, which catches their shadows, and a key light stands where the photo's sun is.

The panorama was shot from a point ``height_m`` above its ground. A ground point p (y = 0) is
given the panorama's radiance L in the direction from that point to p, as a diffuse albedo
``pi L / E`` where E is the irradiance the unoccluded ground receives from the (sun-less)
panorama and the key light: unshadowed, the ground renders as the photo; where a person blocks
the light, it darkens as a shadow in the photo would. The ground is a polar mesh around the
projection centre whose rows are the panorama's own elevations, out to 0.05 degrees below the
horizon; beyond it rays meet the panorama itself.

A projection is exact only from its own point: seen from elsewhere, the photo's ground smears
into streaks (near the horizon one panorama row spans a metre of ground) and whatever stood on
it (furniture, walls) lies flat. So each view is rendered with the projection moved above its
camera (``centre_backdrop``; ``view_projection_point``), as BEDLAM shoots from the HDRI's own
point; the ground does not move over a view's clip, so it stays still as the camera moves.

Directions follow Mitsuba's ``envmap`` (checked against its ``eval`` in tests/test_backdrop.py):
pixel (row, col) of an H x W panorama looks along theta = pi (row + 0.5) / H from +y and
phi = 2 pi (col + 0.5) / W, local d = (sin theta sin phi, cos theta, -sin theta cos phi), then
turned ``rotation_deg`` about +y.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.scene.panorama import Dome, lookup, pixel_directions, rot_y, solid_angles

SUN_RATIO = 30.0          # a sun is a peak at least this many times the sky's 99th percentile
SUN_RADIUS_DEG = 6.0      # what is taken from the panorama around the peak


@dataclass
class HdriSun:
    """A sun found in a panorama: ``direction`` towards it (world, unit), ``irradiance`` (RGB)
    on a plane facing it, ``pixels``: the panorama with the sun replaced by its surroundings."""

    direction: np.ndarray
    irradiance: np.ndarray
    pixels: np.ndarray


def ground_irradiance(pixels: np.ndarray) -> np.ndarray:
    """RGB irradiance on an unoccluded horizontal plane from the panorama's upper half."""
    h, w = pixels.shape[:2]
    cos_t = np.cos(np.pi * (np.arange(h) + 0.5) / h)[:, None]
    weight = solid_angles(h, w) * np.clip(cos_t, 0, None)
    return (pixels * weight[..., None]).sum((0, 1))


def find_sun(pixels: np.ndarray, rotation_deg: float = 0.0) -> HdriSun | None:
    """The panorama's sun, if its brightest sky pixel is ``SUN_RATIO`` times the sky's 99th
    percentile: every pixel within ``SUN_RADIUS_DEG`` of the peak and brighter than the ring
    around it gives its excess over that ring to a directional key light."""
    h, w = pixels.shape[:2]
    lum = pixels @ np.array([0.2126, 0.7152, 0.0722])
    sky = lum[: h // 2]
    peak = np.unravel_index(np.argmax(sky), sky.shape)
    if sky[peak] < SUN_RATIO * np.percentile(sky, 99):
        return None
    dirs = pixel_directions(h, w)
    cos_dist = dirs @ dirs[peak]
    disc, ring = cos_dist > np.cos(np.radians(SUN_RADIUS_DEG)), (cos_dist > np.cos(np.radians(1.5 * SUN_RADIUS_DEG)))
    ring &= ~disc
    level = np.median(pixels[ring], axis=0)
    excess = np.where(disc[..., None], np.clip(pixels - level, 0, None), 0.0)
    weight = solid_angles(h, w)[..., None] * excess
    irradiance = weight.sum((0, 1))
    direction = (dirs * (weight @ np.array([0.2126, 0.7152, 0.0722]))[..., None]).sum((0, 1))
    direction = rot_y(rotation_deg) @ (direction / np.linalg.norm(direction))
    return HdriSun(direction, irradiance, (pixels - excess).astype(np.float32))


def _below(f: np.ndarray, height_m: float, radius_m: float) -> np.ndarray:
    """Radians below the projection point's horizon at ring fraction f: 0 straight down .. 1 at
    the disc's edge."""
    edge = np.arctan2(height_m, radius_m)
    return np.pi / 2 - 1e-5 + f * (edge - np.pi / 2 + 1e-5)


def projected_ground_mesh(height_m: float, radius_m: float, rows: int, cols: int, tex_rows: int, centre=(0.0, 0.0)):
    """A polar ground disc of ``radius_m`` around ``centre`` (x, z): ``rows`` rings evenly spaced
    in elevation as seen from the projection point ``height_m`` up, ``cols`` segments; returns
    vertices, faces and uv (u: azimuth 0..1 with a seam column; v: the ring's texel-centre row
    in a ``tex_rows`` texture, up as OBJ's)."""
    f = np.linspace(0.0, 1.0, rows)
    dist = height_m / np.tan(_below(f, height_m, radius_m))
    az = 2 * np.pi * np.arange(cols + 1) / cols
    D, A = np.meshgrid(dist, az, indexing="ij")
    verts = np.stack([centre[0] + D * np.sin(A), np.zeros_like(D), centre[1] - D * np.cos(A)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(rows - 1), np.arange(cols), indexing="ij")
    a = (i * (cols + 1) + j).ravel()
    b, c, d = a + 1, a + cols + 2, a + cols + 1
    faces = np.concatenate([np.stack([a, d, c], 1), np.stack([a, c, b], 1)])
    n = np.cross(verts[faces[:, 1]] - verts[faces[:, 0]], verts[faces[:, 2]] - verts[faces[:, 0]])
    faces = np.where((n[:, 1] < 0)[:, None], faces[:, [0, 2, 1]], faces)   # all facing +y
    v_tex = (0.5 + np.repeat(f, cols + 1) * (tex_rows - 1)) / tex_rows
    uv = np.stack([np.tile(np.arange(cols + 1) / cols, rows), 1.0 - v_tex], 1)
    return verts, faces, uv


def ground_albedo(pixels: np.ndarray, rotation_deg: float, height_m: float, radius_m: float, rows: int, cols: int,
                  irradiance: np.ndarray) -> np.ndarray:
    """(rows, cols, 3) shadow-catching albedo ``pi L / E`` (at most 1) of the polar ground's
    texture: row r at ring fraction r / (rows - 1), column c at azimuth 2 pi (c + 0.5) / cols."""
    below = _below(np.linspace(0.0, 1.0, rows), height_m, radius_m)
    B, A = np.meshgrid(below, 2 * np.pi * (np.arange(cols) + 0.5) / cols, indexing="ij")
    d = np.stack([np.cos(B) * np.sin(A), -np.sin(B), -np.cos(B) * np.cos(A)], -1)
    albedo = np.pi * lookup(pixels, d, rotation_deg) / np.maximum(irradiance, 1e-9)
    # brighter than the light allows (sunlit ground of a panorama whose sun is clipped): scaled
    # down whole, so its hue stays
    return (albedo / np.maximum(albedo.max(-1, keepdims=True), 1.0)).astype(np.float32)


TEX_ROWS, TEX_COLS = 512, 2048   # the ground's texture: under 0.18 degrees a texel
MESH_ROWS, MESH_COLS = 256, 256


def add_backdrop(scene, lighting, height_m: float, radius_m: float, centre=(0.0, 0.0),
                 key_light: bool = True) -> HdriSun | None:
    """The drawn HDRI ``lighting`` (an ``EnvmapLighting``) as the environment seen on a dome of
    ``radius_m``, its sun (if any and ``key_light``) as a directional light, and the ground
    disc projected from ``height_m`` above ``centre`` as a shadow catcher (instance and layer
    of a ground). Returns the sun."""
    from synmitsuba.compose.instances import GROUND_INSTANCE
    from synmitsuba.scene.layers import Layer
    from synmitsuba.scene.materials import DirectionalLight, EnvMap, Material
    env = lighting.emitter()
    pixels = env.pixels()
    sun = find_sun(pixels, env.rotation_deg) if key_light else None
    if sun is not None:
        pixels = sun.pixels
        scene.add_light(DirectionalLight(direction=tuple(-sun.direction), irradiance=tuple(env.scale * sun.irradiance)))
    dome = Dome((float(centre[0]), float(height_m), float(centre[1])), float(radius_m))
    scene.set_environment(EnvMap(source=pixels, scale=env.scale, rotation_deg=env.rotation_deg, dome=dome))
    irradiance = ground_irradiance(pixels) + (0 if sun is None else sun.irradiance * max(sun.direction[1], 0.0))
    albedo = ground_albedo(pixels, env.rotation_deg, height_m, radius_m, TEX_ROWS, TEX_COLS, irradiance)
    v, f, uv = projected_ground_mesh(height_m, radius_m, MESH_ROWS, MESH_COLS, TEX_ROWS, centre)
    scene.add_mesh("ground", v, f, uv=uv, normals=np.tile([0, 1.0, 0], (len(v), 1)),
                   material=Material(texture=albedo, kind="diffuse", name="ground"),
                   instance=GROUND_INSTANCE, layer=int(Layer.GROUND))
    return sun


def view_projection_point(cameras: list) -> np.ndarray:
    """Where a view's backdrop is projected from: its camera at the clip's middle frame (fixed
    over the clip, so the photo's ground moves with the world, not with the camera)."""
    return np.asarray(cameras[len(cameras) // 2].center, np.float64)


def centre_backdrop(scene, point) -> bool:
    """Project the scene's backdrop from above ``point`` (x, _, z): the ground disc, whose
    texture is polar about its own centre, and the dome move there (the height stays the
    photo's). Built afresh from the point, so a view renders the same bits whichever views came
    before it. False (nothing done) without a backdrop or when it is there already."""
    env = scene.environment
    dome = getattr(env, "dome", None)
    if dome is None or "ground" not in scene.meshes:
        return False
    x, z = float(point[0]), float(point[2])
    if (x, z) == (dome.centre[0], dome.centre[2]):
        return False
    height = dome.centre[1]
    v, _, _ = projected_ground_mesh(height, dome.radius_m, MESH_ROWS, MESH_COLS, TEX_ROWS, (x, z))
    ground = scene.meshes["ground"]
    scene.update_mesh("ground", v, normals=ground.normals)
    ground.previous_vertices = ground.vertices    # the ground stands still in time (flow)
    env.dome = Dome((x, height, z), dome.radius_m)
    return True
