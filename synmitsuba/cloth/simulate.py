"""``simulate_cloth(human, motion) -> ClothTrack``: a subject's hanging garments (``CLOTH_KINDS``)
simulated over its clip with Newton's VBD cloth solver on the CPU (deterministic: Warp's CPU
kernels run in order), layer by layer (``kinds.stages``: trousers, then the top over them against
the trousers as simulated), against the posed body as a moving mesh collider (its hands a closed
shape of their own, without friction) and the ground.

Each garment's uv seams are welded (else its panels fall apart); its held vertices (a
waistband, a bodice) are not simulated but moved to the skinned garment's place at every
substep, and the rest hangs from them; its hem band (the turned-in edge) is not simulated
either but set, each frame, its depth in from its edge along the cloth's normal. The cloth
is put on with the arms in the rest A-pose (hands clear of any skirt) and hangs for ``settle_s``
(from the skinned garment: gravity takes out its shell's stiffness), the arms coming down to the
clip's first pose over its first ``lead_s``, then follows the clip frame by frame, starting at the velocity its
held part moves at (a clip starts at full speed), the body and the held vertices moved linearly
between frames over the substeps, the air's drag on every triangle added to gravity
(``cloth.air``: without it a hem swings on as in a vacuum). Newton's full-surface contacts (the
body's edges and faces against the cloth's, not only its vertices) keep a leg from passing
between the cloth's vertices."""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable

import numpy as np

from synmitsuba.body.binding import MeshIndex
from synmitsuba.body.garments import GARMENTS, hem_sources, open_edges
from synmitsuba.body.topology import collapse_short_edges, weld
from synmitsuba.cloth.air import Air, drag_forces
from synmitsuba.cloth.fabrics import FABRICS, Fabric
from synmitsuba.cloth.kinds import CLOTH_KINDS, fabric_of, simulated, stages, worn_over, worn_under
from synmitsuba.cloth.lead import Schedule, arm_joints, arms_from_rest
from synmitsuba.cloth.seal import WaistSeal, waist_seal
from synmitsuba.cloth.web import thigh_web
from synmitsuba.errors import ConfigError, SynMitsubaError
from synmitsuba.geometry import face_normals, rigid_fit, triangle_areas, unique_rows, vertex_normals
from synmitsuba.schema import POSITIVE, Check, Flag, Nested, Number, check_fields, optional, spec


class ClothError(SynMitsubaError, RuntimeError):
    """A garment's simulation diverged: the sequence must not be written with that cloth. It
    ``repeats``: the stage is deterministic, so ``generate`` does not try the sequence again."""

    repeats = True

    def __init__(self, garment: str, frame: int, what: str):
        self.garment, self.frame = garment, frame
        super().__init__(f"cloth simulation of the {garment} diverged at clip frame {frame} ({what}); nothing was "
                         "written for it: try more substeps (ClothSettings.substeps) or cloth: skinned")


@dataclass(frozen=True)
class _Device(Check):
    """A Warp device: ``cpu``, ``cuda`` or ``cuda:N``."""

    def __call__(self, where: str, value):
        if not (isinstance(value, str) and re.fullmatch(r"cpu|cuda(:\d+)?", value)):
            raise ConfigError(where, value, "give cpu, cuda or cuda:N (an NVIDIA GPU's index)")
        return value


_METRES = Number(0.0)


@dataclass(frozen=True)
class ClothSettings:
    substeps: int = spec(10, POSITIVE, doc="solver steps per clip frame, at least")
    max_step: float = spec(0.004, Number(1e-4), doc="metres the collider near the cloth may move in one step: "
                           "more steps where it is faster")
    max_substeps: int = spec(40, POSITIVE)
    iterations: int = spec(5, POSITIVE, doc="VBD iterations per step")
    settle_s: float = spec(0.5, Number(0.0), doc="seconds the cloth hangs at the first pose before the clip starts")
    lead_s: float = spec(0.3, Number(0.0), doc="the first of those in which the arms come down from the rest pose "
                         "(Collider.lead)")
    contact_gap: float = spec(0.01, _METRES, doc="metres within which body contacts are made")
    particle_radius: float = spec(0.004, _METRES, doc="metres the cloth keeps off the body")
    contact_stiffness: float = spec(1.0e4, Number(0.0), doc="against the body: 1e3 let a taut cloth 3 mm into a sphere")
    full_contact: bool = spec(True, Flag(), doc="the body's edges and faces too, not only its vertices")
    max_drift: float = spec(1.0, _METRES, doc="metres a vertex may stray from the skinned garment before it "
                            "counts as diverged")
    max_stretch: float = spec(0.2, _METRES, doc="metres an edge of cloth may grow past its rest length before the "
                              "piece counts as torn (a vertex caught by a hand and dragged off)")
    # cloth against itself and the other simulated pieces (Newton VBD's self-contact); off by default:
    # on a skirt over a walk it fought the body's contacts (a vertex 8.8 mm into the body, then a leg through,
    # 2026-11-27, when a step let the cloth move only 1.9 mm: ``_self_contact_gap``); with it a pair of trousers
    # follows a walk, but its knees' backs still pass through themselves in most frames (bench/RESULTS.md,
    # session 99); not yet measured over the benches' clips
    self_contact: bool = spec(False, Flag())
    self_contact_margin: float = spec(0.003, _METRES, doc="metres at which two pieces of cloth start to push apart")
    self_contact_exclusion: float = spec(0.02, _METRES, doc="metres apart when put on under which two bits of cloth "
                                         "never push apart: a shell cut from the body crosses itself at the crotch, "
                                         "and cloth touching there from the start never moved")
    air: Air | None = spec(Air(), optional(Nested(Air)), doc="air resistance on the cloth (cloth.air); None: a vacuum")
    device: str = spec("cpu", _Device(), doc="Warp's device: cuda runs the solver on an NVIDIA GPU "
                       "(bench/cloth_device.py); bit-identical results are promised on the CPU only")

    def __post_init__(self):
        check_fields(self, "cloth")
        if self.max_substeps < self.substeps:
            raise ConfigError("cloth.max_substeps", self.max_substeps,
                              f"give at least substeps ({self.substeps})")


