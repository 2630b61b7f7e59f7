"""A garment's procedural texture written in drjit, so a render differentiates through it.

``body.textures.render_garment_texture`` draws the same base colour, pattern, decal and blend
in numpy for datasets; here every edge is a one-texel ramp instead of a step (a step has no
derivative with respect to where it lies), so pattern scale and phase, decal placement and
size, colours and blend weights all get gradients. Colours are linear RGB, what the renderer
sees (``base_lab`` and friends are converted once). The camouflage pattern keeps its numpy
mask: its colours and blend weight are differentiable, its scale and phase are not.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.body.textures import GarmentTextureParams, _pattern_mask, _uv_grid, lab_to_linear_rgb
from synmitsuba.engine.build import aligned_floats
from synmitsuba.errors import ConfigError


@dataclass(frozen=True)
class Variable:
    """One differentiable parameter: its drjit type, the range kept after each step and the
    Adam learning rate that suits its scale."""

    kind: str        # "rgb", "float" or "uv"
    low: float
    high: float
    lr: float


VARIABLES = {
    "base_rgb": Variable("rgb", 0.0, 1.0, 0.02),
    "pattern_rgb": Variable("rgb", 0.0, 1.0, 0.02),
    "pattern_alpha": Variable("float", 0.0, 1.0, 0.02),
    "pattern_scale": Variable("float", 1.0, 64.0, 0.05),
    "pattern_width": Variable("float", 0.05, 0.95, 0.01),
    "phase": Variable("uv", -10.0, 10.0, 0.005),
    "decal_rgb": Variable("rgb", 0.0, 1.0, 0.02),
    "decal_alpha": Variable("float", 0.0, 1.0, 0.02),
    "decal_center": Variable("uv", 0.0, 1.0, 0.005),
    "decal_size": Variable("float", 0.02, 0.5, 0.005),
}


def drjit_value(kind: str, value):
    """A drjit value of the variable's kind from numbers."""
    import mitsuba as mi
    if kind == "texture":
        return mi.TensorXf(np.ascontiguousarray(value, dtype=np.float32))
    v = np.atleast_1d(np.asarray(value, dtype=np.float64))
    if kind == "rgb":
        return mi.Color3f(*(float(x) for x in v[:3]))
    if kind == "uv":
        return mi.Point2f(float(v[0]), float(v[1]))
    return mi.Float(float(v[0]))


def as_numbers(value) -> list[float] | float:
    """A drjit value back to plain numbers (a float or a list)."""
    arr = np.asarray(value, dtype=np.float64).ravel()
    return float(arr[0]) if arr.size == 1 else [float(x) for x in arr]


