"""synmitsuba: synthetic, exactly annotated datasets of people rendered with Mitsuba 3.

    import synmitsuba as sm
    sm.set_variant()                     # cuda_ad_rgb on a GPU, else llvm_ad_rgb
    scene = sm.Scene(); scene.add_mesh(...)
    sample = sm.render(scene, sm.Camera.look_at(...), spp=16, seed=0)
    sm.write_sample(sample, "out/0000")

Names are imported on first use: ``import synmitsuba`` loads neither Mitsuba nor torch.
"""
from synmitsuba._lazy import lazy_exports

__version__ = "0.1.0"

_FROM = {
    "synmitsuba.errors": ("ConfigError", "LLVMError", "SynMitsubaError", "SynMitsubaWarning"),
    "synmitsuba.scene": ("Camera", "Layer", "Material", "Blend", "Constant", "SunSky", "EnvMap", "PointLight",
                         "DirectionalLight", "AreaLight", "Scene", "MeshShape", "CurveShape"),
    "synmitsuba.sample": ("Sample", "PASSES", "register_pass"),
    "synmitsuba.engine.variant": ("set_variant", "current_variant"),
    "synmitsuba.io": ("write_sample", "read_sample", "list_samples", "to_srgb8", "write_png",
                      "contact_sheet", "export_coco", "export_humandata", "sample_panel"),
    "synmitsuba.body": ("SubjectRecipe", "sample_subject", "build_subject", "LayeredHuman", "PosedLayer", "Skeleton",
                        "forward_kinematics", "anny_uv_masks", "GARMENT_KINDS", "ACCESSORY_KINDS", "EyeParams",
                        "GazeTarget", "aim_eyes", "BrowParams", "FACE_UNITS", "HAND_KEYPOINTS",
                        "face_keypoint_names", "FACE68_VERTICES"),
    "synmitsuba.motion": ("Motion", "load_bvh", "parse_bvh", "BVHError", "load_amass", "smplx_skeleton",
                          "procedural_motion", "MOTION_KINDS", "foot_sliding", "retarget", "humanoid_skeleton",
                          "MotionLibrary", "random_window", "is_allowed", "load_motion", "HandTrack", "HandKey",
                          "sample_hands", "with_hands", "HAND_BEHAVIOURS", "FaceTrack", "FaceKey", "sample_face",
                          "with_face", "EXPRESSIONS"),
    "synmitsuba.cloth": ("simulate_cloth", "drape", "ClothSettings", "ClothTrack", "ClothError", "ClothPiece",
                         "Collider", "FABRICS", "CLOTH_KINDS", "Air"),
    "synmitsuba.compose": ("load_scene_file", "SceneFile", "scene_spec", "add_subjects", "SubjectEntry",
                           "retarget_to_subject", "compose_scene", "ComposeConfig", "SceneSpec", "load_environment",
                           "environment_names"),
    "synmitsuba.seeds": ("sequence_rng", "render_seed"),
    "synmitsuba.pipeline": ("render_sequence",),
    "synmitsuba.rendering.photo": ("Photo", "PhotoOptions"),
    "synmitsuba.annotate": ("Annotator", "fit_smplx", "SMPLXFit", "SMPLXOptions", "write_anny_model"),
    "synmitsuba.data": ("SynDataset",),
    "synmitsuba.generate": ("GenerateConfig", "load_generate_config", "add_body_model_fits", "sequence_spec",
                            "write_sequence"),
    "synmitsuba.diff": ("DiffScene", "fit_texture", "FitResult"),
}
_EXPORTS = {name: module for module, names in _FROM.items() for name in names}
_EXPORTS["render"] = "synmitsuba.rendering.passes:render"  # a plain function (the package is synmitsuba.rendering)
_EXPORTS["metrics"] = "synmitsuba.metrics:"
_EXPORTS["diff"] = "synmitsuba.diff:"
_EXPORTS["SampleDataset"] = "synmitsuba.data.dataset:SynDataset"  # the earlier name of the one dataset class
_EXPORTS["generate_dataset"] = "synmitsuba.generate.run:generate"  # sm.generate is the subpackage

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = sorted(_EXPORTS)