@dataclass
class ClothTrack:
    """Simulated garment vertices per clip frame, each (F, V, 3) in its layer's vertex order
    (``PosedLayer.vertices`` of the garment named by the key)."""

    frames: dict

    @property
    def n_frames(self) -> int:
        return len(next(iter(self.frames.values())))

    def rolled(self, start: int) -> ClothTrack:
        """The track started at frame ``start`` and wrapped round, as ``Motion.rolled`` starts
        its clip."""
        k = int(start) % self.n_frames
        return ClothTrack({name: np.roll(v, -k, 0) for name, v in self.frames.items()})

    def at(self, time: float) -> dict:
        """Each garment's vertices at fractional clip frame ``time`` (clamped; linear between
        frames, a whole ``time`` is that frame exactly)."""
        t = float(np.clip(time, 0, self.n_frames - 1))
        i = min(int(np.floor(t)), self.n_frames - 1)
        if t == i:
            return {k: v[i] for k, v in self.frames.items()}
        a = t - i
        return {k: (1 - a) * v[i] + a * v[i + 1] for k, v in self.frames.items()}


@dataclass
class ClothPiece:
    """One piece of cloth as particles: its triangles, the particles held (moved, not
    simulated) and its fabric. ``carried`` (None: none): particles the solver does not move
    either, set each step where the cloth round them puts them (``_Carry``). ``rest``: the
    cloth's rest shape, as cut (None: as it is put on). A garment's is its rest-pose mesh: put
    on at a clip's first pose, skinned and pushed out of the legs, a stride had stretched its
    edges 4-15 cm (a vertex pushed out alone: a spike), and cloth keeps its rest shape's spikes."""

    faces: np.ndarray  # (T, 3) particle indices
    held: np.ndarray   # (P,) bool
    fabric: Fabric
    carried: np.ndarray | None = None  # (P,) bool
    rest: np.ndarray | None = None     # (P, 3)
    flat: bool = False  # bends from flat (sewn from flat panels), not from the rest shape's curvature
    sheltered: bool = False  # worn close over the body, its faces wound outward: no drag on its body side (``air``)


@dataclass
class Collider:
    """A mesh that the cloth cannot pass, possibly moving: ``at(frame) -> (collider vertices,
    every piece's particles concatenated)`` gives the collider and where the held particles
    are (the others' entries are ignored but the first frame's, which start the cloth)."""

    faces: np.ndarray
    at: Callable[[int], tuple[np.ndarray, np.ndarray]]
    fps: float
    n_frames: int
    project: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None  # (collider vertices, particles) ->
    # particles moved out of the collider, after each frame (the solver's contacts are soft)
    lead: Callable[[float], tuple[np.ndarray, np.ndarray]] | None = None  # as ``at``, from w = 0 (where the cloth
    # is put on) to w = 1 (frame 0), over ``ClothSettings.lead_s`` at the start of the settling
    slippery: np.ndarray | None = None  # (T,) bool: faces that push the cloth without friction (the hands:
    # with friction a walking hand dragged a pleated skirt's side up to the waist, an edge 13 cm past its
    # rest length, issue 34's stability clip 171); a closed mesh of its own, as the rest is (``_collider_parts``)
    body_count: int | None = None  # how many of ``faces`` (the first) are the closed body's; None: all. Those after
    # them: the skinned garments worn under a ``ClothKind.layered`` one (``inner``: open shells, capped where
    # ``_collider_parts`` closes the collider) and the web between its thighs (``cloth.web``)
    inner: tuple[np.ndarray, ...] = ()  # each garment's (T, 3), inner first (trousers, then the top over them)

    @property
    def body_faces(self) -> np.ndarray:
        return self.faces if self.body_count is None else self.faces[:self.body_count]


@dataclass
class _Garment:
    """A subject's simulated garment: ``rows`` the layer vertex each particle is (the first of
    its group: welded, short edges collapsed, ``_particles``), ``index`` the particle of each
    layer vertex but the hem band's; the band
    (``band``: its vertices' edge vertices, ``depth``: how far in along the cloth's normal) is
    not simulated: its few-millimetre triangles are where VBD went unstable (pleated skirts),
    so it follows its edge."""

    name: str
    part: int
    rows: np.ndarray
    index: np.ndarray
    piece: ClothPiece
    faces: np.ndarray  # the layer's faces but the band's
    band: np.ndarray
    depth: np.ndarray
    sink: np.ndarray | None = None  # (P,) metres each held particle is set in from the skinned garment (``seated``)

    def place(self, layer: np.ndarray) -> np.ndarray:
        """Where the particles go on the skinned garment's ``layer`` vertices: held ones ``sink``
        metres in along the cloth's normal."""
        q = layer[self.rows]
        if self.sink is None:
            return q
        return q - vertex_normals(q, self.piece.faces) * self.sink[:, None]


def simulated_garments(human, names: list[str] | None = None) -> list[_Garment]:
    """The subject's garments that the cloth stage simulates (those of them in ``names``, one of
    ``kinds.stages``; None: all), as particles."""
    every = simulated([m.params.kind for m in human.garments])
    out, names = [], every if names is None else names
    for k, part in enumerate(human.parts):
        if part.name not in names:
            continue
        kind = CLOTH_KINDS[part.name]
        mesh, band, main, faces = _without_band(human, part)
        rows, index = _particles(part.rest[:main], faces)
        cloth = _without_fins(_proper(index[faces]))
        held = kind.held(part.rest[rows], human.regions) | _cuffs(human, part.rest[rows], kind.cuffs) | \
            _covered(human, part.rest[rows], part.name, every)
        if held.all():  # nothing of it hangs (shorts under a skinned shirt that reaches past them): skinned
            continue
        carried = slight(part.rest[rows], cloth, kind.slight) & ~held
        lonely = carried & ~_beside_free(cloth, carried, len(rows))
        held, carried = held | lonely, carried & ~lonely
        fabric = FABRICS[fabric_of(kind, mesh.params)]
        normals = vertex_normals(part.rest[:main], faces)[band]
        depth = np.einsum("ij,ij->i", part.rest[band] - part.rest[main:], normals)  # signed: towards the body
        piece = ClothPiece(cloth, held, fabric, carried, part.rest[rows], flat=kind.flat, sheltered=kind.sheltered)
        sink = None if kind.seat is None else seated(human, part.rest[rows], held, kind.seat, mesh.offset, cloth,
                                                     _under_yoke(human, part.name))
        out.append(_Garment(part.name, k, rows, index, piece, faces, band, depth, sink))
    return out


