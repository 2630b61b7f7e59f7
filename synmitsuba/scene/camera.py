"""Cameras in the OpenCV convention: pinhole, optionally with lens distortion and a thin lens.

Camera frame: x right, y down, z forward. ``K`` is 3x3 in pixels with pixel centres at
integer + 0.5 (pixel (0, 0) spans [0, 1) x [0, 1)). ``R``, ``t`` map world to camera:
``x_cam = R @ x_world + t``. Any K works (off-centre principal point, fx != fy, skew).
``dist`` are OpenCV's distortion coefficients of the ``lens`` model (``scene.lens``):
``cv2.projectPoints`` (``cv2.fisheye.projectPoints``) with K, dist, R and t gives
``Camera.project``. ``aperture_radius`` (metres, 0 = pinhole) and ``focus_distance`` (metres
along the optical axis) make a thin lens for the RGB only: exact passes and labels use the ray
through the lens centre.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from synmitsuba.errors import ConfigError
from synmitsuba.geometry import camera_ray_matrix, frame
from synmitsuba.scene.lens import LENS_MODELS, NUMPY_OPS, folded_radius, image_radius
from synmitsuba.schema import POSITIVE as PIXELS


def _matrix(name: str, value, shape) -> np.ndarray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != shape:
        raise ConfigError(name, np.asarray(value).tolist() if arr.size < 20 else f"array{arr.shape}",
                          f"give a {shape[0]}x{shape[1] if len(shape) > 1 else ''} array".rstrip("x"))
    if not np.isfinite(arr).all():
        raise ConfigError(name, arr.tolist(), "all entries must be finite numbers")
    return arr


FAR_OUTSIDE = 1e3  # normalised radius project() gives points beyond where the lens folds back


@dataclass
class Camera:
    """A camera: intrinsics ``K`` (pixels), world->camera ``R``, ``t``, image size, lens
    distortion (``lens`` model, ``dist`` coefficients) and thin-lens depth of field."""

    K: np.ndarray
    R: np.ndarray = field(default_factory=lambda: np.eye(3))
    t: np.ndarray = field(default_factory=lambda: np.zeros(3))
    width: int = 320
    height: int = 240
    lens: str = "brown_conrady"
    dist: np.ndarray | None = None      # the model's coefficients; None: zeros (a pinhole)
    aperture_radius: float = 0.0        # metres; 0: everything in focus
    focus_distance: float = 1.0         # metres along the optical axis

    def __post_init__(self):
        self.K = _matrix("camera.K", self.K, (3, 3))
        self.R = _matrix("camera.R", self.R, (3, 3))
        self.t = _matrix("camera.t", self.t, (3,))
        self.width = PIXELS("camera.width", self.width)
        self.height = PIXELS("camera.height", self.height)
        if not np.allclose(self.K[2], [0, 0, 1]):
            raise ConfigError("camera.K", self.K.tolist(), "the last row of K must be [0, 0, 1]")
        if self.K[0, 0] <= 0 or self.K[1, 1] <= 0:
            raise ConfigError("camera.K", self.K.tolist(), "fx = K[0][0] and fy = K[1][1] must be > 0 (pixels)")
        if self.K[1, 0] != 0:
            raise ConfigError("camera.K", self.K.tolist(), "K[1][0] must be 0: an OpenCV K is upper triangular "
                              "[[fx, skew, cx], [0, fy, cy], [0, 0, 1]]")
        if not np.allclose(self.R @ self.R.T, np.eye(3), atol=1e-6) or np.linalg.det(self.R) < 0:
            raise ConfigError("camera.R", self.R.tolist(), "R must be a rotation (orthonormal, det +1)")
        self._check_lens()

    def _check_lens(self) -> None:
        """The distortion model and coefficients (refused when the image folds back on itself)
        and the thin lens; K is checked already."""
        if self.lens not in LENS_MODELS:
            raise ConfigError("camera.lens", self.lens, f"use one of {', '.join(LENS_MODELS)}")
        n = len(LENS_MODELS[self.lens].coefficients)
        self.dist = np.zeros(n) if self.dist is None else _matrix("camera.dist", self.dist, (n,))
        if self.distorted:
            reach, corners = folded_radius(self.lens, self.dist), image_radius(self.K, self.width, self.height)
            if corners > 0.98 * reach:
                raise ConfigError("camera.dist", np.asarray(self.dist).tolist(),
                                  f"this distortion folds back inside the image (its radius stops growing at "
                                  f"{reach:.3f} in normalised coordinates, the corners reach {corners:.3f}): "
                                  "use smaller coefficients")
        if not (np.isfinite(self.aperture_radius) and self.aperture_radius >= 0):
            raise ConfigError("camera.aperture_radius", self.aperture_radius, "give a radius >= 0 in metres")
        if not (np.isfinite(self.focus_distance) and self.focus_distance > 0):
            raise ConfigError("camera.focus_distance", self.focus_distance, "give a distance > 0 in metres")

    # -- construction ------------------------------------------------------------------
    @staticmethod
    def intrinsics(fov_y_deg: float, width: int, height: int) -> np.ndarray:
        """K for a vertical field of view with square pixels and a centred principal point."""
        if not 0 < fov_y_deg < 180:
            raise ConfigError("camera.fov_y_deg", fov_y_deg, "give a field of view in (0, 180) degrees")
        f = 0.5 * height / np.tan(np.radians(fov_y_deg) / 2)
        return np.array([[f, 0, width / 2], [0, f, height / 2], [0, 0, 1.0]])

    @classmethod
    def look_at(cls, eye, target, up=(0.0, 1.0, 0.0), fov_y_deg: float = 45.0,
                width: int = 320, height: int = 240, K=None) -> "Camera":
        """A camera at ``eye`` looking at ``target`` with ``up`` pointing up in the image."""
        eye = _matrix("camera.eye", eye, (3,))
        target = _matrix("camera.target", target, (3,))
        up = _matrix("camera.up", up, (3,))
        if np.linalg.norm(target - eye) < 1e-9:
            raise ConfigError("camera.target", target.tolist(), "target must differ from eye")
        try:
            F = frame(target - eye, up, keep="forward")
        except ValueError:
            raise ConfigError("camera.up", up.tolist(), "up must not be parallel to the viewing direction") from None
        R = np.stack([-F[:, 0], -F[:, 1], F[:, 2]])  # OpenCV: x right (= -side), y down, z forward
        K = cls.intrinsics(fov_y_deg, width, height) if K is None else K
        return cls(K=K, R=R, t=-R @ eye, width=width, height=height)

    @property
    def distorted(self) -> bool:
        """Whether any distortion coefficient is non-zero (else rays are the pinhole's, bit for bit)."""
        return bool(np.any(self.dist))

    # -- geometry ----------------------------------------------------------------------
    @property
    def center(self) -> np.ndarray:
        """Camera centre in world coordinates."""
        return -self.R.T @ self.t

    @property
    def ray_matrix(self) -> np.ndarray:
        """``R^T K^-1``: pixel [u, v, 1] -> world ray direction (not normalised)."""
        return camera_ray_matrix(self.K, self.R)

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """World points (N, 3) -> pixel coordinates (N, 2) and z-depth (N,)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3) @ self.R.T + self.t
        if self.distorted:
            with np.errstate(divide="ignore", invalid="ignore"):
                x, y = p[:, 0] / p[:, 2], p[:, 1] / p[:, 2]
                xd, yd = LENS_MODELS[self.lens].distort(x, y, self.dist, NUMPY_OPS)
                beyond = x * x + y * y > LENS_MODELS[self.lens].fold(self.dist)  # not imaged: far outside instead
                out = FAR_OUTSIDE / np.maximum(np.hypot(x, y), 1e-12)
                xd, yd = np.where(beyond, x * out, xd), np.where(beyond, y * out, yd)
            uvw = np.stack([xd, yd, np.ones_like(xd)], 1) @ self.K.T
            return uvw[:, :2], p[:, 2]
        uvw = p @ self.K.T
        return uvw[:, :2] / uvw[:, 2:3], p[:, 2]

    def pixel_rays(self, offsets=None) -> np.ndarray:
        """Unit world-space directions through pixel centres (H, W, 3), or through
        ``pixel + offsets`` when offsets (..., 2) in [0, 1) are given (broadcast per pixel)."""
        u, v = np.meshgrid(np.arange(self.width, dtype=np.float64), np.arange(self.height, dtype=np.float64))
        pix = np.stack([u, v], -1)
        pix = pix + (0.5 if offsets is None else np.asarray(offsets))
        ones = np.ones(pix.shape[:-1] + (1,))
        if self.distorted:
            n = np.concatenate([pix, ones], -1) @ np.linalg.inv(self.K).T
            d = np.stack(LENS_MODELS[self.lens].direction(n[..., 0], n[..., 1], self.dist, NUMPY_OPS), -1) @ self.R
        else:
            d = np.concatenate([pix, ones], -1) @ self.ray_matrix.T
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def resized(self, width: int, height: int) -> "Camera":
        """The same camera at another resolution (K scaled per axis)."""
        S = np.diag([width / self.width, height / self.height, 1.0])
        return dataclasses.replace(self, K=S @ self.K, width=width, height=height)

    def blended(self, other: "Camera", a: float) -> "Camera":
        """The camera a share ``a`` of the way to ``other`` (a motion-blur sub-frame): centre
        and K linearly, rotation by slerp; lens and image size are this camera's."""
        if a == 0 or (np.array_equal(self.R, other.R) and np.array_equal(self.t, other.t)
                      and np.array_equal(self.K, other.K)):
            return self
        from synmitsuba.geometry import slerp_matrices
        R = slerp_matrices(np.stack([self.R, other.R]), np.array([a]))[0]
        centre = (1 - a) * self.center + a * other.center
        return dataclasses.replace(self, K=(1 - a) * self.K + a * other.K, R=R, t=-R @ centre)

    # -- serialization -----------------------------------------------------------------
    def to_dict(self) -> dict:
        return {"K": self.K.tolist(), "R": self.R.tolist(), "t": self.t.tolist(),
                "width": self.width, "height": self.height, "convention": "opencv_world_to_camera",
                "lens": self.lens, "dist": np.asarray(self.dist).tolist(),
                "aperture_radius": float(self.aperture_radius), "focus_distance": float(self.focus_distance)}

    @classmethod
    def from_dict(cls, d: dict) -> "Camera":
        return cls(K=d["K"], R=d["R"], t=d["t"], width=d["width"], height=d["height"],
                   lens=d.get("lens", "brown_conrady"), dist=d.get("dist"),
                   aperture_radius=d.get("aperture_radius", 0.0), focus_distance=d.get("focus_distance", 1.0))