def _ramp(signed, e):
    """1 where ``signed`` > 0, 0 where < 0, a smoothstep over a width ``e`` around 0: C1, so
    that a loss is smooth in where an edge lies and finite differences agree with AD."""
    import drjit as dr
    t = dr.clip(signed / e + 0.5, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _band(t, width, e):
    """Periodic band: 1 where frac(t) lies in [0, width), with soft edges ``e`` wide (in periods)."""
    import drjit as dr
    c = t - 0.5 * width
    wrapped = c - dr.floor(c + 0.5)  # distance to the band's centre, in [-0.5, 0.5)
    return _ramp(0.5 * width - dr.abs(wrapped), e)


class ProceduralTexture:
    """The garment texture of ``params`` as a drjit function of its ``VARIABLES``, evaluated on
    the ``size`` x ``size`` texel centres of the bitmap it replaces (row 0 is v = 1), its
    pattern over ``coords`` (the garment's panels: its material's ``pattern_coords``) when given,
    its albedo times ``shade`` (its material's ``texture_shade``: the folds' creases) when given."""

    def __init__(self, params: GarmentTextureParams, size: int, coords: np.ndarray | None = None,
                 shade: np.ndarray | None = None):
        if not isinstance(params, GarmentTextureParams):
            raise ConfigError("texture", type(params).__name__, "give a GarmentTextureParams (a garment's .texture)")
        if coords is not None and np.shape(coords) != (size, size, 2):
            raise ConfigError("coords", f"shape {np.shape(coords)}", f"give ({size}, {size}, 2) pattern coordinates "
                              "(the material's pattern_coords) or None")
        if shade is not None and np.shape(shade) != (size, size):
            raise ConfigError("shade", f"shape {np.shape(shade)}", f"give ({size}, {size}) albedo factors "
                              "(the material's texture_shade) or None")
        self.params, self.size = params, int(size)
        self._shade = None if shade is None else aligned_floats(np.repeat(np.asarray(shade)[..., None], 3, -1))
        v, u = (np.mgrid[:size, :size] + 0.5) / size
        v = 1 - v
        self._u, self._v = aligned_floats(u), aligned_floats(v)  # each at one alignment: one kernel at any address
        s = params.uv_scale  # the uv transform before the phase (uv_offset) is added
        if coords is None:
            u = u * params.uv_aspect  # as body.textures._uv_grid: metres along u as along v
            step = np.full(u.shape, 1.0 / size)  # one texel in the pattern's coordinates
        else:  # a garment's panels (body.panels): a texel spans what its coordinates change by
            u, v = coords[..., 0].astype(np.float64), coords[..., 1].astype(np.float64)
            step = np.maximum(*(np.hypot(*np.gradient(c)) for c in (u, v)))
        a = np.radians(params.uv_rotation_deg)
        self._x0 = aligned_floats((np.cos(a) * u - np.sin(a) * v) * s)
        self._y0 = aligned_floats((np.sin(a) * u + np.cos(a) * v) * s)
        self._texel = aligned_floats(step * s)  # one texel in the transformed coordinates
        self._camouflage = None
        if params.pattern == "camouflage":
            x, y = _uv_grid(params, size, coords)
            self._camouflage = aligned_floats(np.clip(_pattern_mask(params, x, y), 0, 1))

    def initial(self) -> dict:
        """The variables' values that reproduce ``params``, as drjit values."""
        p = self.params
        numbers = {"base_rgb": lab_to_linear_rgb(p.base_lab), "pattern_rgb": lab_to_linear_rgb(p.pattern_lab),
                   "pattern_alpha": p.pattern_alpha, "pattern_scale": p.pattern_scale,
                   "pattern_width": p.pattern_width, "phase": p.uv_offset,
                   "decal_rgb": lab_to_linear_rgb(p.decal_lab), "decal_alpha": 1.0,
                   "decal_center": p.decal_center, "decal_size": p.decal_size}
        return {k: drjit_value(VARIABLES[k].kind, v) for k, v in numbers.items()}

    def evaluate(self, values: dict):
        """The albedo tensor (size, size, 3) for ``values`` (every name of ``VARIABLES``)."""
        import drjit as dr
        import mitsuba as mi
        m = dr.clip(self._pattern(values), 0.0, 1.0) * values["pattern_alpha"]
        img = values["base_rgb"] * (1.0 - m) + values["pattern_rgb"] * m
        d = dr.clip(self._decal(values), 0.0, 1.0) * values["decal_alpha"]
        img = img * (1.0 - d) + values["decal_rgb"] * d
        flat = dr.ravel(img)
        if self._shade is not None:  # the folds' creases, as body.textures.garment_material darkens them
            flat = flat * self._shade
        return mi.TensorXf(flat, shape=(self.size, self.size, 3))  # type: ignore[call-overload]

    def _pattern(self, values):
        import drjit as dr
        pattern, s, w = self.params.pattern, values["pattern_scale"], values["pattern_width"]
        if self._camouflage is not None:
            return self._camouflage
        x, y = self._x0 + values["phase"].x, self._y0 + values["phase"].y
        e = self._texel * s  # one texel, in periods of the pattern
        if pattern == "stripes":
            return _band(y * s, w, e)
        if pattern == "checks":  # odd (floor(xs) + floor(ys)): the xor of two half-period bands
            a, b = _band(x * s * 0.5 - 0.5, 0.5, 0.5 * e), _band(y * s * 0.5 - 0.5, 0.5, 0.5 * e)
            return a + b - 2.0 * a * b
        if pattern == "plaid":
            return 0.5 * _band(x * s, w, e) + 0.5 * _band(y * s, w, e)
        if pattern == "dots":
            fx, fy = x * s - dr.floor(x * s) - 0.5, y * s - dr.floor(y * s) - 0.5
            return _ramp(0.5 * w - dr.sqrt(fx * fx + fy * fy + 1e-12), e)
        if pattern == "gradient":
            return y - dr.floor(y)
        return dr.zeros(type(x), dr.width(x))

    def _decal(self, values):
        import drjit as dr
        decal, size, c = self.params.decal, values["decal_size"], values["decal_center"]
        dx, dy = (self._u - c.x) * self.params.uv_aspect / size, (self._v - c.y) / size
        e = 1.0 / (self.size * size)  # one texel, in decal sizes
        r = dr.sqrt(dx * dx + dy * dy + 1e-12)
        if decal == "circle":
            return _ramp(1.0 - r, e) * _ramp(r - 0.6, e) + _ramp(0.35 - r, e)
        if decal == "star":
            return _ramp(0.55 + 0.45 * dr.cos(5.0 * dr.atan2(dy, dx)) - r, e) * _ramp(1.0 - r, e)
        if decal == "band":
            return _ramp(0.3 - dr.abs(dy), e)
        if decal == "number":  # two bars and a stem, as in body.textures
            bars = dr.maximum(_ramp(0.15 - dr.abs(dy - 0.6), e), _ramp(0.15 - dr.abs(dy + 0.6), e))
            stem = _ramp(0.15 - dr.abs(dx - 0.35), e) * _ramp(0.75 - dr.abs(dy), e)
            return dr.maximum(bars * _ramp(0.5 - dr.abs(dx), e), stem)
        return dr.zeros(type(dx), dr.width(dx))