def seated(human, rest: np.ndarray, held: np.ndarray, seat: float, offset: float, faces: np.ndarray,
           under: tuple | list = ()) -> np.ndarray:
    """(P,) metres to set each held particle in so that it stands ``seat`` over the rest body
    and the garments ``under`` it (``MeshIndex``es: the top under a jacket), none where it is
    closer already or inside one (a jacket's back in a hoodie's hood): the shell proper, which
    stands the garment's ``offset`` off the body, in full under 3 cm below the neck's base; not
    at all above that base, nor over ``offset`` + 8 mm, so a collar stands round the neck and a
    hood lies down the back as they were cut (set in with the shell, a hoodie's hood went under
    its back). Moved along its normal, the cloth only goes in where that normal is the body's
    (not at a hood's seam), by no more than ``SINK_SLOPE`` a metre over a neighbour and not at
    all on its open edges (``_HeldEdges.gentle``), and no held triangle is turned over: each of these
    turned some over (shards at necklines and cuffs; bench/RESULTS.md, session 101)."""
    from synmitsuba.body.collide import Surface
    surface = Surface.of(human.body.vertices, human.body.faces, human._incidence, human._around)
    height, outward = surface.clearance(rest, band=0.1)
    below_neck = np.clip((human.regions.neck_y - rest[:, 1]) / 0.03, 0.0, 1.0)
    shell = np.clip((offset + 0.008 - height) / 0.005, 0.0, 1.0)
    for mesh in under:
        height = np.minimum(height, np.maximum(mesh.signed_distance(rest), 0.0))
    facing = np.clip((np.einsum("ij,ij->i", vertex_normals(rest, faces), outward) - 0.7) / 0.2, 0.0, 1.0)
    held_edges = _HeldEdges.of(rest, faces, held)
    sink = held_edges.gentle(np.where(held, np.clip(height - seat, 0.0, None) * below_neck * shell * facing, 0.0))
    for _ in range(8):  # not on a held sliver that the move would still turn over
        placed = rest - vertex_normals(rest, faces) * sink[:, None]
        turned = held[faces].all(1) & (np.einsum("ij,ij->i", face_normals(rest[faces]), face_normals(placed[faces])) < 0.5)
        if not turned.any():
            break
        sink[faces[turned].ravel()] = 0.0
        sink = held_edges.gentle(sink)
    return sink


SINK_SLOPE = 0.5  # metres a held particle is set in more than its neighbour, a metre between them


@dataclass
class _HeldEdges:
    """The held cloth's edges (E, 2), both ways, ``SINK_SLOPE`` times their rest lengths, and the
    particles on the cloth's open edges (``ends``: a neckline, a cuff)."""
    edges: np.ndarray
    step: np.ndarray
    ends: np.ndarray

    @classmethod
    def of(cls, rest: np.ndarray, faces: np.ndarray, held: np.ndarray) -> "_HeldEdges":
        e = unique_rows(np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1))
        e = e[held[e[:, 0]] & held[e[:, 1]]]
        e = np.concatenate([e, e[:, ::-1]])
        return cls(e, SINK_SLOPE * np.linalg.norm(rest[e[:, 0]] - rest[e[:, 1]], axis=1), np.unique(open_edges(faces)))

    def gentle(self, sink: np.ndarray) -> np.ndarray:
        """``sink`` lowered until no held particle is set in more than ``step`` over a held
        neighbour's (a distance transform over the edges), and none on the open edges (moved
        along their normals, which lean out there, the triangles beside them turned over)."""
        out = sink.copy()
        out[self.ends] = 0.0
        while True:
            bound = out.copy()
            np.minimum.at(bound, self.edges[:, 0], out[self.edges[:, 1]] + self.step)
            if np.array_equal(bound, out):
                return out
            out = bound


def _under_yoke(human, name: str) -> list[MeshIndex]:
    """The rest surfaces (``MeshIndex``) of the garments worn under garment ``name`` that reach
    its yoke (a top under a jacket)."""
    top = human.regions.shoulder[1] - 0.04
    return [MeshIndex(human.parts[k].rest, human.parts[k].faces) for k in _worn_under(human, name)
            if human.parts[k].rest[:, 1].max() > top]


def _without_band(human, part):
    """A garment layer's mesh (``GarmentMesh``), its hem band's edge vertices, how many of its
    vertices come before the band's and its faces but the band's (the band is the last of both)."""
    mesh = next(m for m in human.garments if m.params.kind == part.name)
    band = hem_sources(mesh)
    return mesh, band, len(part.rest) - len(band), part.faces[:len(part.faces) - mesh.hem[0]]


def _worn_under(human, name: str) -> list[int]:
    """The parts (indices) of the garments that the subject wears under garment ``name``."""
    under = set(worn_under(name, [m.params.kind for m in human.garments]))
    return [k for k, part in enumerate(human.parts) if part.name in under]


def _cuffs(human, rest: np.ndarray, band: float) -> np.ndarray:
    """(V,) bool: the garment's vertices within ``band`` metres (along the arm) of each sleeve's
    end, by the arm coordinate of their nearest body vertex (``BodyRegions.arm_s``); none for 0."""
    held = np.zeros(len(rest), bool)
    if band <= 0:
        return held
    from scipy.spatial import cKDTree
    r = human.regions
    nearest = cKDTree(human.body.vertices).query(rest)[1]
    arm = np.isin(r.group[nearest], ["upperarm", "lowerarm", "hand"])
    s = r.arm_s[nearest] * r.arm_length
    for side in (rest[:, 0] > 0, rest[:, 0] <= 0):
        sleeve = arm & side
        if sleeve.any():
            held |= sleeve & (s >= s[sleeve].max() - band)
    return held


COVER = 0.02  # metres under the end of a skinned garment worn over a simulated one that it is held down to


