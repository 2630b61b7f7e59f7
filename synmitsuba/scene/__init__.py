"""Scene description: cameras, materials, lights, shapes (plain data, no renderer state)."""
from synmitsuba.scene.camera import Camera
from synmitsuba.scene.layers import Layer
from synmitsuba.scene.materials import (AreaLight, Constant, DirectionalLight, EnvMap, Material,
                                        PointLight, SunSky)
from synmitsuba.scene.scene import CurveShape, MeshShape, Scene

__all__ = ["Camera", "Layer", "Material", "Constant", "SunSky", "EnvMap", "PointLight",
           "DirectionalLight", "AreaLight", "Scene", "MeshShape", "CurveShape"]
