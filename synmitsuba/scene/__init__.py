"""Scene description: cameras, materials, lights, shapes (plain data, no renderer state)."""
from synmitsuba._lazy import lazy_exports

_EXPORTS = {"Camera": "synmitsuba.scene.camera", "Layer": "synmitsuba.scene.layers",
            **{n: "synmitsuba.scene.materials" for n in ("Material", "Blend", "Constant", "SunSky", "EnvMap", "PointLight",
                                                         "DirectionalLight", "AreaLight")},
            **{n: "synmitsuba.scene.scene" for n in ("Scene", "MeshShape", "CurveShape")}}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = sorted(_EXPORTS)