def _covered(human, rest: np.ndarray, name: str, every: list[str]) -> np.ndarray:
    """(V,) bool: the garment's vertices from ``COVER`` under the lowest end of each skinned
    garment worn over it up (its lowest vertex over the torso or legs, not a sleeve's): free
    cloth there would pass through the skinned one (trousers' legs under a coat's skirt, or
    under a t-shirt that stays skinned under a jacket). None when nothing skinned is over it."""
    over = [w for w in worn_over(name, [m.params.kind for m in human.garments]) if w not in every]
    if not over:
        return np.zeros(len(rest), bool)
    from scipy.spatial import cKDTree
    tree, low = cKDTree(human.body.vertices), np.inf
    for part in human.parts:
        if part.name in over:
            body = np.asarray(human.regions.group)[tree.query(part.rest)[1]]
            low = min(low, float(part.rest[np.isin(body, ["torso", "upperleg", "lowerleg"]), 1].min(initial=np.inf)))
    return rest[:, 1] >= low - COVER


SHORT = 0.002  # metres: a cloth edge shorter than this is collapsed to a point (see ``_particles``)


def _particles(rest: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The garment's particles: ``rows``, the layer vertex each one is, and ``index``, the
    particle of each layer vertex. Its uv seams are welded, and the ends of every edge under
    ``SHORT`` are one particle: the cut between a dress's bodice and its skirt leaves vertices
    0.4 mm apart and needles (22 x 22 x 0.5 mm) under the held line, which the solver's bending
    flipped back and forth until a particle beside them ran off at 240 m/s, 3 m within a frame
    (issue 34's stability clip 324: a shift in a jog)."""
    rows, index = np.unique(weld(rest), return_inverse=True)
    index = index.reshape(-1)
    first, index2 = np.unique(collapse_short_edges(rest[rows], index[faces], SHORT), return_inverse=True)
    return rows[first], index2.reshape(-1)[index]


def _proper(faces: np.ndarray) -> np.ndarray:
    """``faces`` but those with a corner twice (an edge collapsed)."""
    return faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])]


def _without_fins(faces: np.ndarray) -> np.ndarray:
    """``faces`` (over particles) but those that occur twice: a dress's two halves each had a
    sliver on their seam line, back to back, which welded into a fin on the seam (the seam's
    edges of three triangles, one of four) that Newton read as non-manifold: its bending edges
    and the solver's colouring went wrong ("node_idx -1 is out of range", the README's turn).
    Without the fin each seam edge joins the two halves' triangles alone."""
    _, inverse, count = unique_rows(np.sort(faces, axis=1), return_inverse=True, return_counts=True)
    return faces[count[inverse.reshape(-1)] == 1]


SLIGHT = 0.35  # a particle with under this share of the median particle's cloth is held (see ``slight``)


def slight(q: np.ndarray, faces: np.ndarray, share: float = SLIGHT) -> np.ndarray:
    """(P,) bool: particles whose triangles hold under ``share`` of the median particle's area.
    The solver's pull on a particle scales with that area: slivers where a dress's bodice meets
    its skirt, just under the held line, left a shift's vertex with 1 % of it, which a running
    hand threw off and the cloth never pulled back (1.1 m from its neighbours: issue 34's
    stability clip 164); one with 31 %, in two triangles, was flung 1.6 m in a squat (clip 222).
    Most lie within 2.5 cm under the held line (over 10 dress clips: 4-22 a garment); the corners
    of a vent's hem (one and two triangles) are the others. Carried (``_Carry``), such a particle
    goes where the cloth round it goes: held to the skinned garment, a vent's corner kept to the
    skinned hem while the cloth's hem swung, its edges up to 3 cm past their cut in a jog (clip
    256; carried, 4 mm)."""
    area = np.zeros(len(q))
    np.add.at(area, faces.ravel(), np.repeat(triangle_areas(q[faces]), 3))
    return area < share * np.median(area[area > 0])


def _within_two_edges(faces: np.ndarray, n: int):
    """(n, n) sparse matrix, non-zero where two of ``n`` particles are within two edges."""
    from scipy.sparse import coo_matrix
    pairs = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    near = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    return ((near + near.T) + (near + near.T) @ (near + near.T)).tocsr()


def _beside_free(faces: np.ndarray, carried: np.ndarray, n: int) -> np.ndarray:
    """(P,) bool: particles within two edges of one that is not carried: a carried particle
    is placed by a fit to those (``_Carry``), and one with none has nothing to follow."""
    return (_within_two_edges(faces, n) @ (~carried).astype(float)) > 0


def _with_band(g: _Garment, q: np.ndarray) -> np.ndarray:
    """(F, V, 3) layer vertices from the simulated ones (F, main, 3): the hem band ``depth``
    in from its edge along the simulated cloth's normal there."""
    if not len(g.band):
        return q
    n = np.stack([vertex_normals(f, g.faces)[g.band] for f in q])
    return np.concatenate([q, q[:, g.band] - n * g.depth[None, :, None]], axis=1)


def simulate_cloth(human, motion, settings: ClothSettings | None = None) -> ClothTrack | None:
    """The subject's simulated garments over every frame of ``motion`` (placed, as rendered);
    None when it wears none that the cloth stage simulates. Raises ``ClothError`` naming the
    garment and frame where a simulation goes non-finite or strays ``max_drift`` from the
    skinned garment."""
    s = settings or ClothSettings()
    done: dict = {}
    for names in stages([m.params.kind for m in human.garments]):
        garments, collider = cloth_inputs(human, motion, s, names, done)
        if not garments:
            continue
        q = drape([g.piece for g in garments], collider, s, names=[g.name for g in garments])
        frames, start = {}, 0
        for g in garments:
            frames[g.name] = _with_band(g, q[:, start:start + len(g.rows)][:, g.index])
            start += len(g.rows)
        done.update(_outside_body(frames, collider, s))
    return ClothTrack(done) if done else None


def _outside_body(frames: dict, collider: Collider, s: ClothSettings) -> dict:
    """Every garment vertex, held and hem band too, out of the body at each frame by half the
    particle radius (``outside.keep_outside``: the whole body mesh, not the nearest vertices'),
    then out of each garment worn under it, then (if any was) out of the body again."""
    from synmitsuba.cloth.outside import keep_outside
    inner = [_capped(faces, 1.0) for faces in collider.inner]
    for f in range(collider.n_frames):
        body = collider.at(f)[0]
        for v in frames.values():
            v[f] = keep_outside(body, collider.body_faces, v[f], s.particle_radius / 2)
            # and out of each garment under it, closed (open, a winding number reads nothing), inner first,
            # twice over two (the top's push can end in the trousers where they overlap): out of the union of a
            # jacket's t-shirt and trousers, a vertex between them at the hips was set out of the trousers, still
            # 18 mm inside the t-shirt (bench/RESULTS.md, session 91)
            for part in inner * min(len(inner), 2):
                v[f] = keep_outside(part.place(body), part.faces, v[f], s.particle_radius / 2)
            # and out of the body last: where a garment under it runs into the body (the trousers at a squat's
            # hip crease) the push out of that garment ended inside the body: a coat's vertex 10 mm inside
            # the belly (bench/RESULTS.md, session 97). The body wins: the garment under it is inside there too
            if inner:
                v[f] = keep_outside(body, collider.body_faces, v[f], s.particle_radius / 2)
    return frames


