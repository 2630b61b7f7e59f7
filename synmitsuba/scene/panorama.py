"""Equirectangular panoramas as Mitsuba's ``envmap`` reads them, and the dome a ground-projected
panorama is seen on.

Pixel (row, col) of an H x W panorama looks along theta = pi (row + 0.5) / H from +y and
phi = 2 pi (col + 0.5) / W: local d = (sin theta sin phi, cos theta, -sin theta cos phi), then
turned ``rotation_deg`` about +y (checked against Mitsuba's ``eval`` in tests/test_backdrop.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Dome:
    """A panorama shot from ``centre`` (x, y, z), seen on a dome of ``radius_m`` around the
    point of the ground below it: what lies beyond the projected ground is drawn there, so
    walls and trees stand at that distance instead of at infinity."""

    centre: tuple
    radius_m: float


def rot_y(deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def pixel_directions(h: int, w: int, rotation_deg: float = 0.0) -> np.ndarray:
    """(h, w, 3) world directions of an equirectangular panorama's pixel centres."""
    theta = np.pi * (np.arange(h) + 0.5) / h
    phi = 2 * np.pi * (np.arange(w) + 0.5) / w
    T, P = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(T) * np.sin(P), np.cos(T), -np.sin(T) * np.cos(P)], -1)
    return d @ rot_y(rotation_deg).T


def azimuth_deg(directions: np.ndarray, rotation_deg: float = 0.0) -> np.ndarray:
    """Where world ``directions`` (..., 3) fall across the panorama: its column over the width
    times 360 (0 at the left edge), for a panorama turned ``rotation_deg``."""
    d = directions @ rot_y(rotation_deg)
    return (np.degrees(np.arctan2(d[..., 0], -d[..., 2])) % 360.0)


def lookup(pixels: np.ndarray, directions: np.ndarray, rotation_deg: float = 0.0) -> np.ndarray:
    """Bilinear radiance of the panorama along world ``directions`` (..., 3), u wrapping."""
    h, w = pixels.shape[:2]
    d = directions @ rot_y(rotation_deg)        # world -> panorama frame (inverse rotation)
    u = (np.arctan2(d[..., 0], -d[..., 2]) / (2 * np.pi)) % 1.0 * w - 0.5
    v = np.arccos(np.clip(d[..., 1], -1, 1)) / np.pi * h - 0.5
    v = np.clip(v, 0, h - 1)
    u0, v0 = np.floor(u).astype(int), np.minimum(np.floor(v).astype(int), h - 2)
    fu, fv = (u - u0)[..., None], np.clip(v - v0, 0, 1)[..., None]
    u0, u1 = u0 % w, (u0 + 1) % w
    top = pixels[v0, u0] * (1 - fu) + pixels[v0, u1] * fu
    bottom = pixels[v0 + 1, u0] * (1 - fu) + pixels[v0 + 1, u1] * fu
    return top * (1 - fv) + bottom * fv


def solid_angles(h: int, w: int) -> np.ndarray:
    """(h, 1) solid angle of one pixel of each row."""
    theta = np.pi * (np.arange(h) + 0.5) / h
    return (2 * np.pi / w) * (np.pi / h) * np.sin(theta)[:, None]


def dome_directions(origin: np.ndarray, rays: np.ndarray, dome: Dome) -> np.ndarray:
    """Where rays from ``origin`` (3,) along unit ``rays`` (..., 3) meet the dome, seen from its
    centre (unit, ...). Rays from outside the dome keep their own direction."""
    c = np.asarray(dome.centre, np.float64)
    foot = np.array([c[0], 0.0, c[2]])
    o = np.asarray(origin, np.float64) - foot
    b = rays @ o
    disc = b * b - (o @ o - dome.radius_m ** 2)
    inside = o @ o < dome.radius_m ** 2
    t = -b + np.sqrt(np.maximum(disc, 0.0))
    p = np.asarray(origin) + t[..., None] * rays - c
    out = p / np.maximum(np.linalg.norm(p, axis=-1, keepdims=True), 1e-12)
    return out if inside else rays
