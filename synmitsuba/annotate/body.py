"""Layered body labels: what lies under the clothes and hair. Pixel-centre rays against the
subjects' bodies alone give, where the pixel shows that subject (any of its layers), the body
part (``body.segments``: 24 parts), the body surface point (anny face index + 1 and
barycentric weights of its vertices 1 and 2: a DensePose-like correspondence, the same
topology for every subject), the body's z-depth and camera-frame normal, and the cloth
thickness (body depth minus visible depth where a garment covers the body). The rays are cast
in the rendered scene, passing through clothes and hair to the first body."""
from __future__ import annotations

import numpy as np

from synmitsuba.body.segments import vertex_parts
from synmitsuba.engine.raycast import far_side, hits_through
from synmitsuba.engine.rays import pixel_centre_rays
from synmitsuba.scene.camera import Camera
from synmitsuba.scene.layers import Layer
from synmitsuba.scene.scene import Scene

GARMENT_LAYERS = (int(Layer.TOP), int(Layer.BOTTOM), int(Layer.DRESS), int(Layer.SHOES))


class BodyLayer:
    """The subjects' posed bodies, seen through their clothes and hair in the scene they are
    rendered in (the body meshes there are the ones posed here)."""

    def __init__(self, subjects: list):
        self.subjects = subjects
        self.faces = [p.human.parts[0].faces.astype(np.int64) for p in subjects]
        self.face_parts = [vertex_parts(p.human.parts[0].weights, p.human.skeleton.names)[f[:, 0]] + 1
                           for p, f in zip(subjects, self.faces)]
        self.bodies: list = []
        self.normals: list = []  # welded across the uv seams, as the rendered normals are

    def pose(self, bodies: list) -> None:
        """The bodies' posed vertices (one (V, 3) array per subject)."""
        self.bodies = bodies
        self.normals = [p.human.smooth_normals("body")(v) for p, v in zip(self.subjects, bodies)]

    def passes(self, cam: Camera, scene: Scene, instance: np.ndarray, depth: np.ndarray, layer: np.ndarray) -> dict:
        """The body passes of one view (H, W arrays; see the module docstring), from rays cast
        only where a subject shows, through anything not a body (``hits_through``)."""
        H, W = cam.height, cam.width
        d = pixel_centre_rays(cam).astype(np.float64)  # the instance pass's rays
        by_name = {f"{p.prefix}_body": k for k, p in enumerate(self.subjects)}
        shown = np.flatnonzero(np.isin(instance.reshape(-1), [p.instance for p in self.subjects]))
        far = max((far_side(b, cam.center) for b in self.bodies), default=0.0)
        hits = hits_through(scene, cam.center, d[shown], by_name, far)
        own = (hits["instance"] > 0) & (hits["instance"] == instance.reshape(-1)[shown])  # this body's subject shows
        out: dict[str, np.ndarray] = {"body_part": np.zeros(H * W, np.uint8), "body_face": np.zeros(H * W, np.int32),
               "body_bary": np.zeros((H * W, 2), np.float32), "body_depth": np.zeros(H * W, np.float32),
               "body_normal": np.zeros((H * W, 3), np.float32)}
        for idx in np.unique(hits["shape"][own]):
            k = by_name[hits["names"][idx]]
            m = own & (hits["shape"] == idx)
            sel, face, u, v = shown[m], hits["prim"][m], hits["u"][m], hits["v"][m]
            out["body_part"][sel] = self.face_parts[k][face]
            out["body_face"][sel] = face + 1
            out["body_bary"][sel] = np.stack([u, v], 1)
            out["body_depth"][sel] = hits["t"][m] * (d[sel] @ cam.R[2])
            n = self.normals[k][self.faces[k][face]]
            n = (1 - u - v)[:, None] * n[:, 0] + u[:, None] * n[:, 1] + v[:, None] * n[:, 2]
            n = n @ cam.R.T
            n /= np.linalg.norm(n, axis=1, keepdims=True)
            out["body_normal"][sel] = np.where((n[:, 2] > 0)[:, None], -n, n)  # facing the camera
        covered = np.isin(layer.reshape(-1), GARMENT_LAYERS) & (out["body_face"] > 0)
        thickness = np.where(covered, out["body_depth"] - depth.reshape(-1), 0.0)
        out["cloth_thickness"] = np.clip(thickness, 0, None).astype(np.float32)
        return {k: v.reshape((H, W) + v.shape[1:]) for k, v in out.items()}