@dataclass
class _Under:
    """A skinned garment worn under a ``layered`` simulated one, as part of its collider: the
    layer's vertices ``rows`` (its uv seams welded, its hem band left out: an open shell whose
    openings ``_collider_parts`` caps) and its faces over them."""

    part: int
    rows: np.ndarray
    faces: np.ndarray

    @classmethod
    def of(cls, human, k: int) -> _Under:
        part = human.parts[k]
        _, _, main, faces = _without_band(human, part)
        rows, index = np.unique(weld(part.rest[:main]), return_inverse=True)
        return cls(k, rows, _proper(index.reshape(-1)[faces]))


def cloth_inputs(human, motion, s: ClothSettings, names: list[str] | None = None,
                 done: dict | None = None) -> tuple[list[_Garment], Collider]:
    """The subject's simulated garments (those in ``names``; None: all) and the moving body they
    drape over: the closed body (and, under a ``layered`` kind, the garments worn under it:
    simulated, as ``done`` has them per frame, else skinned) and the skinned garments'
    particles (where held ones go) per frame of ``motion``."""
    garments, done = simulated_garments(human, names), done or {}
    layered = any(CLOTH_KINDS[g.name].layered for g in garments)
    under = [_Under.of(human, k) for k in sorted({k for g in garments if CLOTH_KINDS[g.name].layered
                                                   for k in _worn_under(human, g.name)},
                                                  key=lambda k: (GARMENTS[human.parts[k].name].order, k))]
    web, web_faces = thigh_web(human.body.vertices, human.regions.group, human.regions.crotch_y) if layered else \
        (np.zeros(0, np.int64), np.zeros((0, 3), np.int64))

    def posed(rotations: np.ndarray, root: np.ndarray, face, frame: int) -> tuple[np.ndarray, np.ndarray]:
        layers = human.pose(rotations, root, face=face)  # (closed body, skinned garments' particles)
        body = human.closed_body(layers)
        worn = [done[human.parts[u.part].name][frame] if human.parts[u.part].name in done else layers[u.part].vertices
                for u in under]
        body = np.concatenate([body, *(v[u.rows] for v, u in zip(worn, under)), body[web]])
        return body, np.concatenate([g.place(layers[g.part].vertices) for g in garments])

    def at(frame: int) -> tuple[np.ndarray, np.ndarray]:
        rotations, root = motion.frame(frame)
        return posed(rotations, root, motion.face_at(frame), frame)

    arms = arm_joints(human.skeleton)

    def lead(w: float) -> tuple[np.ndarray, np.ndarray]:  # a simulated garment under it as at frame 0 (the legs
        rotations, root = arms_from_rest(motion.frame(0), arms, w)  # are, only the arms come down)
        return posed(rotations, root, motion.face_at(0), 0)

    seals, nb = _seals(human, garments), len(human.body.vertices)

    def project(body: np.ndarray, q: np.ndarray) -> np.ndarray:
        for seal in seals:
            q = seal.apply(body[:nb], q)
        return out_of_body(human, body[:nb], q, s.particle_radius / 2)

    starts = np.cumsum([nb] + [len(u.rows) for u in under])
    inner = tuple(u.faces + a for u, a in zip(under, starts))
    if not layered:
        faces, body_count = human.body.faces, None
    else:
        faces = np.concatenate([human.body.faces, *inner, web_faces + starts[-1]])
        body_count = len(human.body.faces)
    hands = (np.asarray(human.regions.group) == "hand")[human.body.faces].any(axis=1)
    hands = np.concatenate([hands, np.zeros(len(faces) - len(hands), bool)])
    return garments, Collider(faces, at, motion.fps, motion.n_frames, project, lead, slippery=hands,
                              body_count=body_count, inner=inner)


def _seals(human, garments: list[_Garment]) -> list[WaistSeal]:
    """A ``WaistSeal`` for each garment whose kind is ``sealed`` (a skirt's waistband)."""
    out, start = [], 0
    for g in garments:
        n = len(g.rows)
        if CLOTH_KINDS[g.name].sealed:
            rest = human.parts[g.part].rest[g.rows]
            out.append(waist_seal(rest, g.piece.held, np.arange(start, start + n), human.body.vertices,
                                  human.regions.group == "torso"))
        start += n
    return out


def out_of_body(human, body: np.ndarray, q: np.ndarray, margin: float) -> np.ndarray:
    """Particles under ``margin`` over the posed body set ``margin`` over it, along the
    outward normal at the exact closest point (``body.collide.Surface.clearance``): the
    solver's contacts are springs, and a fast thigh can carry a few vertices under the skin."""
    from synmitsuba.body.collide import Surface
    surface = Surface.of(body, human.body.faces, human._incidence, human._around)
    height, normal = surface.clearance(q, band=margin)
    low = np.flatnonzero(height < margin)
    q = q.copy()
    q[low] += normal[low] * (margin - height[low])[:, None]
    return q


def drape(pieces: list[ClothPiece], collider: Collider, settings: ClothSettings | None = None,
          names: list[str] | None = None) -> np.ndarray:
    """(F, P, 3) particle positions per frame of cloth ``pieces`` (their particles concatenated)
    over the moving ``collider`` and the ground at y = 0: ``settle_s`` at the first frame, then
    each frame in ``substeps``, the collider and the held particles moved linearly between
    frames. ``names`` name the pieces in a ``ClothError``."""
    import warp as wp

    from synmitsuba.process import apply_warp_settings
    apply_warp_settings()  # before Newton is first imported: its kernels are made then
    s = settings or ClothSettings()
    names = names or [f"piece {k}" for k in range(len(pieces))]
    with wp.ScopedDevice(s.device):
        return _run(pieces, collider, s, names)


