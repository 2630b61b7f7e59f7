"""Sampler choice and denoising of the path-traced RGB.

Sampler (measured on the demo scene, 160x134, against a 4096-spp reference; bench/RESULTS.md):
at equal spp ``ldsampler`` beats ``independent`` by +4.9 dB at 4 spp and +8.1 dB at 16, and
16 ldsampler spp (0.30 s, 35.7 dB) beat 64 independent spp (0.82 s, 32.4 dB). Mitsuba rounds
the sample count of every sampler but ``independent`` (ldsampler to a power of 4, multijitter
and stratified to products it can stratify), so ``auto`` takes the best sampler that keeps
the requested count exactly: a sample always has the spp it asked for. Under an HDRI it
prefers multijitter (+2.5 dB at 16 spp over ldsampler; bench/samplers.py).

Denoising: Intel Open Image Denoise (``pyoidn``, ``pip install synmitsuba[denoise]``) on the
linear HDR colour with albedo and normal guides rendered by Mitsuba's ``aov`` integrator
(primary hit, averaged over the pixel with the same box filter as the colour, so they are
anti-aliased like it and nearly noise-free; passed as clean guides). OIDN's inference, not
the guides, is denoising's cost (256x256 on 2 cores: guides 0.02 s, OIDN 0.15 s at its ``high``
quality, 0.07 s ``balanced``, 0.04 s ``fast``): ``denoise="oidn-balanced"`` / ``"oidn-fast"``
choose the cheaper networks.
"""
from __future__ import annotations

import functools

import numpy as np

from synmitsuba.errors import ConfigError
GUIDE_SPP = 16


def guide_samples(spp: int) -> int:
    """Samples per pixel of the guides for a colour of ``spp``: 16, doubled from 4 spp on (sky-only
    scene, 256 px, OIDN high: 32 instead of 16 gain 0.25 dB at 1 spp for 10 % more time, 0.44 dB
    at 4 spp and 0.75 dB at 16 for 5-9 %; bench/RESULTS.md)."""
    return GUIDE_SPP if spp < 4 else 2 * GUIDE_SPP


@functools.lru_cache(maxsize=4)
def _aov_integrator(variant: str):
    import mitsuba as mi
    return mi.load_dict({"type": "aov", "aovs": "albedo:albedo,nn:sh_normal"})


def guides(mi_scene, sensor_dict: dict, seed: int, spp: int = GUIDE_SPP) -> tuple[np.ndarray, np.ndarray]:
    """(albedo, normal) (H, W, 3) float32 of the primary hits, averaged over each pixel (through
    the same sensor as the colour: its lens distortion and depth of field blur them alike)."""
    import mitsuba as mi
    sensor = mi.load_dict({**sensor_dict, "sampler": {"type": "independent", "sample_count": spp}})
    img = np.array(mi.render(mi_scene, sensor=sensor, integrator=_aov_integrator(mi.variant()), spp=spp, seed=seed))
    return np.ascontiguousarray(img[..., 0:3], np.float32), np.ascontiguousarray(img[..., 3:6], np.float32)


def oidn(rgb: np.ndarray, albedo: np.ndarray, normal: np.ndarray, quality: str = "high") -> np.ndarray:
    """The denoised linear HDR RGB (float32); ``quality``: OIDN's ``high``, ``balanced`` or ``fast``."""
    try:
        import pyoidn
    except ImportError:
        raise ConfigError("denoise", "oidn", "the denoiser is not installed: pip install 'synmitsuba[denoise]' "
                          "(Intel Open Image Denoise, pyoidn), or render with denoise='none'") from None
    out = pyoidn.denoise(np.ascontiguousarray(rgb, np.float32), albedo, np.clip(normal, -1, 1), hdr=True,
                         clean_aux=True, quality=quality)
    return np.maximum(np.asarray(out, np.float32), 0.0)
