"""A generated sequence as a Rerun recording (``rerun-sdk``; ``synmitsuba view``): on the
``frame`` timeline, each camera with its pose and intrinsics (OpenCV: x right, y down, z
forward), its sRGB image, depth (the viewer draws it as a point cloud through the camera), 2D
keypoints coloured by visibility class and boxes; in the world (y up), each subject's 3D
keypoints and, rebuilt from ``scene.json``, its posed body mesh."""
from __future__ import annotations

import os

import numpy as np

from synmitsuba.errors import ConfigError
from synmitsuba.io.overlay import VIS_COLOURS  # the panels' colours: one code table for every picture



def _rerun():
    try:
        import rerun as rr
    except ImportError:
        raise ConfigError("view", "rerun-sdk", "the viewer needs Rerun: pip install 'synmitsuba[view]'") from None
    return rr


def sequence_folder(root: str, sequence: int | None) -> str:
    """``root`` itself when it holds samples, else its ``seq_XXXXXX`` (the first by default)."""
    from synmitsuba.io.listing import dataset_samples
    stems = dataset_samples(root)
    folders = sorted({os.path.dirname(s) for s in stems})
    if sequence is None:
        return folders[0]
    name = f"seq_{int(sequence):06d}"
    for f in folders:
        if os.path.basename(f) == name:
            return f
    raise ConfigError("--sequence", sequence, f"no complete {name} in {root}; it has "
                      + ", ".join(os.path.basename(f) for f in folders))


def write_recording(folder: str, out: str, meshes: bool = True) -> dict:
    """Write ``folder``'s samples (one sequence) to the Rerun file ``out``; returns counts."""
    rr = _rerun()
    from synmitsuba.io.exr import read_sample
    from synmitsuba.io.listing import list_samples
    stems = list_samples(folder)
    if not stems:
        raise ConfigError("sequence", folder, "no complete samples here")
    rec = rr.RecordingStream("synmitsuba", recording_id=os.path.basename(os.path.abspath(folder)))
    rec.save(out)
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Y_UP, static=True)
    bodies = _bodies(folder) if meshes else {}
    frames: set[int] = set()
    views: set[str] = set()
    meshes_logged = 0
    for stem in stems:
        s = read_sample(stem)
        frame, view = int(s.meta.get("frame", 0)), str(s.meta.get("view", os.path.basename(stem)))
        rec.set_time("frame", sequence=frame)
        _log_view(rr, rec, s, f"world/{view}")
        if frame not in frames:  # the world's content once per frame
            _log_world(rr, rec, s, bodies, frame)
            meshes_logged += len(bodies)
        frames.add(frame)
        views.add(view)
    rec.flush()
    return {"samples": len(stems), "frames": len(frames), "views": len(views), "meshes": meshes_logged}


def _log_view(rr, rec, s, path: str) -> None:
    from synmitsuba.io.preview import to_srgb8
    cam = s.camera
    rec.log(path, rr.Transform3D(translation=cam.t, mat3x3=cam.R, relation=rr.TransformRelation.ChildFromParent))
    rec.log(path, rr.Pinhole(image_from_camera=cam.K, resolution=[cam.width, cam.height],
                             camera_xyz=rr.ViewCoordinates.RDF))
    rec.log(f"{path}/image", rr.Image(to_srgb8(s.rgb)))
    rec.log(f"{path}/depth", rr.DepthImage(s.depth, meter=1.0))
    for r in s.subjects:
        vis = np.asarray(r["visibility"])
        shown = vis > 0
        rec.log(f"{path}/image/keypoints/{r['instance']}",
                rr.Points2D(np.asarray(r["keypoints2d"])[shown], colors=[VIS_COLOURS[int(v)] for v in vis[shown]], radii=2.0))
        boxes = [r[k] for k in ("bbox_visible", "bbox_amodal") if r[k] is not None]
        if boxes:
            rec.log(f"{path}/image/boxes/{r['instance']}", rr.Boxes2D(array=boxes, array_format=rr.Box2DFormat.XYXY,
                                                                      labels=[f"{r['instance']} visible", "amodal"][:len(boxes)]))


def _log_world(rr, rec, s, bodies: dict, frame: int) -> None:
    for r in s.subjects:
        vis = np.asarray(r["visibility"])
        rec.log(f"world/subjects/{r['instance']}/keypoints",
                rr.Points3D(np.asarray(r["keypoints3d_world"]), colors=[VIS_COLOURS[int(v)] for v in vis], radii=0.02))
    for instance, (human, motion) in bodies.items():
        rot, root = motion.frame(frame % motion.n_frames)
        face = motion.face_at(frame % motion.n_frames)
        body = next(layer for layer in human.pose(rot, root, face=face) if layer.name == "body")
        rec.log(f"world/subjects/{instance}/body", rr.Mesh3D(vertex_positions=body.vertices, triangle_indices=body.faces,
                                                             albedo_factor=[0.8, 0.7, 0.6]))


def _bodies(folder: str) -> dict:
    """Each subject's human and placed clip, rebuilt from the sequence's ``scene.json``."""
    from synmitsuba.compose.spec import SceneSpec
    path = os.path.join(folder, "scene.json")
    if not os.path.isfile(path):
        return {}
    with open(path) as fh:
        spec = SceneSpec.from_json(fh.read())
    return {p.instance: (p.human, p.motion) for p in spec.placed_subjects()}


def viewer_available() -> bool:
    """Whether a Rerun viewer window can open here (a display)."""
    import sys
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")) or sys.platform == "darwin"
