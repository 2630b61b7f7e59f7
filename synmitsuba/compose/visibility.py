"""Occlusion as a target: what share of subject records should be partly hidden (a visible
fraction in ``visible``), met by choosing views whose ray-cast estimate supplies that share.

Occlusion-robust estimators (PARE, BEDLAM's and AGORA's training sets) learn from people half
hidden by others and by objects; left to the best-view score, composition picks the clearest
views (in ``make demo`` 71 of 72 records were fully visible before this target existed).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synmitsuba.compose import cameras as cams
from synmitsuba.compose.cameras import azimuth_gaps, slot_options, tolerance_pools
from synmitsuba.schema import Number, Params, Range, spec


@dataclass
class VisibilityTarget(Params):
    share: float = spec(0.0, Number(0, 1), doc="wanted share of subject records whose visible fraction lies in "
                        "`visible` (0: no target, the clearest views win)")
    visible: list = spec(factory=lambda: [0.3, 0.8], check=Range(0, 1), doc="the partly hidden range of visible fraction")
    cluster: float = spec(0.0, Number(0, 1), doc="odds that placement stands a subject next to one already placed "
                          "(0.6 m at most); off by default: it hid people wholly more often than partly")

    @property
    def on(self) -> bool:
        return self.share > 0


AIMS_PER_PAIR = 4  # candidates per ordered pair of subjects on the line through them
OFFSET_M = (0.1, 0.45)  # how far the one behind stands aside of the one in front, as the camera sees them


def lines_of_sight(group: cams.Group, object_boxes: np.ndarray, cfg: cams.CameraConfig, rng: np.random.Generator,
                   sizes: list) -> list:
    """Extra candidates for an occlusion target: cameras on the line through two subjects
    (at the clip's middle frame), beyond the first, so it stands in front of the second, with
    the second shifted aside by 0.1-0.45 m (partly hidden, not wholly); distance and pitch
    drawn within the shell grid's ranges, the field of view from the part of ``hfov_deg`` that
    frames the group, kept only within the same bounds. A grid of 24 azimuths passes such
    lines 0.8 m apart for people 3 m apart, and misses most."""
    mid = group.frame_boxes[len(group.frame_boxes) // 2]
    feet = np.stack([(mid[:, 0] + mid[:, 3]) / 2, (mid[:, 2] + mid[:, 5]) / 2], 1)
    centre = group.centre[[0, 2]]
    out = []
    sizes = sorted(set(sizes))
    for i in range(len(feet)):
        for j in range(len(feet)):
            if i == j or np.linalg.norm(feet[i] - feet[j]) < 1e-6:
                continue
            for _ in range(AIMS_PER_PAIR):
                size = sizes[int(rng.integers(len(sizes)))]
                traj = _on_line(feet[j], feet[i], centre, group, object_boxes, cfg, rng, size)
                if traj is not None:
                    out.append(traj)
    return out


def _on_line(back, front, centre, group, object_boxes, cfg, rng, size):
    """A candidate whose eye lies on the line through ``front`` and a point 0.1-0.45 m beside
    ``back`` (ground xz), beyond ``front``: ``back`` shows that far aside of it; its field of
    view drawn from the part of ``hfov_deg`` that frames the group within ``distance_max``,
    its motion from the kinds that do not zoom. None outside the bounds."""
    kinds = [k for k in cfg.motion if not cams.CAMERA_MOTIONS[k].zooms]
    K = _framing_intrinsics(group, cfg, rng, size)
    if not kinds or K is None:
        return None
    kind = str(kinds[int(rng.integers(len(kinds)))])
    lo = cams.l_min(group, cams.narrow_fov(K, *size), cfg.fit_lambda)
    dist = float(rng.uniform(lo, min(cfg.distance_max, cfg.framing_max * lo)))
    pitch = np.radians(rng.uniform(*cfg.pitch_deg))
    reach = dist * np.cos(pitch)  # the eye's ground distance from the centre
    u = (front - back) / np.linalg.norm(front - back)
    aside = back + rng.uniform(*OFFSET_M) * rng.choice([-1, 1]) * np.array([-u[1], u[0]])
    u = (front - aside) / np.linalg.norm(front - aside)  # the eye's line runs through front and beside back
    b = float(u @ (aside - centre))
    disc = b * b - float((aside - centre) @ (aside - centre)) + reach * reach
    if disc < 0:
        return None
    eye = aside + (-b + np.sqrt(disc)) * u  # the far root: past the front subject
    if (eye - aside) @ u <= np.linalg.norm(front - aside):
        return None
    azimuth = np.arctan2(eye[0] - centre[0], eye[1] - centre[1])
    traj = cams.trajectory(kind, group, azimuth, pitch, dist, K, cfg, rng, size)
    return traj if cams.bounds_ok(traj, group, object_boxes, cfg) else None


def _framing_intrinsics(group, cfg, rng, size) -> np.ndarray | None:
    """K with a horizontal field of view drawn from the part of ``hfov_deg`` wide enough to
    frame the group from ``distance_max`` (L_min <= distance_max); None when none is."""
    w, h = size
    radius = cams.l_min(group, np.pi, 1.0)  # max |pv_i - p̄|
    ratio = cfg.fit_lambda * radius / cfg.distance_max
    if ratio >= 1:
        return None
    narrow = 2 * np.arcsin(ratio)
    need = np.degrees(2 * np.arctan(np.tan(narrow / 2) * w / min(w, h)))
    lo, hi = max(cfg.hfov_deg[0], need + 1e-6), cfg.hfov_deg[1]
    if lo > hi:
        return None
    shift = rng.uniform(-cfg.principal_jitter, cfg.principal_jitter, 2) if cfg.principal_jitter else (0.0, 0.0)
    return cams.intrinsics(rng.uniform(lo, hi), w, h, shift)


NEAR_COST = 0.1  # views this close to the best cost count as ties, broken by azimuth diversity


def expected_counts(visible: np.ndarray, seen: np.ndarray, target: VisibilityTarget,
                    in_view_min: float) -> tuple[np.ndarray, np.ndarray]:
    """Per candidate view, from ``visible`` (V, S, F) and ``seen`` (V, S): the expected number
    of subject records (per frame) in the target range, and of records in sight (in_view at
    least ``in_view_min``) but hidden below it."""
    lo, hi = target.visible
    in_sight = (seen >= in_view_min)[..., None]
    mid = ((visible >= lo) & (visible <= hi) & in_sight).mean(2).sum(1)
    low = ((visible < lo) & in_sight).mean(2).sum(1)
    return mid, low


def choose_for_target(visible: np.ndarray, seen: np.ndarray, azimuths: np.ndarray, count: int, tolerance: float,
                      target: VisibilityTarget, in_view_min: float, classes: np.ndarray | None = None,
                      wanted: list | None = None) -> list[int]:
    """Indices of ``count`` views that, together, bring the scene's share of partly hidden
    records nearest ``target.share``: among views framing the subjects within ``tolerance`` of
    the best (mean in-view share), each next view is the one whose expected count of partly
    hidden records is nearest what is still wanted (a record hidden below the range costs as
    much as a miss); near-ties go to the view farthest in azimuth from those chosen.
    ``classes`` and ``wanted`` keep each view to its image size (``cameras.choose_views``)."""
    framing = seen.mean(1)
    classes = np.zeros(len(framing), int) if classes is None else np.asarray(classes)
    wanted = [0] * count if wanted is None else list(wanted)
    pools = tolerance_pools(framing, tolerance, classes, wanted)
    mid, low = expected_counts(visible, seen, target, in_view_min)
    S = seen.shape[1]
    chosen: list[int] = []
    for k, want in enumerate(wanted):
        rest = slot_options(pools, want, chosen)
        if not rest:
            break
        need = target.share * S * (k + 1) - mid[chosen].sum()
        cost = np.abs(mid[rest] - need) + low[rest]
        near = [i for i, c in zip(rest, cost) if c <= cost.min() + NEAR_COST]
        if not chosen:
            chosen.append(near[0])
            continue
        chosen.append(near[int(np.argmax(azimuth_gaps(near, chosen, azimuths)))])
    return chosen