def _model(pieces: list[ClothPiece], parts: list[_Part], collider_v: np.ndarray, q: np.ndarray, s: ClothSettings):
    """Newton's model: the ground, the collider's closed ``parts`` as mesh shapes (returned, to
    move them), each piece as cloth of its fabric, its held particles inactive (moved, not
    simulated)."""
    import newton
    import warp as wp
    builder = newton.ModelBuilder(up_axis=newton.Axis.Y)  # gravity along -y
    builder.add_ground_plane()
    meshes = []
    for part in parts:
        mesh = newton.Mesh(part.place(collider_v).astype(np.float32), part.faces.astype(np.int32).ravel())
        cfg = builder.default_shape_cfg.copy()
        cfg.mu = part.mu
        builder.add_shape_mesh(body=-1, mesh=mesh, cfg=cfg)
        meshes.append((mesh, part))
    start = 0
    for p in pieces:
        f, pts = p.fabric, _rest_shape(p, q[start:start + len(p.held)]).astype(np.float32)
        edges = len(builder.edge_rest_angle)
        builder.add_cloth_mesh(pos=wp.vec3(0, 0, 0), rot=wp.quat_identity(), scale=1.0,  # type: ignore[arg-type]
                               vel=wp.vec3(0, 0, 0), vertices=[wp.vec3(*v) for v in pts],
                               indices=p.faces.astype(np.int32).ravel().tolist(), density=f.density, tri_ke=f.stretch,
                               tri_ka=f.shear, tri_kd=f.damping, edge_ke=f.bend, edge_kd=f.bend_damping,
                               particle_radius=s.particle_radius)
        if p.flat:
            builder.edge_rest_angle[edges:] = [0.0] * (len(builder.edge_rest_angle) - edges)
        start += len(p.held)
    builder.color(include_bending=True)
    model = builder.finalize()
    assert model.particle_q is not None  # a model with particles has their positions
    model.particle_q.assign(q.astype(np.float32))  # put on where the held ones are (the rest shape's only the cloth's)
    held = np.concatenate([p.held for p in pieces])
    old = model.particle_flags
    assert old is not None  # a model with particles has their flags
    flags = old.numpy()
    flags[held | _carried(pieces)] &= ~newton.ParticleFlags.ACTIVE
    model.particle_flags = wp.array(flags, dtype=old.dtype)
    model.soft_contact_ke, model.soft_contact_kd = s.contact_stiffness, 1.0e-2
    model.soft_contact_mu = float(np.mean([p.fabric.friction for p in pieces]))
    return model, meshes, held


@dataclass
class _Part:
    """A closed piece of the collider for Newton: its ``vertices`` (collider vertices) and a cap
    vertex at the middle of each of its ``loops`` (where it was cut from the rest), its faces
    over those, capped, and its friction (Newton's shape ``mu``, 1 by default: it takes the
    geometric mean of it and the fabric's)."""

    vertices: np.ndarray
    loops: list
    faces: np.ndarray
    mu: float

    def place(self, v: np.ndarray) -> np.ndarray:
        """The part's vertices from the collider's ``v`` (positions or velocities)."""
        caps = [v[loop].mean(0) for loop in self.loops]
        return np.concatenate([v[self.vertices], caps]) if caps else v[self.vertices]


WORN_MU = 0.2  # Newton's shape mu of the garments worn under a simulated one (and the web between the thighs):
# cloth slides over cloth; at the body's 1, a t-shirt's back was carried up over the seat of the trousers and
# stood out behind as a stiff bell (bench/RESULTS.md, session 90)


def _collider_parts(faces: np.ndarray, slippery: np.ndarray | None, n: int, worn: int | None = None) -> list[_Part]:
    """The collider's faces with friction, those from ``worn`` on (the garments worn under the
    cloth and the web between the thighs: ``WORN_MU``) and its ``slippery`` ones (``mu`` 0), each closed:
    open where they were cut apart, Newton's mesh contacts took cloth near the cut for inside
    and threw it off (9 of 37 stability clips raised), so each cut loop is capped by a fan
    round a vertex at its middle."""
    if (slippery is None or not slippery.any()) and worn is None:
        return [_Part(np.arange(n), [], faces, 1.0)]
    slippery = np.zeros(len(faces), bool) if slippery is None else slippery
    rest = np.arange(len(faces)) >= (len(faces) if worn is None else worn)  # the faces after the body's
    groups = ((~slippery & ~rest, 1.0), (rest, WORN_MU), (slippery, 0.0))
    return [_capped(faces[pick], mu) for pick, mu in groups if pick.any()]


def _capped(f: np.ndarray, mu: float) -> _Part:
    """The mesh of faces ``f`` closed: each loop of edges that only one face has capped by a fan
    round a vertex at its middle."""
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    _, first, count = unique_rows(np.sort(directed, axis=1), return_index=True, return_counts=True)
    cut = directed[first[count == 1]]  # (a, b) as the part's own faces run round it
    loops = _loops(cut)
    used, local = np.unique(f, return_inverse=True)  # the cut's vertices are the faces' too
    f_local = local.reshape(-1, 3)
    caps = [np.stack([np.searchsorted(used, b), np.searchsorted(used, a), np.full(len(a), len(used) + k)], axis=1)
            for k, (a, b) in enumerate(cut[np.isin(cut[:, 0], loop)].T for loop in loops)]
    return _Part(used, loops, np.concatenate([f_local, *caps]), mu)


