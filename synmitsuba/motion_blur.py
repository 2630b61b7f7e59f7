"""Motion blur on deforming bodies: sub-frames across a shutter's exposure rendered and averaged
into one RGB (and its denoising guides), labels left at the exposure centre. Mitsuba has no
motion blur for deforming meshes, so the subjects are posed at three keys of the exposure and
moved linearly between them; moving cameras are interpolated per sub-frame.
"""
from __future__ import annotations

import bisect
from dataclasses import dataclass, field

import numpy as np

from synmitsuba.annotate.flow import Geometry, pixel_hits, points_at
from synmitsuba.rendering.denoise import guide_samples
from synmitsuba.rendering.passes import render_rgb
from synmitsuba.seeds import subframe_seed


def subframe_times(frame: int, shutter: float, subframes: int) -> list[float]:
    """Centres of ``subframes`` equal slices of the exposure [f - shutter / 2, f + shutter / 2]
    (in frames), so the sub-frames average to the exposure centre, frame f."""
    return [frame + shutter * ((k + 0.5) / subframes - 0.5) for k in range(subframes)]


def _camera_at(cameras: list, time: float):
    """A view's camera at fractional frame ``time`` (clamped to the clip)."""
    t = float(np.clip(time, 0, len(cameras) - 1))
    i = min(int(t), len(cameras) - 1)
    return cameras[i].blended(cameras[min(i + 1, len(cameras) - 1)], t - i)


@dataclass
class _Keys:
    """Subject shapes posed at a few times of the exposure; sub-frames between them move each
    vertex (normal, hair point) linearly, so a sub-frame costs an in-place update, not a posing."""

    names: list
    times: list = field(default_factory=list)
    meshes: list = field(default_factory=list)   # per key: {name: (vertices, normals)}
    curves: list = field(default_factory=list)   # per key: {name: points}

    def take(self, scene, time: float) -> None:
        """Add the shapes' positions now as the key at ``time`` (kept in time order)."""
        k = bisect.bisect(self.times, time)
        self.times.insert(k, float(time))
        self.meshes.insert(k, {n: (scene.meshes[n].vertices, scene.meshes[n].normals) for n in self.names
                               if n in scene.meshes})
        self.curves.insert(k, {n: scene.curves[n].points for n in self.names if n in scene.curves})

    def geometry(self, k: int) -> Geometry:
        """Key ``k`` as flow's ``Geometry``."""
        return Geometry({n: v for n, (v, _) in self.meshes[k].items()}, dict(self.curves[k]))

    def restore(self, scene, k: int) -> None:
        """Put key ``k``'s arrays back as they were (bit for bit)."""
        for n, (v, normals) in self.meshes[k].items():
            scene.update_mesh(n, v, normals)
        for n, p in self.curves[k].items():
            scene.update_curves(n, p)

    def move(self, scene, time: float) -> None:
        """Every shape where linear motion between the keys around ``time`` puts it."""
        k = int(np.clip(np.searchsorted(self.times, time) - 1, 0, len(self.times) - 2))
        a = (time - self.times[k]) / (self.times[k + 1] - self.times[k])
        for n, (v0, n0) in self.meshes[k].items():
            v1, n1 = self.meshes[k + 1][n]
            normals = None if n0 is None else (1 - a) * n0 + a * n1
            if normals is not None:
                normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
            scene.update_mesh(n, (1 - a) * v0 + a * v1, normals)
        for n, p0 in self.curves[k].items():
            scene.update_curves(n, (1 - a) * p0 + a * self.curves[k + 1][n])


def _exposure_keys(scene, placed: list, frame: int, times: list) -> _Keys:
    """The subjects posed at the exposure's first sub-frame, its centre (the frame, posed
    already: key 1) and its last sub-frame."""
    prefixes = tuple(f"{p.prefix}_" for p in placed)
    keys = _Keys([n for n in list(scene.meshes) + list(scene.curves) if n.startswith(prefixes)])
    keys.take(scene, frame)
    for t in (times[0], times[-1]):
        for p in placed:
            p.pose_at(scene, t)
        keys.take(scene, t)
    return keys


