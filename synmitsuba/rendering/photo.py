"""A camera's development of the rendered radiance into a photo: metered exposure with a bias,
a white-balance error, photon and read noise at an ISO, and JPEG compression, in that order
(the order a camera applies them). The labels never see any of it; the rendered radiance stays
in the sample as ``rgb_clean``.

- Exposure: the image is scaled so its log-average luminance (the scene's "key", as a
  matrix meter averages) lands on 18 % grey, times 2^bias.
- White balance: the camera balanced for a light of ``white_balance_k`` kelvin while the
  scene's white is D65: each channel is scaled by D65's linear sRGB over that light's (Kang et
  al. 2002 Planckian locus), green kept, so a lower temperature turns the image blue.
- Sensor: 1.0 is a full well of ``full_well_e`` electrons at ISO 100 (``full_well_e * 100 /
  iso`` at ``iso``); each pixel counts Poisson electrons plus Gaussian read noise of
  ``read_noise_e``, then clips at saturation.
- JPEG: the sRGB-encoded 8-bit image through Pillow's encoder at ``jpeg_quality`` and back to
  linear (0: none).
"""
from __future__ import annotations

import io
from dataclasses import asdict, dataclass

import numpy as np

from synmitsuba._colour import XYZ_TO_RGB, srgb_decode, srgb_encode
from synmitsuba.schema import Flag, Number, Params, Range, spec

LUMA = np.array([0.2126, 0.7152, 0.0722])  # linear sRGB -> relative luminance Y
MIDDLE_GREY = 0.18


@dataclass(frozen=True)
class Photo:
    """One image's development settings (what a sample's meta stores as ``photo``)."""

    exposure_bias_ev: float = 0.0
    white_balance_k: float = 6504.0
    iso: float = 100.0
    full_well_e: float = 20000.0
    read_noise_e: float = 3.0
    jpeg_quality: int = 0

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass
class PhotoOptions(Params):
    """A generation's photo development (``render.photo``): ranges drawn per sequence."""

    enabled: bool = spec(False, Flag(), doc="develop the radiance into a photo (the raw render stays as rgb_clean)")
    exposure_bias_ev: list = spec(factory=lambda: [-1.0, 1.0], check=Range(-5, 5), doc="on the metered exposure, stops")
    white_balance_k: list = spec(factory=lambda: [5000.0, 8000.0], check=Range(1667, 25000),
                                 doc="the light the camera balanced for, kelvin (the scene's white is D65, 6504 K)")
    iso: list = spec(factory=lambda: [100.0, 1600.0], check=Range(25, 102400))
    full_well_e: float = spec(20000.0, Number(100, 1e6), doc="electrons at saturation, ISO 100")
    read_noise_e: float = spec(3.0, Number(0, 100), doc="electrons, standard deviation")
    jpeg_quality: list = spec(factory=lambda: [0, 0], check=Range(0, 100), doc="Pillow JPEG quality range; 0: no JPEG")

    def draw(self, rng: np.random.Generator) -> Photo:
        """One sequence's settings; ISO log-uniform."""
        q = int(round(rng.uniform(*self.jpeg_quality))) if any(self.jpeg_quality) else 0
        return Photo(float(rng.uniform(*self.exposure_bias_ev)), float(rng.uniform(*self.white_balance_k)),
                     float(np.exp(rng.uniform(*np.log(self.iso)))), self.full_well_e, self.read_noise_e, max(q, 1) if q else 0)


def planck_xy(kelvin: float) -> tuple[float, float]:
    """CIE 1931 chromaticity of a black body at ``kelvin`` (Kang et al. 2002 cubics, 1667-25000 K)."""
    T = float(np.clip(kelvin, 1667.0, 25000.0))
    if T <= 4000:
        x = -0.2661239e9 / T ** 3 - 0.2343589e6 / T ** 2 + 0.8776956e3 / T + 0.179910
    else:
        x = -3.0258469e9 / T ** 3 + 2.1070379e6 / T ** 2 + 0.2226347e3 / T + 0.240390
    if T <= 2222:
        y = -1.1063814 * x ** 3 - 1.34811020 * x ** 2 + 2.18555832 * x - 0.20219683
    elif T <= 4000:
        y = -0.9549476 * x ** 3 - 1.37418593 * x ** 2 + 2.09137015 * x - 0.16748867
    else:
        y = 3.0817580 * x ** 3 - 5.87338670 * x ** 2 + 3.75112997 * x - 0.37001483
    return x, y


def _white_rgb(kelvin: float) -> np.ndarray:
    x, y = planck_xy(kelvin)
    return XYZ_TO_RGB @ np.array([x / y, 1.0, (1 - x - y) / y])


def white_balance_gains(kelvin: float) -> np.ndarray:
    """(3,) channel gains of a camera balanced for ``kelvin`` under a D65-white scene (green 1)."""
    g = _white_rgb(6504.0) / _white_rgb(kelvin)
    return g / g[1]


def metered_scale(rgb: np.ndarray, bias_ev: float = 0.0) -> float:
    """The factor that puts the image's log-average luminance on 18 % grey, times 2^bias."""
    lum = np.asarray(rgb, np.float64) @ LUMA
    key = float(np.exp(np.mean(np.log(1e-4 + np.maximum(lum, 0.0)))))
    return MIDDLE_GREY / key * 2.0 ** bias_ev


def sensor_noise(rgb: np.ndarray, photo: Photo, rng: np.random.Generator) -> np.ndarray:
    """Photon (Poisson) and read (Gaussian) noise on exposed linear values, clipped at saturation."""
    well = photo.full_well_e * 100.0 / photo.iso  # electrons at 1.0
    electrons = rng.poisson(np.clip(rgb, 0.0, 1.0) * well) + rng.normal(0.0, photo.read_noise_e, rgb.shape)
    return np.clip(electrons / well, 0.0, 1.0)


def jpeg(rgb: np.ndarray, quality: int) -> np.ndarray:
    """Linear [0, 1] RGB through an 8-bit sRGB JPEG at ``quality`` and back to linear."""
    from PIL import Image
    buf = io.BytesIO()
    Image.fromarray(np.round(srgb_encode(np.clip(rgb, 0, 1)) * 255).astype(np.uint8)).save(buf, "JPEG", quality=quality)
    return srgb_decode(np.asarray(Image.open(io.BytesIO(buf.getvalue())), np.float64) / 255.0)


def develop(rgb: np.ndarray, photo: Photo, rng: np.random.Generator) -> np.ndarray:
    """The photo of linear radiance ``rgb`` (H, W, 3): exposure, white balance, noise, JPEG;
    float32 linear in [0, 1]."""
    out = np.asarray(rgb, np.float64) * metered_scale(rgb, photo.exposure_bias_ev)
    out = out * white_balance_gains(photo.white_balance_k)
    out = sensor_noise(out, photo, rng)
    if photo.jpeg_quality:
        out = jpeg(out, photo.jpeg_quality)
    return out.astype(np.float32)
