"""CIELAB, CIE XYZ and linear sRGB (D65, 2-degree observer), written out so that a worker does
not import colour-science (2 s) to convert a few garment colours; tests check every function
against colour-science."""
import numpy as np

D65_XY = (0.3127, 0.3290)  # CIE 1931 chromaticity of the sRGB (and our CIELAB) white
# IEC 61966-2-1's published (rounded) matrices, each given by the standard, not one the other's inverse
RGB_TO_XYZ = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
XYZ_TO_RGB = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])


def _xy_to_xyz(x: float, y: float) -> np.ndarray:
    return np.array([x / y, 1.0, (1.0 - x - y) / y])


WHITE = _xy_to_xyz(*D65_XY)
_EPS, _KAPPA = 216 / 24389, 24389 / 27  # CIE's exact constants


def lab_to_xyz(lab) -> np.ndarray:
    lab = np.asarray(lab, dtype=np.float64)
    fy = (lab[..., 0] + 16) / 116
    f = np.stack([fy + lab[..., 1] / 500, fy, fy - lab[..., 2] / 200], axis=-1)
    cube = f ** 3
    return np.where(cube > _EPS, cube, (116 * f - 16) / _KAPPA) * WHITE


def xyz_to_lab(xyz) -> np.ndarray:
    r = np.asarray(xyz, dtype=np.float64) / WHITE
    f = np.where(r > _EPS, np.cbrt(r), (_KAPPA * r + 16) / 116)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], axis=-1)


def xyz_to_rgb(xyz) -> np.ndarray:
    """Linear sRGB (no transfer function)."""
    return np.asarray(xyz, dtype=np.float64) @ XYZ_TO_RGB.T


def rgb_to_xyz(rgb) -> np.ndarray:
    return np.asarray(rgb, dtype=np.float64) @ RGB_TO_XYZ.T


def srgb_decode(v) -> np.ndarray:
    """IEC 61966-2-1's sRGB transfer function inverted: encoded [0, 1] to linear (float64)."""
    v = np.asarray(v, dtype=np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def srgb_encode(v) -> np.ndarray:
    """IEC 61966-2-1's sRGB transfer function: linear [0, 1] to encoded (float64)."""
    v = np.asarray(v, dtype=np.float64)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.abs(v) ** (1 / 2.4) - 0.055)
