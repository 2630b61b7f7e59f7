"""Render render_quality.py's exported scene with Blender Cycles (run by render_quality.py under
a Python that has ``bpy``; never imported by synmitsuba).

    python cycles_render.py SCENE.npz JOBS.json OUT_DIR

SCENE.npz (written by render_quality.py, world y up, metres): per mesh ``<i>_vertices``,
``<i>_faces``, ``<i>_uv`` (optional), ``<i>_color``, ``<i>_texture`` (optional, linear float);
the camera (``cam_to_world`` 4x4 with OpenCV axes, ``fov_y_deg``, ``width``, ``height``); an
optional sun (``sun_direction`` towards it, ``sun_irradiance``); the sky: ``env_radiance`` (constant)
or ``env_map`` (equirectangular, Mitsuba's layout: u = 0.25 looks along +x, 0.5 along +z, row 0
up) with ``env_scale``.
JOBS.json: a list of {"name", "spp", "denoise", "seed", "adaptive" (optional, default true)}; denoise "none", "oidn" (Blender's
defaults) or "oidn-fast" (OIDN quality FAST, prefilter FAST). Each job writes OUT_DIR/<name>.npy
(linear RGB, H x W x 3, row 0 at the top) and its seconds to OUT_DIR/times.json: the time of
``bpy.ops.render.render`` (scene sync, BVH, path tracing, denoising), the scene built before.
Blender's defaults are kept (adaptive sampling, Blackman-Harris filter 1.5 px wide, OIDN with albedo
and normal passes, prefilter "accurate") except the sample count, the thread count, the bounce
limit (5, as Mitsuba's max_depth 6), the seed, and adaptive sampling off for the reference.
"""
import json
import os
import sys
import time

import bpy
import numpy as np

Y_UP_TO_Z_UP = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], float)  # (x, y, z) -> (x, -z, y)


def _material(name: str, color, texture):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    bsdf = nodes.new("ShaderNodeBsdfDiffuse")
    links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    bsdf.inputs["Color"].default_value = (*[float(c) for c in color], 1.0)
    if texture is not None:
        h, w = texture.shape[:2]
        img = bpy.data.images.new(name + "_tex", w, h, float_buffer=True)
        img.colorspace_settings.name = "Non-Color"  # the array is linear albedo already
        rgba = np.concatenate([texture, np.ones((h, w, 1), np.float32)], -1)
        img.pixels.foreach_set(rgba.ravel())  # Blender's row 0 is v = 0, as Mitsuba's is
        tex = nodes.new("ShaderNodeTexImage")
        tex.image, tex.interpolation = img, "Linear"
        links.new(tex.outputs["Color"], bsdf.inputs["Color"])
    return mat


def _mesh(i: int, data):
    v = data[f"{i}_vertices"] @ Y_UP_TO_Z_UP.T
    f = data[f"{i}_faces"]
    mesh = bpy.data.meshes.new(f"mesh{i}")
    mesh.from_pydata(v.tolist(), [], f.tolist())
    if f"{i}_uv" in data:
        uv = data[f"{i}_uv"][f.ravel()]
        layer = mesh.uv_layers.new(name="uv")
        layer.data.foreach_set("uv", uv.astype(np.float32).ravel())
    mesh.update()
    obj = bpy.data.objects.new(f"obj{i}", mesh)
    obj.data.materials.append(_material(f"mat{i}", data[f"{i}_color"], data.get(f"{i}_texture")))
    bpy.context.scene.collection.objects.link(obj)


def _camera(data):
    from mathutils import Matrix
    c2w = data["cam_to_world"]
    M = np.eye(4)
    M[:3, :3] = Y_UP_TO_Z_UP @ c2w[:3, :3] @ np.diag([1, -1, -1])  # OpenCV -> Blender camera axes
    M[:3, 3] = Y_UP_TO_Z_UP @ c2w[:3, 3]
    cam = bpy.data.cameras.new("cam")
    cam.sensor_fit, cam.lens_unit = "VERTICAL", "FOV"
    cam.angle = float(np.radians(data["fov_y_deg"]))
    obj = bpy.data.objects.new("cam", cam)
    obj.matrix_world = Matrix(M.tolist())
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.scene.camera = obj


