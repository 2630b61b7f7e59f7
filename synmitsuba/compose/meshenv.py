"""Your own environment: a glTF/GLB, OBJ or PLY scene read with trimesh, its materials kept, its
walkable floor found by ray casting and its obstacles turned into boxes, so that placement and
cameras work on it as on the built-in environments.

``environment: {mesh: room.glb}`` (a YAML environment's ``mesh`` key, or a mesh file named
directly in ``compose.environments``). The floor is the height most of the straight-down
rays first stand on with ``CLEARANCE_M`` free above them; the mesh is lifted or lowered so
that floor lies at y = 0 (the convention of every stage). Cells on another height (steps,
slopes, table tops) or under something lower than ``CLEARANCE_M`` are obstacles; where a
ceiling stands over the floor, cameras stay under it.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

CELL_M = 0.1          # the floor grid
CLEARANCE_M = 2.0     # free height a walkable cell needs
FLOOR_TOL_M = 0.02    # a cell's floor within this of the floor height is walkable
MIN_FLOOR_M2 = 4.0    # less walkable floor than this is no floor (the top of a ball, a shelf)
LAYERS = 8            # surfaces followed down each vertical ray
MAX_TEXTURE_PX = 1024


@dataclass
class MeshPart:
    """One piece of the environment mesh: world vertices (V, 3), faces, uv (or None), material."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray | None
    material: object


@dataclass
class MeshFloor:
    """What ray casting found: ``offset_y`` (added to the mesh's y so its floor lies at 0),
    ``area`` (x_min, z_min, x_max, z_max) of the walkable cells, ``walkable`` (nz, nx) over the
    grid from ``origin`` (x, z) in ``CELL_M`` cells; boxes (N, 6), floor at y = 0:
    ``obstacles`` (every cell off the floor), ``keep_out`` (ceilings over the floor and all
    beyond the mesh: no camera goes there)."""

    offset_y: float
    area: list
    walkable: np.ndarray
    origin: tuple
    obstacles: np.ndarray
    keep_out: np.ndarray


def _material(visual):
    """Our Material from a trimesh visual: base colour texture (sRGB, times its factor, at most
    ``MAX_TEXTURE_PX``), roughness and metallic factors; vertex colours as their mean."""
    from synmitsuba._colour import srgb_decode
    from synmitsuba.scene.materials import Material
    kind = getattr(visual, "kind", None)
    if kind == "texture" and visual.material is not None:
        mat = visual.material
        image = getattr(mat, "baseColorTexture", None) or getattr(mat, "image", None)
        factor = getattr(mat, "baseColorFactor", None)
        if factor is None:
            factor = getattr(mat, "diffuse", None)
        factor = np.ones(3) if factor is None else np.asarray(factor, np.float64)[:3] / (255.0 if np.max(factor) > 1 else 1.0)
        rough = getattr(mat, "roughnessFactor", None)
        metal = getattr(mat, "metallicFactor", None)
        common = dict(kind="principled", roughness=float(0.7 if rough is None else np.clip(rough, 0, 1)),
                      metallic=float(0.0 if metal is None else np.clip(metal, 0, 1)))
        if image is not None:
            image = image.convert("RGB")
            if max(image.size) > MAX_TEXTURE_PX:
                k = MAX_TEXTURE_PX / max(image.size)
                image = image.resize((max(1, int(image.size[0] * k)), max(1, int(image.size[1] * k))))
            tex = srgb_decode(np.asarray(image, np.float32) / 255.0) * factor
            return Material(texture=np.clip(tex, 0, 1).astype(np.float32), **common)
        return Material(base_color=tuple(np.clip(srgb_decode(factor), 0, 1)), **common)
    colours = getattr(visual, "vertex_colors", None)
    if kind in ("vertex", "face") and colours is not None and len(colours):
        rgb = np.asarray(colours, np.float64)[:, :3].mean(0) / 255.0
        return Material(base_color=tuple(srgb_decode(rgb)), kind="principled", roughness=0.7)
    return Material(base_color=(0.5, 0.5, 0.5), kind="principled", roughness=0.7)


