"""Scene composition: scene files (environment, objects, lights, cameras) and the subjects
placed in them, as a ``Scene`` ready to render; automatic composition (``compose_scene``):
environments, whole-clip placement, cameras scored by ray-cast occlusion, camera motion."""
from synmitsuba._lazy import lazy_exports

_EXPORTS = {"load_scene_file": "synmitsuba.compose.scenefile_spec", "SceneFile": "synmitsuba.compose.scenefile",
            "scene_spec": "synmitsuba.compose.scenefile_spec",
            "add_subjects": "synmitsuba.compose.subjects", "SubjectEntry": "synmitsuba.compose.subjects",
            "PlacedSubject": "synmitsuba.compose.subjects", "retarget_to_subject": "synmitsuba.compose.subjects",
            "compose_scene": "synmitsuba.compose.composition",
            "ComposeConfig": "synmitsuba.compose.composition", "SceneSpec": "synmitsuba.compose.spec",
            "load_environment": "synmitsuba.compose.environments",
            "environment_names": "synmitsuba.compose.environments"}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = sorted(_EXPORTS)