def _world(data):
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    bg = nodes["Background"]
    bg.inputs["Strength"].default_value = 1.0
    if "env_map" in data:
        # Blender's u = 0.5 looks along its +x (ours +x), 0.75 along its -y (ours +z): Mitsuba's
        # columns a quarter turn on; its pixel rows run from the bottom
        px = np.roll(data["env_map"].astype(np.float32), data["env_map"].shape[1] // 4, axis=1)[::-1]
        h, w = px.shape[:2]
        img = bpy.data.images.new("env", w, h, float_buffer=True)
        img.colorspace_settings.name = "Non-Color"
        img.pixels.foreach_set(np.concatenate([px, np.ones((h, w, 1), np.float32)], -1).ravel())
        tex = nodes.new("ShaderNodeTexEnvironment")
        tex.image, tex.interpolation = img, "Linear"
        links.new(tex.outputs["Color"], bg.inputs["Color"])
        bg.inputs["Strength"].default_value = float(data["env_scale"])
    else:
        bg.inputs["Color"].default_value = (*[float(c) for c in data["env_radiance"]], 1.0)
    bpy.context.scene.world = world


def _lights(data):
    from mathutils import Vector
    if "sun_direction" in data:
        sun = bpy.data.lights.new("sun", "SUN")
        sun.energy, sun.angle = float(data["sun_irradiance"]), 0.0
        obj = bpy.data.objects.new("sun", sun)
        towards = Vector((Y_UP_TO_Z_UP @ data["sun_direction"]).tolist())
        obj.rotation_euler = towards.to_track_quat("Z", "Y").to_euler()  # the lamp shines along its -Z
        bpy.context.scene.collection.objects.link(obj)
    _world(data)


def build(path: str) -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    data = dict(np.load(path))
    n = int(data["n_meshes"])
    for i in range(n):
        _mesh(i, data)
    _camera(data)
    _lights(data)
    s = bpy.context.scene
    s.render.engine = "CYCLES"
    s.cycles.device = "CPU"
    s.render.threads_mode, s.render.threads = "FIXED", int(data["threads"])
    s.render.resolution_x, s.render.resolution_y = int(data["width"]), int(data["height"])
    s.render.resolution_percentage = 100
    s.cycles.max_bounces = s.cycles.diffuse_bounces = 5
    s.view_settings.view_transform = "Standard"
    s.render.image_settings.file_format = "OPEN_EXR"
    s.render.image_settings.color_depth = "32"


def render(job: dict, out: str) -> float:
    s = bpy.context.scene
    s.cycles.samples, s.cycles.seed = int(job["spp"]), int(job["seed"])
    s.cycles.use_adaptive_sampling = job.get("adaptive", True)  # off for the reference: every pixel converged
    s.cycles.use_denoising = job["denoise"] != "none"
    if s.cycles.use_denoising:
        s.cycles.denoiser = "OPENIMAGEDENOISE"
        fast = job["denoise"] == "oidn-fast"
        s.cycles.denoising_quality = "FAST" if fast else "HIGH"
        s.cycles.denoising_prefilter = "FAST" if fast else "ACCURATE"
    path = os.path.join(out, job["name"] + ".exr")
    s.render.filepath = path
    t = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    seconds = time.perf_counter() - t
    img = bpy.data.images.load(path)
    px = np.array(img.pixels[:], np.float32).reshape(img.size[1], img.size[0], -1)[::-1, :, :3]  # top row first
    np.save(os.path.join(out, job["name"] + ".npy"), px)
    bpy.data.images.remove(img)
    os.remove(path)
    return seconds


def main(scene_path: str, jobs_path: str, out: str) -> None:
    build(scene_path)
    with open(jobs_path) as fh:
        jobs = json.load(fh)
    times = {}
    for job in jobs:
        times[job["name"]] = render(job, out)
    with open(os.path.join(out, "times.json"), "w") as fh:
        json.dump(times, fh)


if __name__ == "__main__":
    main(*sys.argv[-3:])