def load_mesh_parts(path: str, scale: float = 1.0, where: str = "environment.mesh") -> list[MeshPart]:
    """The mesh file's pieces in world coordinates (y up, metres times ``scale``)."""
    import trimesh
    from synmitsuba.errors import ConfigError
    try:
        loaded = trimesh.load(path, force="scene")
    except Exception as exc:  # trimesh raises many kinds on a bad file
        raise ConfigError(where, path, f"trimesh cannot read it ({type(exc).__name__}: {exc}); give a glTF/GLB, "
                          "OBJ or PLY file") from exc
    parts = []
    for k, geom in enumerate(loaded.dump()):  # type: ignore[attr-defined]  # force="scene" gives a Scene
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        uv = getattr(geom.visual, "uv", None) if getattr(geom.visual, "kind", None) == "texture" else None
        parts.append(MeshPart(f"envmesh{k}", np.asarray(geom.vertices, np.float64) * scale,
                              np.asarray(geom.faces, np.int64), None if uv is None else np.asarray(uv, np.float64),
                              _material(geom.visual)))
    if not parts:
        raise ConfigError(where, path, "the file holds no triangles; give a mesh with faces")
    return parts


def _layers(parts: list[MeshPart], xs: np.ndarray, zs: np.ndarray):
    """Heights (nz, nx, LAYERS) of the surfaces met going straight down from above the mesh at
    each cell centre (nan: none) and whether each faces up (|n_y| > 0.9)."""
    from synmitsuba.engine.raycast import surface_hits
    from synmitsuba.scene.scene import Scene
    scene = Scene()
    for p in parts:
        scene.add_mesh(p.name, p.vertices, p.faces)
    top = max(p.vertices[:, 1].max() for p in parts) + 1.0
    X, Z = np.meshgrid(xs, zs)
    n = X.size
    origins = np.stack([X.ravel(), np.full(n, top), Z.ravel()], 1)
    down = np.tile([0.0, -1.0, 0.0], (n, 1))
    heights = np.full((n, LAYERS), np.nan)
    flat = np.zeros((n, LAYERS), bool)
    normals = {p.name: np.cross(p.vertices[p.faces[:, 1]] - p.vertices[p.faces[:, 0]],
                                p.vertices[p.faces[:, 2]] - p.vertices[p.faces[:, 0]]) for p in parts}
    for layer in range(LAYERS):
        hits = surface_hits(scene, origins, down)
        got = np.isfinite(hits["t"])
        if not got.any():
            break
        y = origins[:, 1] - hits["t"]
        heights[got, layer] = y[got]
        for i in np.flatnonzero(got):
            nrm = normals[hits["names"][hits["shape"][i]]][hits["prim"][i]]
            flat[i, layer] = abs(nrm[1]) > 0.9 * np.linalg.norm(nrm)
        origins[got, 1] = y[got] - 1e-3
        origins[~got, 1] = -1e9
    return heights.reshape(X.shape + (LAYERS,)), flat.reshape(X.shape + (LAYERS,))


def _runs(mask: np.ndarray) -> list:
    """(row, first, last + 1) of every run of True cells along x in each row of ``mask``."""
    out = []
    for r in range(mask.shape[0]):
        row = np.concatenate([[False], mask[r], [False]])
        starts, ends = np.flatnonzero(~row[:-1] & row[1:]), np.flatnonzero(row[:-1] & ~row[1:])
        out += [(r, int(a), int(b)) for a, b in zip(starts, ends)]
    return out