def _loops(edges: np.ndarray) -> list[np.ndarray]:
    """The vertices (sorted) of each closed loop that ``edges`` (E, 2) make, the loops in the
    order of their smallest vertex."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    used, local = np.unique(edges, return_inverse=True)
    local = local.reshape(-1, 2)
    graph = coo_matrix((np.ones(len(local)), (local[:, 0], local[:, 1])), shape=(len(used), len(used)))
    _, label = connected_components(graph, directed=False)
    return [used[label == k] for k in range(label.max() + 1)] if len(used) else []


def _run(pieces: list[ClothPiece], collider: Collider, s: ClothSettings, names: list[str]) -> np.ndarray:
    import newton
    plan = Schedule.of(collider, s)
    (body0, q0), start = plan.first, plan.start()
    parts = _collider_parts(collider.faces, collider.slippery, len(start[0]), collider.body_count)
    model, meshes, held = _model(pieces, parts, start[0], start[1], s)
    solver = newton.solvers.SolverVBD(model=model, iterations=s.iterations, particle_enable_self_contact=s.self_contact,
                                      particle_self_contact_margin=s.self_contact_margin,
                                      particle_self_contact_gap=_self_contact_gap(s),
                                      dat_conservative_bound_relaxation=DAT_RELAXATION,
                                      particle_rest_shape_contact_exclusion_radius=s.self_contact_exclusion)
    s0, s1, control = model.state(), model.state(), model.control()
    pipeline = newton.CollisionPipeline(model, soft_contact_gap=s.contact_gap,
                                        enable_rigid_soft_full_surface_contact=s.full_contact)
    contacts = pipeline.contacts()
    out = np.empty((collider.n_frames, len(q0), 3))
    faces, weight = _all_faces(pieces)
    shelter = np.concatenate([np.full(len(p.faces), p.sheltered) for p in pieces])
    lee = shelter if shelter.any() else None
    rest = _rest_shapes(pieces, start[1])
    edges = [_Edges.of(p.faces + k, held, rest) for p, k in zip(pieces, np.cumsum([0] + [len(p.held) for p in pieces]))]
    carry = _Carry.of(pieces, rest)
    prev, near = start, _near(body0, q0)
    for f in range(-plan.settle, collider.n_frames):
        now, moving = plan.at(f), plan.moving(f)
        if plan.lead and f == plan.lead - plan.settle:  # the arms are down: the body stands at frame 0, still
            _move(meshes, body0, np.zeros_like(body0))
        n = _substeps(prev[0][near], now[0][near], s)
        if s.self_contact:  # no held particle further than self-contact lets the cloth follow in a step
            n = max(n, _substeps(prev[1][held], now[1][held], s))
        dt = 1.0 / collider.fps / n
        if f == 1:
            s0.particle_qd.assign(s0.particle_qd.numpy() + _start_velocity(pieces, s0.particle_q.numpy(), prev[1], now[1],
                                                                           collider.fps))
        for k in range(n):
            w = (k + 1) / n
            if moving:
                _move(meshes, prev[0] + w * (now[0] - prev[0]), (now[0] - prev[0]) * collider.fps)
            if moving or len(carry.index):
                q = s0.particle_q.numpy()
                if moving:
                    q[held] = (prev[1] + w * (now[1] - prev[1]))[held]
                s0.particle_q.assign(carry.place(q))
            pipeline.collide(s0, contacts)
            s0.clear_forces()
            if s.air is not None:
                _blow(s0, faces, weight, dt, s.air, lee)
            solver.step(s0, s1, control, contacts, dt)
            s0, s1 = s1, s0
        q = s0.particle_q.numpy()
        if collider.project is not None:
            q = collider.project(now[0], q.astype(np.float64))
            q[held] = now[1][held]
            s0.particle_q.assign(carry.place(q).astype(np.float32))
        if f >= 0:
            out[f] = s0.particle_q.numpy()
            _check(out[f], now[1], pieces, edges, names, f, s)
        prev = now
    return out


def _blow(state, faces: np.ndarray, weight: np.ndarray, dt: float, air: Air, sheltered: np.ndarray | None) -> None:
    """The air's drag on the cloth as the state's external particle forces for the next step."""
    forces = drag_forces(state.particle_q.numpy().astype(np.float64), state.particle_qd.numpy(), faces, weight, dt, air,
                         sheltered)
    state.particle_f.assign(forces.astype(np.float32))


def _all_faces(pieces: list[ClothPiece]) -> tuple[np.ndarray, np.ndarray]:
    """Every piece's triangles over the concatenated particles, and each one's areal density."""
    starts = np.cumsum([0] + [len(p.held) for p in pieces[:-1]])
    faces = np.concatenate([p.faces + s for p, s in zip(pieces, starts)])
    return faces, np.concatenate([np.full(len(p.faces), p.fabric.density) for p in pieces])


def _start_velocity(pieces: list[ClothPiece], q: np.ndarray, held_from: np.ndarray, held_to: np.ndarray,
                    fps: float) -> np.ndarray:
    """(P, 3) float32 velocities that move each piece's particles ``q`` as its held ones move
    from ``held_from`` to ``held_to`` in a frame (a rigid fit; 0 for a piece that holds none),
    added to the cloth's own when the clip starts: it starts at full speed, and cloth settled at
    rest was thrown (a circle skirt's hem to the chest in a run's first frames)."""
    out, start = np.zeros_like(q, dtype=np.float64), 0
    for p in pieces:
        part = slice(start, start + len(p.held))
        start += len(p.held)
        a, b = held_from[part][p.held], held_to[part][p.held]
        if not len(a):
            continue
        spread = np.linalg.svd(a - a.mean(0), compute_uv=False)
        if len(spread) > 1 and spread[1] > 1e-6 * spread[0]:  # a turn is fixed unless the held points are on a line
            rot, t = rigid_fit(a, b)
            out[part] = (np.einsum("ij,kj->ik", q[part], rot) + t - q[part]) * fps  # not BLAS: same bits at any thread count
        else:
            out[part] = (b - a).mean(0) * fps
    return out.astype(np.float32)


def _near(collider: np.ndarray, q: np.ndarray, reach: float = 0.15) -> np.ndarray:
    """The collider's vertices within ``reach`` of the cloth: where its speed sets the steps."""
    from scipy.spatial import cKDTree
    return np.flatnonzero(np.isfinite(cKDTree(q).query(collider, distance_upper_bound=reach)[0]))


# Newton's self-contact lets a particle move at most DAT_RELAXATION / 2 of its query radius (the
# contact margin and gap) between two detections (one a step). At the margin's 3 mm and half that
# again, 1.9 mm a step, a pair of trousers was left where a walk began (bench/RESULTS.md, session
# 99): the query radius now lets the cloth move ``max_step`` in a step, as far as the collider near
# it (``_substeps``) and, with self-contact, the held particles (``_run``) may.
DAT_RELAXATION = 0.85


def _self_contact_gap(s: ClothSettings) -> float:
    """Metres Newton's self-contact detection reaches past the contact margin: enough that the
    cloth may move ``max_step`` between two detections."""
    return max(s.self_contact_margin / 2, 2 * s.max_step / DAT_RELAXATION - s.self_contact_margin)