def exposure_motion(scene, keys: _Keys, cameras: list, frame: int, times: list) -> np.ndarray:
    """(H, W, 2) pixels: the image motion over the whole exposure of the point each pixel-centre
    ray hits at ``frame`` (its centre): where it is seen at the last sub-frame minus where at the
    first, times n / (n - 1) for the exposure's full length (the motion is taken linear, as the
    sub-frames take it). The blur's extent and direction; 0 on background. The scene holds the centre."""
    cam = cameras[frame]
    hits = pixel_hits(scene, cam)
    ends = []
    for k, t in ((0, times[0]), (2, times[-1])):
        P = points_at(scene, hits, cam.center, hits["rays"], keys.geometry(1), keys.geometry(k))
        ends.append((np.isfinite(P[:, 0]), _camera_at(cameras, t).project(np.nan_to_num(P))[0]))
    ok = ends[0][0] & ends[1][0]
    span = len(times) / (len(times) - 1)
    motion = np.where(ok[:, None], (ends[1][1] - ends[0][1]) * span, 0.0)
    return motion.reshape(cam.height, cam.width, 2).astype(np.float32)


@dataclass
class Exposure:
    """A view's motion-blurred frame: the RGB, the denoising guides averaged like it (with
    ``denoise="oidn"``), the blur vectors (``exposure_motion``, when asked for) and the
    sub-frame cameras (what an HDRI dome behind the people is averaged over)."""

    rgb: np.ndarray | None
    guides: tuple | None = None
    motion: np.ndarray | None = None
    cameras: list | None = None


class _Accumulator:
    """Sample-weighted sums of a view's sub-frame images."""

    def __init__(self):
        self.rgb, self.albedo, self.normal, self.cameras = 0.0, 0.0, 0.0, []

    def add(self, weight: float, rgb: np.ndarray, aux: tuple | None, aux_weight: float, camera) -> None:
        self.rgb = self.rgb + weight * rgb.astype(np.float64)
        self.cameras.append(camera)
        if aux is not None:
            self.albedo, self.normal = self.albedo + aux_weight * aux[0], self.normal + aux_weight * aux[1]

    def exposure(self, with_guides: bool) -> Exposure:
        guides = (np.asarray(self.albedo, np.float32), np.asarray(self.normal, np.float32)) if with_guides else None
        return Exposure(np.asarray(self.rgb, np.float32), guides, cameras=self.cameras)


def blurred_rgbs(scene, placed: list, views: list, frame: int, shutter: float, subframes: int, spp: int, seed: int,
                 render_args: dict, motion: bool = False, before_view=None) -> dict[str, Exposure]:
    """Each view's motion-blurred ``Exposure`` at ``frame`` (subjects posed there): ``min(subframes,
    spp)`` renders across the exposure, each with its share of ``spp`` (the total stays
    ``spp``), averaged by samples; with ``render_args["denoise"]`` not ``none`` the guides are
    traced per sub-frame too (``guide_samples(spp)`` shared likewise) so they blur as the colour does.
    Subjects are posed at the exposure's first and last sub-frame and its centre, and move
    linearly between those keys (``_Keys``); moving cameras are blended per sub-frame. The scene
    is left posed at ``frame`` with its previous positions (flow's) as they were. With
    ``motion``, each view's ``exposure_motion``. ``before_view(view)`` readies the scene for a
    view before each of its renders (an HDRI backdrop projected from its camera)."""
    n = min(subframes, spp)
    shares = [spp // n + (k < spp % n) for k in range(n)]
    times = subframe_times(frame, shutter, n)
    args = {k: v for k, v in render_args.items() if k in ("max_depth", "rfilter", "sampler")}
    denoised = render_args.get("denoise", "none") != "none"
    guide_spp = max(1, guide_samples(spp) // n) if denoised else 0
    sums = {v.name: _Accumulator() for v in views}
    with scene.keeping_previous():
        keys = _exposure_keys(scene, placed, frame, times) if n > 1 else None
        for k, (t, share) in enumerate(zip(times, shares)):
            if keys is not None:
                keys.move(scene, t)
            for v in views:
                if before_view is not None:
                    before_view(v)
                cam = _camera_at(v.cameras, t)
                rgb, aux = render_rgb(scene, cam, share, subframe_seed(seed + frame, k), guide_spp=guide_spp, **args)
                sums[v.name].add(share / spp, rgb, aux, 1 / n, cam)  # guides: the same spp every sub-frame
        out = {name: acc.exposure(denoised) for name, acc in sums.items()}
        if keys is not None:
            keys.restore(scene, 1)  # the frame's own positions, bit for bit
            if motion:
                for v in views:
                    out[v.name].motion = exposure_motion(scene, keys, v.cameras, frame, times)
    return out
