"""The skin lines of the hands, painted in the atlas from the rest geometry: knuckle wrinkles
over the backs of the finger joints (a few bowed lines over a darker, redder pad, the pads of
dark skin darker still), flexion creases across the fingers' undersides at each joint and across
the palm (the two transverse creases and the thenar crease round the thumb's ball).

Each texel of the hands is placed on the rest surface (``textures.uv_surface``) and measured in
the frame of its finger joint (along the bone, round it, back or palm side), so the lines lie
where real ones do on every phenotype and move with the skin."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.body.hand_points import dorsal_axis

MM = 1e-3
LINE_WIDTH = 0.9 * MM  # a crease's half width (a Gaussian's sigma), its fold's shade included; where texels
# are coarser it widens to half a texel and fades as much, so a coarse atlas is not darkened by blurred lines
KNUCKLE_LINES = {1: (-2.6, 0.0, 2.6), 2: (-1.6, 1.6)}  # joint (1 PIP, 2 DIP) -> wrinkle offsets along the finger, mm
KNUCKLE_PAD = (5.0, 7.0)  # the pad's half length along the finger and half width across it, mm
PALMAR_LINES = {1: (-1.2, 1.2), 2: (0.0,)}  # the two creases under a PIP joint, one under a DIP
BASE_CREASE = 0.38  # the crease at a finger's base, this share of the way from its MCP to its PIP joint
# the palm's creases as polylines in (along: wrist 0 .. middle finger's MCP 1, across: index 0 ..
# pinky 1), from the typical palm
PALM_CREASES = (((0.70, 1.05), (0.75, 0.70), (0.80, 0.40), (0.86, 0.22)),   # distal transverse ("heart")
                ((0.74, -0.05), (0.68, 0.25), (0.60, 0.55), (0.52, 0.75)),  # proximal transverse ("head")
                ((0.73, -0.02), (0.55, 0.12), (0.35, 0.22), (0.12, 0.30)))  # thenar ("life"), round the thumb's ball


@dataclass
class HandLines:
    """Maps (size, size) in [0, 1]: ``creases`` (every line) and ``knuckles`` (the pads under
    the backs' wrinkles)."""

    creases: np.ndarray
    knuckles: np.ndarray


def _line(d: np.ndarray, width: float) -> np.ndarray:
    return np.exp(-0.5 * (d / width) ** 2)


def _finger_frames(skeleton, s: str, f: int, pos: np.ndarray, nrm: np.ndarray, nails: np.ndarray):
    """Joint heads (3, 3) of finger ``f`` (0 thumb) and their bone axes (3, 3), and the finger's
    back direction: the mean normal of its nail texels (the thumb's nail faces sideways)."""
    P = skeleton.rest_positions
    chain = [skeleton.index(f"finger{f + 1}-{k}.{s}") for k in (1, 2, 3)]
    heads = P[chain]
    axes = np.stack([heads[1] - heads[0], heads[2] - heads[1], heads[2] - heads[1]])
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    d = pos - heads[2]
    t = d @ axes[2]
    near = (t > 0) & (t < 0.03) & (np.linalg.norm(d - np.outer(t, axes[2]), axis=1) < 0.011) & (nails > 0.5)
    back = nrm[near].sum(0) if near.any() else dorsal_axis(skeleton, s)
    return heads, axes, back / np.linalg.norm(back)


def _finger_lines(heads, axes, back, pos, nrm, width, base_crease: bool = True):
    """Crease and pad strengths of the texels ``pos`` from one finger's joints (for the thumb,
    whose first head is its CMC joint, without the crease at the base)."""
    creases, pads = np.zeros(len(pos)), np.zeros(len(pos))
    for j in (1, 2):
        a = axes[j]
        up = back - (back @ a) * a
        up /= np.linalg.norm(up)
        side = np.cross(a, up)
        d = pos - heads[j]
        s, lat, h = d @ a, d @ side, d @ up
        r = np.hypot(lat, h)
        near = (r < 0.014) & (np.abs(s) < 0.012)
        facing = nrm @ up
        bow = 0.02 / MM * lat ** 2  # wrinkles bow towards the fingertip at the finger's sides
        for off in KNUCKLE_LINES[j]:
            creases += near * np.clip(facing / 0.4, 0, 1) * _line(s - off * MM - bow, width)
        for off in PALMAR_LINES[j]:
            creases += near * np.clip(-facing / 0.4, 0, 1) * _line(s - off * MM, width)
        pads += near * np.clip(facing / 0.5, 0, 1) * np.exp(-0.5 * ((s / (KNUCKLE_PAD[0] * MM)) ** 2
                                                                   + (lat / (KNUCKLE_PAD[1] * MM)) ** 2))
    if not base_crease:
        return creases, pads
    a = axes[0]  # the crease at the finger's base, on its palm side
    s = (pos - heads[0]) @ a
    r = np.linalg.norm(pos - heads[0] - np.outer(s, a), axis=1)
    base = BASE_CREASE * np.linalg.norm(heads[1] - heads[0])
    creases += (r < 0.016) * np.clip(-(nrm @ back) / 0.4, 0, 1) * _line(s - base, width)
    return creases, pads


def _palm_lines(skeleton, s: str, pos, nrm, width):
    """The palm's three main creases, on the palm side of the hand's rest plane."""
    P = skeleton.rest_positions
    wrist = P[skeleton.index(f"wrist.{s}")]
    index, middle, pinky = (P[skeleton.index(f"finger{k}-1.{s}")] for k in (2, 3, 5))
    along = middle - wrist
    length = np.linalg.norm(along)
    along /= length
    across = pinky - index - ((pinky - index) @ along) * along
    breadth = np.linalg.norm(across)
    across /= breadth
    d = pos - wrist
    uv = np.stack([d @ along / length, (d - (index - wrist)) @ across / breadth], 1)
    palm = np.clip((nrm @ -dorsal_axis(skeleton, s)) / 0.4, 0, 1) * (uv[:, 0] > 0.05) * (uv[:, 0] < 1.0)
    out = np.zeros(len(pos))
    scale = np.array([length, breadth])
    for crease in PALM_CREASES:
        pts = np.asarray(crease) * scale
        q = uv * scale
        dist = np.full(len(pos), np.inf)
        for p0, p1 in zip(pts[:-1], pts[1:]):
            t = np.clip((q - p0) @ (p1 - p0) / ((p1 - p0) @ (p1 - p0)), 0, 1)
            dist = np.minimum(dist, np.linalg.norm(q - p0 - t[:, None] * (p1 - p0), axis=1))
        out += palm * _line(dist, 1.4 * width)
    return out


def hand_lines(skeleton, surface, nails: np.ndarray) -> HandLines:
    """The hands' creases and knuckle pads over the atlas ``surface`` (``textures.UVSurface`` of
    the hands' texels), ``nails`` the nail mask at its size."""
    size = surface.covered.shape[0]
    rows, cols = np.nonzero(surface.covered)
    pos, nrm = surface.position[rows, cols], surface.normal[rows, cols]
    width = max(LINE_WIDTH, 0.5 * surface.texel)
    fade = LINE_WIDTH / width
    creases, pads = np.zeros(len(pos)), np.zeros(len(pos))
    for s in "LR":
        mine = np.flatnonzero((pos[:, 0] > 0) == (s == "L"))  # the left hand is the one at x > 0
        p, n = pos[mine], nrm[mine]
        for f in range(5):
            heads, axes, back = _finger_frames(skeleton, s, f, p, n, nails[rows[mine], cols[mine]])
            c, k = _finger_lines(heads, axes, back, p, n, width, base_crease=f > 0)
            creases[mine] += c
            pads[mine] += k
        creases[mine] += _palm_lines(skeleton, s, p, n, width)
    out = HandLines(np.zeros((size, size), np.float32), np.zeros((size, size), np.float32))
    out.creases[rows, cols] = np.clip(fade * creases, 0, 1)
    out.knuckles[rows, cols] = np.clip(pads, 0, 1)
    return out