def _substeps(before: np.ndarray, after: np.ndarray, s: ClothSettings) -> int:
    """Steps for a frame: enough that no collider vertex near the cloth moves more than
    ``max_step`` in one (a running knee goes 15 cm in a frame and went through a skirt at 10),
    between ``substeps`` and ``max_substeps``."""
    move = float(np.linalg.norm(after - before, axis=1).max()) if len(before) else 0.0
    return int(np.clip(np.ceil(move / s.max_step), s.substeps, s.max_substeps))


def _move(meshes: list, vertices: np.ndarray, velocities: np.ndarray) -> None:
    for mesh, part in meshes:
        mesh.mesh.points.assign(part.place(vertices).astype(np.float32))
        mesh.mesh.velocities.assign(part.place(velocities).astype(np.float32))
        mesh.mesh.refit()


def _rest_shape(p: ClothPiece, put_on: np.ndarray) -> np.ndarray:
    return put_on if p.rest is None else np.asarray(p.rest)


def _rest_shapes(pieces: list[ClothPiece], put_on: np.ndarray) -> np.ndarray:
    """(P, 3) every piece's rest shape (``ClothPiece.rest``), the pieces' particles concatenated."""
    starts = np.cumsum([0] + [len(p.held) for p in pieces])
    return np.concatenate([_rest_shape(p, put_on[a:b]) for p, a, b in zip(pieces, starts[:-1], starts[1:])])


def _carried(pieces: list[ClothPiece]) -> np.ndarray:
    return np.concatenate([np.zeros(len(p.held), bool) if p.carried is None else p.carried for p in pieces])


@dataclass
class _Carry:
    """The carried particles (``ClothPiece.carried``) and, for each, the particles within two
    edges of it that are not carried (``ring``; ``owner``: whose ring each is). Each step a
    carried particle goes where a rigid fit of its ring's rest positions (``rest``: the cloth's
    rest shape) to their present ones takes it: with the cloth round it, never flung, never
    left behind."""

    index: np.ndarray
    owner: np.ndarray
    ring: np.ndarray
    rest: np.ndarray

    @classmethod
    def of(cls, pieces: list[ClothPiece], q: np.ndarray) -> _Carry:
        carried, faces = _carried(pieces), _all_faces(pieces)[0]
        if not carried.any():  # most pieces: no neighbourhoods to build
            none = np.zeros(0, np.int64)
            return cls(none, none, none, np.asarray(q, np.float64))
        near = _within_two_edges(faces, len(q))
        index = np.flatnonzero(carried)
        rows = [np.setdiff1d(near[i].indices, np.flatnonzero(carried)) for i in index]
        owner = np.repeat(np.arange(len(index)), [len(r) for r in rows])
        return cls(index, owner, np.concatenate(rows + [np.zeros(0, int)]).astype(int), np.asarray(q, np.float64))

    def place(self, q: np.ndarray) -> np.ndarray:
        """``q`` with the carried particles set, in place (returned). Sums by ``np.add.at`` and
        einsum: the same bits whatever the thread count."""
        if not len(self.index):
            return q
        n = np.bincount(self.owner, minlength=len(self.index))[:, None]
        a, b = self.rest[self.ring], np.asarray(q[self.ring], np.float64)
        ca, cb = np.zeros((len(self.index), 3)), np.zeros((len(self.index), 3))
        np.add.at(ca, self.owner, a)
        np.add.at(cb, self.owner, b)
        ca, cb = ca / n, cb / n
        h = np.zeros((len(self.index), 3, 3))
        np.add.at(h, self.owner, np.einsum("ni,nj->nij", a - ca[self.owner], b - cb[self.owner]))
        u, _, vt = np.linalg.svd(h)
        flip = np.ones((len(self.index), 3))
        flip[:, 2] = np.sign(np.linalg.det(u) * np.linalg.det(vt))
        rot = np.einsum("cij,cj,cjk->cki", u, flip, vt)  # (u diag(flip) vt).T: b ~ rot a
        q[self.index] = np.einsum("cij,cj->ci", rot, self.rest[self.index] - ca) + cb
        return q


@dataclass
class _Edges:
    """A piece's edges that the solver moves (a free particle at one end or both: held ones
    follow the skinned garment, stretched as skinning stretches it, 19 cm at a sleeve with the
    arms up) and their rest lengths (the solver's rest shape: ``ClothPiece.rest``)."""

    pairs: np.ndarray
    rest: np.ndarray

    @classmethod
    def of(cls, faces: np.ndarray, held: np.ndarray, q: np.ndarray) -> _Edges:
        pairs = unique_rows(np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1))
        pairs = pairs[~held[pairs].all(axis=1)]
        return cls(pairs, _lengths(q, pairs))

    def stretch(self, q: np.ndarray) -> float:
        """Metres the most stretched edge is longer than at rest."""
        return float((_lengths(q, self.pairs) - self.rest).max()) if len(self.pairs) else 0.0


def _lengths(q: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    return np.linalg.norm(q[pairs[:, 0]] - q[pairs[:, 1]], axis=1)


def _check(q: np.ndarray, start_q: np.ndarray, pieces: list[ClothPiece], edges: list[_Edges], names: list[str],
           frame: int, s: ClothSettings) -> None:
    """Raise ``ClothError`` for the first piece with a non-finite particle, one farther than
    ``max_drift`` from where ``at`` puts it (the skinned garment) or an edge ``max_stretch``
    longer than at rest (torn: issue 34's stability clip 164, a shift's vertex caught by a
    running hand, then 20 cm to 1.1 m from its neighbours while still within ``max_drift``)."""
    start = 0
    for p, e, name in zip(pieces, edges, names):
        part = slice(start, start + len(p.held))
        start += len(p.held)
        if not np.isfinite(q[part]).all():
            raise ClothError(name, frame, "non-finite vertices")
        drift = float(np.linalg.norm(q[part] - start_q[part], axis=1).max())
        if drift > s.max_drift:
            raise ClothError(name, frame, f"a vertex {drift:.2f} m from the skinned garment")
        stretch = e.stretch(q)
        if stretch > s.max_stretch:
            raise ClothError(name, frame, f"an edge stretched {stretch:.2f} m past its rest length: torn")