def find_floor(parts: list[MeshPart], where: str = "environment.mesh") -> MeshFloor:
    """The walkable floor, obstacles and ceilings of a mesh (see the module's docstring)."""
    from synmitsuba.errors import ConfigError
    lo = np.min([p.vertices.min(0) for p in parts], 0)
    hi = np.max([p.vertices.max(0) for p in parts], 0)
    xs = np.arange(lo[0] + CELL_M / 2, hi[0], CELL_M)
    zs = np.arange(lo[2] + CELL_M / 2, hi[2], CELL_M)
    heights, flat = _layers(parts, xs, zs)
    above = np.concatenate([np.full(heights.shape[:2] + (1,), np.inf), heights[..., :-1]], -1)
    above = np.where(np.isnan(above), np.inf, above)
    candidate = flat & np.isfinite(heights) & (above - heights >= CLEARANCE_M)
    if not candidate.any():
        raise ConfigError(where, "mesh", f"no flat floor with {CLEARANCE_M} m free above it was found; give a mesh "
                          "with a walkable floor (y up)")
    levels = np.round(heights[candidate] / FLOOR_TOL_M) * FLOOR_TOL_M
    values, counts = np.unique(levels, return_counts=True)
    floor = float(np.median(heights[candidate][np.abs(levels - values[np.argmax(counts)]) <= FLOOR_TOL_M]))
    on_floor = candidate & (np.abs(heights - floor) <= FLOOR_TOL_M)
    walkable = on_floor.any(-1)
    if walkable.sum() * CELL_M ** 2 < MIN_FLOOR_M2:
        raise ConfigError(where, "mesh", f"its largest flat floor with {CLEARANCE_M} m free above it covers "
                          f"{walkable.sum() * CELL_M ** 2:.2f} m2, under {MIN_FLOOR_M2} m2; give a mesh with a walkable "
                          "floor (y up)")
    ceiling = np.where(on_floor, above, np.inf).min(-1) - floor
    iz, ix = np.nonzero(walkable)
    area = [float(xs[ix.min()] - CELL_M / 2), float(zs[iz.min()] - CELL_M / 2),
            float(xs[ix.max()] + CELL_M / 2), float(zs[iz.max()] + CELL_M / 2)]
    top, h = float(hi[1] - floor) + 1.0, CELL_M / 2
    # obstacles: every cell off the floor, up to above the mesh; keep-out: from 10 cm under the
    # lowest ceiling of a run of roofed cells upwards, and everything past the mesh's bounds
    obstacles = [[xs[a] - h, -1.0, zs[r] - h, xs[b - 1] + h, top, zs[r] + h] for r, a, b in _runs(~walkable)]
    roofed = walkable & np.isfinite(ceiling)
    keep_out = [[xs[a] - h, float(ceiling[r, a:b].min()) - 0.1, zs[r] - h, xs[b - 1] + h, top + 100.0, zs[r] + h]
                for r, a, b in _runs(roofed)]
    far, (x0, z0), (x1, z1) = 1e4, lo[[0, 2]], hi[[0, 2]]
    keep_out += [[x1, -far, -far, far, far, far], [-far, -far, -far, x0, far, far],
                 [-far, -far, z1, far, far, far], [-far, -far, -far, far, far, z0]]
    return MeshFloor(-floor, area, walkable, (float(xs[0]), float(zs[0])),
                     np.asarray(obstacles, np.float64).reshape(-1, 6), np.asarray(keep_out, np.float64))


def split_floor(part: MeshPart, offset_y: float) -> tuple[np.ndarray, np.ndarray]:
    """Face masks of a part lifted by ``offset_y``: (floor faces: flat, facing up, on y = 0;
    the rest)."""
    v = part.vertices + [0.0, offset_y, 0.0]
    tri = v[part.faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    on = (np.abs(tri[..., 1]).max(1) <= FLOOR_TOL_M) & (np.abs(n[:, 1]) > 0.99 * np.linalg.norm(n, axis=1))
    return on, ~on


@functools.lru_cache(maxsize=8)
def mesh_environment(path: str, scale: float, mtime: float) -> tuple[list, MeshFloor]:
    """(parts, floor) of a mesh file, read once per file version (``mtime``) and scale."""
    parts = load_mesh_parts(path, scale)
    return parts, find_floor(parts)
